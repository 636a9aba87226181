/* gibench compare: several methods on one scene, each in its own process
 * with a time limit, against full-GI and bounce-matched references. */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"

#include "gi/cache.h"
#include "gi/image.h"
#include "report.h"
#include "runner.h"
#include "view_file.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define MAX_METHODS 32
/* the failed methods' ids, ", "-separated: room for MAX_METHODS ids of 64 bytes */
#define FAILED_LIST (MAX_METHODS * 66)
#define MAX_PARAMS 64

typedef struct compare_opts {
    const char *scene, *methods, *out, *camera, *reference;
    const char *params[MAX_PARAMS]; /* "method.key=value" */
    uint32_t param_count;
    uint32_t width, height, frames, warmup, seed, ref_spp, ref_bounces;
    double timeout_s, ref_target_se;
    float exposure, time;
    int fresh;
} compare_opts;

static int parse(int argc, char **argv, compare_opts *o)
{
    memset(o, 0, sizeof *o);
    o->width = o->height = 128;
    o->frames = 8;
    o->warmup = 1;
    o->seed = 1;
    o->ref_spp = 256;
    o->ref_bounces = 64;
    o->timeout_s = 600;
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--fresh")) {
            o->fresh = 1;
            continue;
        }
        const char *v = i + 1 < argc ? argv[++i] : NULL;
        unsigned long u;
        float f;
        if (!v && strncmp(a, "--", 2) == 0)
            return cli_fail(EXIT_USAGE, "compare: %s needs a value", a);
        if (!strcmp(a, "--scene"))
            o->scene = v;
        else if (!strcmp(a, "--methods"))
            o->methods = v;
        else if (!strcmp(a, "--out"))
            o->out = v;
        else if (!strcmp(a, "--camera"))
            o->camera = v;
        else if (!strcmp(a, "--reference"))
            o->reference = v;
        else if (!strcmp(a, "--param")) {
            if (o->param_count == MAX_PARAMS || !strchr(v, '.') || !strchr(v, '='))
                return cli_fail(EXIT_USAGE, "compare: --param '%s' is not method.name=value", v);
            o->params[o->param_count++] = v;
        } else if (!strcmp(a, "--size")) {
            if (!cli_parse_size(v, &o->width, &o->height))
                return cli_fail(EXIT_USAGE, "compare: --size '%s' is not WxH", v);
        } else if (!strcmp(a, "--frames") || !strcmp(a, "--warmup") || !strcmp(a, "--seed") ||
                   !strcmp(a, "--ref-spp") || !strcmp(a, "--ref-bounces")) {
            unsigned long lo = !strcmp(a, "--warmup") || !strcmp(a, "--seed") ? 0 : 1;
            if (!cli_parse_uint(v, lo, 1000000000ul, &u))
                return cli_fail(EXIT_USAGE, "compare: %s '%s' is not an integer >= %lu", a, v, lo);
            if (!strcmp(a, "--frames"))
                o->frames = (uint32_t)u;
            else if (!strcmp(a, "--warmup"))
                o->warmup = (uint32_t)u;
            else if (!strcmp(a, "--seed"))
                o->seed = (uint32_t)u;
            else if (!strcmp(a, "--ref-spp"))
                o->ref_spp = (uint32_t)u;
            else
                o->ref_bounces = (uint32_t)u;
        } else if (!strcmp(a, "--timeout")) {
            if (!cli_parse_float(v, &f) || f <= 0)
                return cli_fail(EXIT_USAGE,
                                "compare: --timeout '%s' is not a positive number of seconds", v);
            o->timeout_s = f;
        } else if (!strcmp(a, "--ref-target-se")) {
            if (!cli_parse_float(v, &f) || f <= 0)
                return cli_fail(EXIT_USAGE,
                                "compare: --ref-target-se '%s' is not a positive number", v);
            o->ref_target_se = f;
        } else if (!strcmp(a, "--exposure")) {
            if (!cli_parse_exposure(v, &o->exposure))
                return cli_fail(EXIT_USAGE,
                                "compare: --exposure '%s' is not a number of stops in -64..64", v);
        } else if (!strcmp(a, "--time")) {
            if (!cli_parse_float(v, &o->time) || o->time < 0)
                return cli_fail(EXIT_USAGE, "compare: --time '%s' is not a non-negative number", v);
        } else {
            return cli_fail(EXIT_USAGE, "compare: unknown argument '%s' (see gibench --help)", a);
        }
    }
    if (!o->scene || !o->methods || !o->out)
        return cli_fail(EXIT_USAGE, "compare: --scene, --methods and --out are required");
    if (o->frames > 1 && o->warmup >= o->frames)
        o->warmup = o->frames - 1;
    if (o->frames == 1)
        o->warmup = 0;
    return EXIT_OK;
}

