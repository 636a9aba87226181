/* Cache entries (gi/cache.h, gi_cache_store / gi_cache_load): a stored
 * entry reads back whole; a missing one is no entry and no error; one
 * copied under another entry's name, truncated, padded, flipped or without
 * the header is refused with one line saying why (issue 32, item 3). */
#define _POSIX_C_SOURCE 200809L
#include "check.h"
#include "gi/cache.h"
#include "gi/scene.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char dir[] = "/tmp/gi_test_cache_XXXXXX";

static char *path_of(const char *name)
{
    return gi_cache_path(dir, name);
}

/* Loads `name`; 1 when refused with a message containing `why`. */
static int refused(const char *name, const char *why)
{
    char *p = path_of(name);
    void *data = NULL;
    size_t size = 0;
    gi_error err = {{0}};
    gi_result r = gi_cache_load(p, &data, &size, &err);
    free(p);
    free(data);
    CHECK_MSG(strchr(err.text, '\n') == NULL, "two lines: %s", err.text);
    return r == GI_ERR_INVALID_ARGUMENT && data == NULL && strstr(err.text, why) != NULL;
}

/* Writes raw bytes to entry `name`. */
static void write_raw(const char *name, const void *bytes, size_t n)
{
    char *p = path_of(name);
    gi_error err;
    CHECK(gi_file_write_atomic(p, bytes, n, &err) == GI_OK);
    free(p);
}

static unsigned char *read_raw(const char *name, size_t *n)
{
    char *p = path_of(name);
    unsigned char *b = gi_file_read_all(p, n);
    free(p);
    return b;
}

/* The object hash that cache names start from changes with a material's
 * doubleSided: under the rule for sides (gi/scene.h) it decides which faces
 * a map holds (issue 28). */
static void test_hash_sides(void)
{
    gi_error err;
    gi_scene *s = gi_scene_load(GI_TEST_DATA "/truth/box_light.gltf", &err);
    CHECK_MSG(s != NULL, "%s", err.text);
    if (!s)
        return;
    uint64_t h0 = gi_scene_object_hash(s, 0);
    uint32_t m = s->vertices[s->objects[0].first_vertex].material;
    s->materials[m].double_sided = !s->materials[m].double_sided;
    CHECK(gi_scene_object_hash(s, 0) != h0);
    s->materials[m].double_sided = !s->materials[m].double_sided;
    CHECK(gi_scene_object_hash(s, 0) == h0);
    gi_scene_free(s);
}

int main(void)
{
    test_hash_sides();
    CHECK(mkdtemp(dir) != NULL);
    const char payload[] = "precomputed maps of one object, 37 bytes";
    const char *a = "m-0123456789abcdef.bin", *b = "m-fedcba9876543210.bin";
    gi_error err;
    char *pa = path_of(a);
    CHECK(gi_cache_store(pa, payload, sizeof payload, &err) == GI_OK);

    /* whole: the payload comes back */
    void *data = NULL;
    size_t size = 0;
    CHECK(gi_cache_load(pa, &data, &size, &err) == GI_OK);
    CHECK(data && size == sizeof payload && !memcmp(data, payload, size));
    free(data);
    /* missing: no entry, no error */
    char *pb = path_of(b);
    data = (void *)1;
    CHECK(gi_cache_load(pb, &data, &size, &err) == GI_OK && data == NULL && size == 0);

    size_t n = 0;
    unsigned char *bytes = read_raw(a, &n);
    CHECK(bytes && n > sizeof payload);
    /* copied under another entry's name (another scene, other settings) */
    write_raw(b, bytes, n);
    CHECK(refused(b, "made as m-0123456789abcdef.bin, not m-fedcba9876543210.bin"));
    /* truncated and padded */
    write_raw(a, bytes, n - 1);
    CHECK(refused(a, "truncated or padded"));
    unsigned char *padded = malloc(n + 1);
    memcpy(padded, bytes, n);
    padded[n] = 0;
    write_raw(a, padded, n + 1);
    CHECK(refused(a, "truncated or padded"));
    /* a byte of the payload flipped */
    memcpy(padded, bytes, n);
    padded[n - 3] ^= 0x40;
    write_raw(a, padded, n);
    CHECK(refused(a, "checksum mismatch"));
    /* no header (an entry written before entries had one) */
    write_raw(a, payload, sizeof payload);
    CHECK(refused(a, "no gibench cache header"));
    /* an empty payload is an entry too */
    CHECK(gi_cache_store(pa, NULL, 0, &err) == GI_OK);
    CHECK(gi_cache_load(pa, &data, &size, &err) == GI_OK && data != NULL && size == 0);
    free(data);

    free(padded);
    free(bytes);
    unlink(pa);
    unlink(pb);
    free(pa);
    free(pb);
    rmdir(dir);
    return gi_test_finish();
}
