/* The CSSM of a static scene (Ritschel et al. 2008, §3.2) for cssm_hrc's
 * prepare(): its six compressed faces read from the cache directory when
 * the meshes, their placement and the parameters that change the maps
 * are the same, else made (cssm.c) and stored there. */
#include "cssm_hrc.h"

#include "gi/cache.h"
#include "gi/log.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define CSSM_FORMAT_VERSION                                                                        \
    7u /* 7: maps by the rays they answer (GI_SIDES_ANY_THEN_RECEIVERS;                            \
           GI_SIDES_EYE_THEN_BOTH with escape) */
static const char cache_magic[8] = {'G', 'I', 'C', 'S', 'S', 'M', '\r', '\n'};

/* Cache name: the meshes, their placement at prepare time and every
 * parameter that changes the maps. */
static void cache_name(const cssm_hrc *c, const gi_gpu_scene *gs, char *name, size_t size)
{
    const gi_scene *s = gs->scene;
    uint32_t key[5] = {CSSM_FORMAT_VERSION, (uint32_t)c->R, (uint32_t)c->M, (uint32_t)c->traversal,
                       c->atlas.count};
    uint64_t h = gi_hash64("gibench-cssm", 12, 0);
    h = gi_hash64(key, sizeof key, h);
    if (c->maps.escape) /* env=cssm: escape intervals (env_cssm.h) */
        h = gi_hash64("escape", 6, h);
    for (uint32_t k = 0; k < s->object_count; k++) {
        uint64_t oh = gi_scene_object_hash(s, k);
        float m[16];
        gi_scene_object_transform(s, k, gs->time, m);
        h = gi_hash64(&oh, sizeof oh, h);
        h = gi_hash64(m, sizeof m, h);
    }
    snprintf(name, size, "cssm_hrc-%016llx.bin", (unsigned long long)h);
}

/* The six compressed faces of a cache file; 1 on a hit. */
static int cache_load(cssm_hrc *c, const char *path)
{
    size_t size = 0;
    void *data = NULL;
    gi_error lerr;
    /* the entry's header names what it was made for (gi_cache_load) */
    if (gi_cache_load(path, &data, &size, &lerr) != GI_OK) {
        c->kit.host->log(c->kit.host, GI_LOG_WARN, "%s: unusable cache file (%s); recomputing",
                         path, lerr.text);
        return 0;
    }
    unsigned char *bytes = data;
    if (!bytes)
        return 0;
    int ok = size >= 16 && !memcmp(bytes, cache_magic, 8);
    size_t at = 16;
    uint64_t dont_care = 0;
    if (ok)
        memcpy(&dont_care, bytes + 8, 8);
    for (int f = 0; f < 6 && ok; f++) {
        uint64_t n = 0;
        gi_error err;
        ok = at + 8 <= size;
        if (ok)
            memcpy(&n, bytes + at, 8);
        ok = ok && n <= size - at - 8 &&
             gi_csm_data_read(bytes + at + 8, (size_t)n, &c->maps.face[f], &err) == GI_OK &&
             c->maps.face[f].M == (uint32_t)c->M && c->maps.face[f].N == c->atlas.count;
        at += 8 + (size_t)n;
    }
    free(bytes);
    if (!ok) {
        c->kit.host->log(c->kit.host, GI_LOG_WARN, "%s: unusable cache file; recomputing", path);
        for (int f = 0; f < 6; f++)
            gi_csm_data_free(&c->maps.face[f]);
        return 0;
    }
    c->maps.dont_care = dont_care;
    return 1;
}

static void cache_store(cssm_hrc *c, const char *path)
{
    void *part[6] = {0};
    size_t sz[6] = {0}, total = 16;
    gi_error err = {{0}};
    int ok = 1;
    for (int f = 0; f < 6 && ok; f++) {
        ok = gi_csm_data_write(&c->maps.face[f], &part[f], &sz[f], &err) == GI_OK;
        total += 8 + sz[f];
    }
    unsigned char *buf = ok ? malloc(total) : NULL;
    if (buf) {
        memcpy(buf, cache_magic, 8);
        memcpy(buf + 8, &c->maps.dont_care, 8);
        size_t at = 16;
        for (int f = 0; f < 6; f++) {
            uint64_t n = sz[f];
            memcpy(buf + at, &n, 8);
            memcpy(buf + at + 8, part[f], sz[f]);
            at += 8 + sz[f];
        }
        if (gi_cache_store(path, buf, total, &err) != GI_OK)
            ok = 0;
    }
    if (!ok || !buf)
        c->kit.host->log(c->kit.host, GI_LOG_WARN, "cssm_hrc: not cached: %s",
                         err.text[0] ? err.text : "no memory");
    free(buf);
    for (int f = 0; f < 6; f++)
        free(part[f]);
}

gi_result cssm_load_or_build_maps(cssm_hrc *c, const gi_gpu_scene *gs, gi_error *err)
{
    const gi_host *host = c->kit.host;
    char name[64], *path = NULL;
    /* env=cssm with direct=maps: with direct=csm the environment goes through the distant CSMs */
    const int escape = c->env_mode == 1 && gs->scene->has_environment && !c->direct;
    c->maps.escape = escape;
    cache_name(c, gs, name, sizeof name);
    path = host->cache_dir ? gi_cache_path(host->cache_dir, name) : NULL;
    gi_result r = cssm_maps_setup(&c->atlas, c->order, (uint32_t)c->M, &c->maps, err);
    if (r != GI_OK) {
        free(path);
        return r;
    }
    c->maps.escape = escape;
    if (path && cache_load(c, path)) {
        host->stat(host, "cache_hit", 1.0);
        free(path);
        return GI_OK;
    }
    cssm_maps_free(&c->maps);
    cssm_build_opts bo = {.escape = escape, .from_eye = escape};
    r = cssm_maps_build_ex(gs, &c->atlas, c->order, (uint32_t)c->M, &bo, host, &c->maps, err);
    if (r == GI_OK && path)
        cache_store(c, path);
    host->stat(host, "cache_hit", 0.0);
    free(path);
    return r;
}