/* The "k=v" part of every --param that names method m; returns how many. */
static uint32_t method_params(const compare_opts *o, const gi_method *m, const char **kv)
{
    uint32_t np = 0;
    size_t idlen = strlen(m->id);
    for (uint32_t k = 0; k < o->param_count; k++)
        if (!strncmp(o->params[k], m->id, idlen) && o->params[k][idlen] == '.')
            kv[np++] = o->params[k] + idlen + 1;
    return np;
}

/* An id that is no installed method: one line listing those that are, as render's. */
static int unknown_method(const gi_plugins *reg, const char *id)
{
    char known[1024] = "";
    for (uint32_t i = 0; i < reg->count; i++) {
        size_t used = strlen(known);
        snprintf(known + used, sizeof known - used, "%s%s", i ? ", " : "",
                 reg->items[i].method->id);
    }
    return cli_fail(EXIT_USAGE, "compare: no method '%s' (installed: %s)", id,
                    known[0] ? known : "none");
}

/* --camera: a camera of the scene, or a view saved by gibench view
 * (view:FILE.json, as render, reference and studies take it: its camera and
 * moved objects). A view's bytes join the scene's content in *scene_hash,
 * so that results made under another view are not reused. */
static int check_camera(const compare_opts *o, const gi_scene *scene, uint64_t *scene_hash)
{
    view_file view;
    char why[600];
    int is_view = view_camera_read(o->camera, &view, why, sizeof why);
    if (is_view < 0)
        return cli_fail(EXIT_USAGE, "compare: --camera %s", why);
    if (is_view) {
        int ok = view_file_check_nodes(&view, scene, why, sizeof why);
        view_file_free(&view);
        if (!ok)
            return cli_fail(EXIT_USAGE, "compare: --camera %s: %s", o->camera, why);
        size_t n = 0;
        unsigned char *bytes = (unsigned char *)gi_file_read_all(o->camera + 5, &n);
        for (size_t i = 0; bytes && i < n; i++)
            *scene_hash = (*scene_hash ^ bytes[i]) * 0x100000001b3ull; /* FNV-1a, as a study's */
        free(bytes);
        return EXIT_OK;
    }
    if (o->camera && gi_scene_find_camera(scene, o->camera) < 0)
        return cli_fail(EXIT_USAGE, "compare: %s has no camera '%s'", o->scene, o->camera);
    return EXIT_OK;
}

/* --methods: every installed method ("all") or the methods it lists. */
static int select_methods(const compare_opts *o, gi_plugins *reg, const gi_method **methods,
                          uint32_t *count)
{
    uint32_t n = 0;
    if (!strcmp(o->methods, "all")) {
        for (uint32_t i = 0; i < reg->count && n < MAX_METHODS; i++)
            methods[n++] = reg->items[i].method;
    } else {
        /* a comma-separated list of installed ids, none empty, none twice */
        char list[1024];
        if (snprintf(list, sizeof list, "%s", o->methods) >= (int)sizeof list)
            return cli_fail(EXIT_USAGE, "compare: --methods is too long");
        for (char *id = list, *next; id; id = next) {
            next = strchr(id, ',');
            if (next)
                *next++ = '\0';
            const gi_method *m = *id ? gi_plugins_find(reg, id) : NULL;
            int twice = 0;
            for (uint32_t k = 0; m && k < n; k++)
                twice |= methods[k] == m;
            if (!m || twice || n == MAX_METHODS) {
                if (!*id)
                    return cli_fail(EXIT_USAGE, "compare: --methods '%s' has an empty method name",
                                    o->methods);
                if (twice)
                    return cli_fail(EXIT_USAGE, "compare: --methods names '%s' twice", id);
                if (m)
                    return cli_fail(EXIT_USAGE, "compare: --methods names more than %d methods",
                                    MAX_METHODS);
                return unknown_method(reg, id);
            }
            methods[n++] = m;
        }
    }
    *count = n;
    if (n == 0)
        return cli_fail(EXIT_USAGE, "compare: no method is installed (see gibench methods)");
    return EXIT_OK;
}

/* Every --param names a method of the comparison and fits its table. */
static int check_params(const compare_opts *o, const gi_method *const *methods, uint32_t n)
{
    for (uint32_t k = 0; k < o->param_count; k++) {
        size_t len = (size_t)(strchr(o->params[k], '.') - o->params[k]);
        int found = 0;
        for (uint32_t i = 0; i < n; i++)
            found |= strlen(methods[i]->id) == len && !strncmp(methods[i]->id, o->params[k], len);
        if (!found)
            return cli_fail(EXIT_USAGE, "compare: --param '%s' names no method of this comparison",
                            o->params[k]);
    }
    /* Each method's parameters against its table, now rather than in a
     * child process after the references have rendered. */
    for (uint32_t i = 0; i < n; i++) {
        const char *kv[MAX_PARAMS];
        uint32_t np = method_params(o, methods[i], kv);
        gi_error err;
        gi_params *p = gi_params_parse(methods[i]->id, methods[i]->params, kv, np, &err);
        if (!p)
            return cli_fail(EXIT_USAGE, "compare: --param %s", err.text);
        gi_params_free(p);
    }
    return EXIT_OK;
}

/* A given reference must be an image of the comparison's size. */
static int check_reference(const compare_opts *o)
{
    if (!o->reference)
        return EXIT_OK;
    gi_error err;
    gi_image *ref = gi_image_read(o->reference, &err);
    int fits = ref && ref->width == o->width && ref->height == o->height;
    uint32_t rw = ref ? ref->width : 0, rh = ref ? ref->height : 0;
    gi_image_free(ref);
    if (fits)
        return EXIT_OK;
    if (!rw)
        return cli_fail(EXIT_USAGE, "compare: --reference %s", err.text);
    return cli_fail(EXIT_USAGE,
                    "compare: --reference %s is %ux%u, the comparison is %ux%u (--size)",
                    o->reference, rw, rh, o->width, o->height);
}

/* The full reference: the one given, or path traced into the output folder. */
static int full_reference(const compare_opts *o, uint64_t scene_hash, char *ref_full, size_t size)
{
    char why[1024];
    if (o->reference) {
        snprintf(ref_full, size, "%s", o->reference);
        return EXIT_OK;
    }
    snprintf(ref_full, size, "%s/reference_b%u.exr", o->out, o->ref_bounces);
    fprintf(stderr, "compare: reference (%u spp, %u bounces)\n", o->ref_spp, o->ref_bounces);
    if (!runner_reference(o->scene, scene_hash, o->camera, o->width, o->height, o->ref_spp,
                          o->ref_target_se, o->ref_bounces, o->seed, o->time, 0, o->timeout_s,
                          ref_full, why, sizeof why))
        return cli_fail(EXIT_RUN, "compare: %s", why);
    return EXIT_OK;
}

/* The bounce-matched references made, for the report's viewer. */
typedef struct matched_refs {
    uint32_t bounces[MAX_METHODS], n;
} matched_refs;

/* The reference limited to b bounces, path traced into `path` and listed
 * in `made`; NULL (after a warning) when it could not be made. */
static const char *matched_reference(const compare_opts *o, uint64_t scene_hash, uint32_t b,
                                     char *path, size_t size, matched_refs *made)
{
    char why[1024];
    snprintf(path, size, "%s/reference_b%u.exr", o->out, b);
    fprintf(stderr, "compare: bounce-matched reference (%u spp, %u bounces)\n", o->ref_spp, b);
    if (!runner_reference(o->scene, scene_hash, o->camera, o->width, o->height, o->ref_spp,
                          o->ref_target_se, b, o->seed, o->time, 0, o->timeout_s, path, why,
                          sizeof why)) {
        fprintf(stderr, "gibench: warning: %s\n", why);
        return NULL;
    }
    uint32_t k = 0;
    while (k < made->n && made->bounces[k] != b)
        k++;
    if (k == made->n)
        made->bounces[made->n++] = b;
    return path;
}

/* One method's run (or its record as not applicable to the scene). */
static json_object *run_method(const compare_opts *o, const gi_scene *scene, uint64_t scene_hash,
                               const gi_method *m, const char *ref_full, matched_refs *made)
{
    const char *params[MAX_PARAMS];
    uint32_t np = method_params(o, m, params);
    char dir[4096], matched[4096];
    snprintf(dir, sizeof dir, "%s/%s", o->out, m->id);
    uint32_t b = m->max_bounces + 1;
    run_spec spec = {m->id,     o->scene, m->id,    o->camera, o->width,    o->height, o->frames,
                     o->warmup, o->seed,  o->time,  0.0f,      params,      np,        o->timeout_s,
                     dir,       m->id,    ref_full, NULL,      o->exposure, 0,         NULL,
                     0,         NULL,     NULL,     NULL};
    char reason[256];
    if (!cli_caps_cover(m, scene, 0, reason, sizeof reason))
        return runner_not_applicable(&spec, reason);
    if (b < o->ref_bounces)
        spec.ref_matched = matched_reference(o, scene_hash, b, matched, sizeof matched, made);
    else
        spec.ref_matched = ref_full; /* the full reference is this method's match */
    double t0 = gi_now();
    json_object *rec = runner_execute(&spec, !o->fresh);
    json_object *c;
    int cached = json_object_object_get_ex(rec, "cached", &c) && json_object_get_boolean(c);
    json_object_object_del(rec, "cached");
    fprintf(stderr, "compare: %s %s (%.1f s)\n", m->id, cached ? "cached" : "ran", gi_now() - t0);
    return rec;
}

/* Counts and reports a failed run, adding its method to the failed list
 * (the one-line verdict names them); keeps the first GL renderer named. */
static void note_outcome(json_object *rec, const gi_method *m, int *failures, char *failed,
                         size_t failed_size, char *renderer, size_t size)
{
    json_object *st, *rn;
    if (json_object_object_get_ex(rec, "status", &st) &&
        !strcmp(json_object_get_string(st), "failed")) {
        (*failures)++;
        json_object *r;
        json_object_object_get_ex(rec, "reason", &r);
        fprintf(stderr, "gibench: warning: %s failed: %s\n", m->id, json_object_get_string(r));
        size_t used = strlen(failed);
        snprintf(failed + used, failed_size - used, "%s%s", used ? ", " : "", m->id);
    }
    if (!renderer[0] && json_object_object_get_ex(rec, "renderer", &rn))
        snprintf(renderer, size, "%s", json_object_get_string(rn));
}

/* The viewer's set: the full reference, every bounce-matched one and every run. */
static json_object *viewer_references(const compare_opts *o, const char *title, json_object *runs,
                                      const matched_refs *made)
{
    json_object *sets = json_object_new_array(), *set = json_object_new_object();
    json_object *mlist = json_object_new_array(), *ids = json_object_new_array();
    char img[64];
    snprintf(img, sizeof img, "reference_b%u.exr", o->ref_bounces);
    json_object_object_add(set, "name", json_object_new_string(title));
    json_object_object_add(set, "full", json_object_new_string(img));
    json_object_object_add(set, "bounces", json_object_new_int((int)o->ref_bounces));
    for (uint32_t k = 0; k < made->n; k++) {
        json_object *m = json_object_new_object();
        snprintf(img, sizeof img, "reference_b%u.exr", made->bounces[k]);
        json_object_object_add(m, "image", json_object_new_string(img));
        json_object_object_add(m, "bounces", json_object_new_int((int)made->bounces[k]));
        json_object_array_add(mlist, m);
    }
    json_object_object_add(set, "matched", mlist);
    for (size_t i = 0; i < json_object_array_length(runs); i++) {
        json_object *id;
        if (json_object_object_get_ex(json_object_array_get_idx(runs, i), "run", &id))
            json_object_array_add(ids, json_object_get(id));
    }
    json_object_object_add(set, "runs", ids);
    json_object_array_add(sets, set);
    return sets;
}

/* The report's header, and for a path-traced reference the viewer's set. */
static json_object *compare_meta(const compare_opts *o, int argc, char **argv, json_object *runs,
                                 const char *renderer, const matched_refs *made)
{
    char title[512], refdesc[512];
    snprintf(title, sizeof title, "gibench compare: %s at %ux%u", o->scene, o->width, o->height);
    if (o->reference)
        snprintf(refdesc, sizeof refdesc, "%s (given); bounce-matched references %u spp",
                 o->reference, o->ref_spp);
    else
        snprintf(refdesc, sizeof refdesc,
                 "path traced (Embree), %u spp, %u bounces; bounce-matched the same spp",
                 o->ref_spp, o->ref_bounces);
    json_object *meta = report_meta_new(title, "compare", argc, argv, renderer, refdesc);
    if (!o->reference) {
        char ref_png[64];
        snprintf(ref_png, sizeof ref_png, "reference_b%u.png", o->ref_bounces);
        json_object_object_add(meta, "reference_png", json_object_new_string(ref_png));
        json_object_object_add(meta, "references", viewer_references(o, title, runs, made));
        json_object_object_add(meta, "exposure", json_object_new_double(o->exposure));
    }
    return meta;
}

/* The references, every method's run and the report; *failures counts the
 * runs that failed and failed (FAILED_LIST bytes) lists their methods. */
static int run_comparison(const compare_opts *o, int argc, char **argv, const gi_scene *scene,
                          uint64_t scene_hash, const gi_method *const *methods, uint32_t n,
                          int *failures, char *failed)
{
    cli_install_signal_handlers();

    /* References: the full one (given or path traced) and one per bounce
     * count the methods need. */
    char ref_full[4096], why[1024];
    int rc = full_reference(o, scene_hash, ref_full, sizeof ref_full);
    if (rc != EXIT_OK)
        return rc;
    json_object *runs = json_object_new_array();
    matched_refs made = {{0}, 0};
    char renderer[256] = "";
    for (uint32_t i = 0; i < n && !cli_interrupted; i++) {
        json_object *rec = run_method(o, scene, scene_hash, methods[i], ref_full, &made);
        note_outcome(rec, methods[i], failures, failed, FAILED_LIST, renderer, sizeof renderer);
        json_object_array_add(runs, rec);
    }
    json_object *meta = compare_meta(o, argc, argv, runs, renderer, &made);
    rc = report_write(o->out, runs, meta, why, sizeof why) ? EXIT_OK
                                                           : cli_fail(EXIT_RUN, "compare: %s", why);
    json_object_put(runs);
    json_object_put(meta);
    return rc;
}

int cmd_compare(int argc, char **argv)
{
    compare_opts o;
    int rc = parse(argc, argv, &o);
    if (rc != EXIT_OK)
        return rc;
    gi_error err;
    gi_scene *scene = gi_scene_load(o.scene, &err);
    uint64_t scene_hash = scene ? cli_scene_content_hash(scene, o.scene) : 0;
    if (!scene)
        return cli_fail(EXIT_USAGE, "%s", err.text);
    rc = check_camera(&o, scene, &scene_hash);
    if (rc != EXIT_OK) {
        gi_scene_free(scene);
        return rc;
    }
    gi_plugins *reg = cli_load_plugins(0);
    const gi_method *methods[MAX_METHODS];
    uint32_t n = 0;
    int failures = 0;
    char failed[FAILED_LIST] = "";
    rc = select_methods(&o, reg, methods, &n);
    if (rc == EXIT_OK)
        rc = check_params(&o, methods, n);
    if (rc == EXIT_OK)
        rc = check_reference(&o);
    if (rc == EXIT_OK && !cli_mkdirs(o.out))
        rc = cli_fail(EXIT_RUN, "compare: cannot create %s", o.out);
    if (rc == EXIT_OK)
        rc = run_comparison(&o, argc, argv, scene, scene_hash, methods, n, &failures, failed);
    gi_plugins_free(reg);
    gi_scene_free(scene);
    if (rc == EXIT_OK && cli_interrupted)
        return cli_fail(EXIT_RUN, "compare: interrupted; rerun the same command to resume");
    /* as study does: a comparison with a failed run is a failure, though
     * its report is written (docs/commands.md "Exit status") */
    if (rc == EXIT_OK && failures)
        return cli_fail(EXIT_RUN, "compare: %d of %u methods failed: %s (see %s/report.md)",
                        failures, n, failed, o.out);
    return rc;
}
