/* mesh.h and cache.h on loaded and hand-built scenes: triangle areas at t,
 * Ritter spheres, welding (tolerance, per object, adjacency, a third of the
 * adjacent areas per vertex), object hashes (placement-independent, changing
 * with the mesh), the cache directory and atomic writes. */
#define _XOPEN_SOURCE 700

#include "check.h"

#include "gi/cache.h"
#include "gi/mesh.h"
#include "gi/scene.h"

#include <dirent.h>
#include <ftw.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define VALID GI_TEST_DATA "/valid/"

static gi_scene *load(const char *path)
{
    gi_error err;
    gi_scene *s = gi_scene_load(path, &err);
    CHECK_MSG(s != NULL, "%s", err.text);
    return s;
}

static void test_areas(void)
{
    gi_scene *s = load(VALID "animated.gltf");
    if (!s)
        return;
    float a[3];
    gi_mesh_triangle_areas(s, 0.0f, a);
    CHECK_NEAR(a[0], 0.5, 1e-6); /* unit right triangle, scale 1 */
    CHECK_NEAR(a[1], 2.0, 1e-6); /* half of the 2 x 2 quad */
    CHECK_NEAR(a[2], 2.0, 1e-6);
    gi_mesh_triangle_areas(s, 10.0f, a); /* scale 3, rotated: area x 9 */
    CHECK_NEAR(a[0], 4.5, 1e-5);
    CHECK_NEAR(a[1], 2.0, 1e-6);
    gi_scene_free(s);
}

static void check_sphere_contains(const gi_scene *s, uint32_t object, const float sp[4])
{
    const gi_object *o = &s->objects[object];
    for (uint32_t i = o->first_vertex; i < o->first_vertex + o->vertex_count; i++) {
        const float *p = s->vertices[i].position;
        float d = sqrtf((p[0] - sp[0]) * (p[0] - sp[0]) + (p[1] - sp[1]) * (p[1] - sp[1]) +
                        (p[2] - sp[2]) * (p[2] - sp[2]));
        CHECK_MSG(d <= sp[3], "vertex %u outside the sphere (%g > %g)", i, (double)d, (double)sp[3]);
    }
}

static void test_spheres(void)
{
    gi_scene *s = load(VALID "animated.gltf");
    if (!s)
        return;
    float sp[4];
    gi_mesh_object_sphere(s, 0, sp); /* triangle (0,0,0) (1,0,0) (0,1,0), local space */
    CHECK_NEAR(sp[0], 0.5, 1e-6);
    CHECK_NEAR(sp[1], 0.5, 1e-6);
    CHECK_NEAR(sp[3], sqrt(0.5), 1e-5);
    check_sphere_contains(s, 0, sp);
    gi_mesh_object_sphere(s, 1, sp); /* quad -1..1: centre 0, radius sqrt 2 */
    CHECK_NEAR(sp[0], 0, 1e-6);
    CHECK_NEAR(sp[3], sqrt(2.0), 1e-5);
    check_sphere_contains(s, 1, sp);
    gi_scene_free(s);
}

/* Object 0: two triangles sharing an edge through duplicated vertices, one
 * of them 1e-5 off; object 1: a triangle touching object 0 at (1,0,0). */
static gi_scene *weld_scene(gi_vertex v[9], uint32_t idx[9], gi_object o[2], gi_node n[2])
{
    static gi_scene s;
    const float pos[9][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0},       {1, 0, 0}, {1, 1, 0},
                             {0, 1.00001f, 0}, {1, 0, 0}, {2, 0, 0}, {1, 1, 0}};
    memset(&s, 0, sizeof s);
    for (uint32_t i = 0; i < 9; i++) {
        memset(&v[i], 0, sizeof v[i]);
        memcpy(v[i].position, pos[i], sizeof pos[i]);
        v[i].normal[2] = 1.0f;
        v[i].object = i < 6 ? 0 : 1;
        idx[i] = i;
    }
    memset(o, 0, 2 * sizeof *o);
    memset(n, 0, 2 * sizeof *n);
    for (int k = 0; k < 2; k++) {
        n[k].parent = -1;
        n[k].rotation[3] = 1.0f;
        n[k].scale[0] = n[k].scale[1] = n[k].scale[2] = 1.0f;
        o[k].node = k;
    }
    o[0].vertex_count = 6;
    o[0].triangle_count = 2;
    o[1].first_vertex = 6;
    o[1].vertex_count = 3;
    o[1].first_triangle = 2;
    o[1].triangle_count = 1;
    s.vertices = v;
    s.vertex_count = 9;
    s.indices = idx;
    s.triangle_count = 3;
    s.objects = o;
    s.object_count = 2;
    s.nodes = n;
    s.node_count = 2;
    float b[6] = {0, 0, 0, 2, 1, 0};
    memcpy(s.bounds, b, sizeof b);
    return &s;
}

static int adjacent(const gi_welded *w, uint32_t wv, uint32_t tri)
{
    for (uint32_t k = w->tri_offsets[wv]; k < w->tri_offsets[wv + 1]; k++)
        if (w->tri_list[k] == tri)
            return 1;
    return 0;
}

static void test_weld(void)
{
    gi_vertex v[9];
    uint32_t idx[9];
    gi_object o[2];
    gi_node n[2];
    gi_scene *s = weld_scene(v, idx, o, n);

    gi_welded *w = gi_mesh_weld(s, 1e-4f); /* tolerance 1e-4 x sqrt 5 > 1e-5 */
    CHECK(w != NULL);
    if (!w)
        return;
    CHECK(w->vertex_count == 7);
    CHECK(w->remap[3] == w->remap[1] && w->remap[5] == w->remap[2]);
    CHECK(w->remap[6] != w->remap[1]); /* never across objects */
    CHECK(w->object[w->remap[6]] == 1 && w->object[w->remap[4]] == 0);
    uint32_t shared = w->remap[1];
    CHECK(w->tri_offsets[shared + 1] - w->tri_offsets[shared] == 2);
    CHECK(adjacent(w, shared, 0) && adjacent(w, shared, 1) && !adjacent(w, shared, 2));
    CHECK(w->tri_offsets[w->remap[0] + 1] - w->tri_offsets[w->remap[0]] == 1);
    CHECK(w->tri_offsets[w->vertex_count] == 9); /* every triangle once per corner */
    CHECK_NEAR(w->areas[shared], 1.0 / 3.0, 1e-5);
    CHECK_NEAR(w->areas[w->remap[0]], 0.5 / 3.0, 1e-6);
    double total = 0.0;
    for (uint32_t i = 0; i < w->vertex_count; i++) {
        total += w->areas[i];
        CHECK_NEAR(w->normals[i * 3 + 2], 1, 1e-6);
    }
    CHECK_NEAR(total, 1.5, 1e-5);
    CHECK(w->positions[shared * 3] == 1.0f && w->positions[shared * 3 + 1] == 0.0f);
    gi_welded_free(w);

    w = gi_mesh_weld(s, 0.0f); /* exact: the 1e-5 offset stays apart */
    CHECK(w && w->vertex_count == 8 && w->remap[3] == w->remap[1] && w->remap[5] != w->remap[2]);
    gi_welded_free(w);
    gi_welded_free(NULL);
}

static void test_hash(void)
{
    CHECK(gi_hash64("abc", 3, 0) == 0x44BC2CF5AD770999ull); /* XXH64 reference value */
    CHECK(gi_hash64("abc", 3, 1) != gi_hash64("abc", 3, 0));
    gi_scene *quad = load(VALID "quad.gltf"), *anim = load(VALID "animated.gltf"),
             *tex = load(VALID "textured.gltf");
    if (quad && anim && tex) {
        uint64_t h = gi_scene_object_hash(quad, 0);
        CHECK(h == gi_scene_object_hash(quad, 0));
        /* the same quad elsewhere in another scene (other first vertex, transform) */
        CHECK(h == gi_scene_object_hash(anim, 1));
        CHECK(h != gi_scene_object_hash(tex, 0)); /* same positions, other uvs */
        CHECK(h != gi_scene_object_hash(anim, 0));
        float old = quad->vertices[2].position[1];
        quad->vertices[2].position[1] += 1e-3f;
        CHECK(gi_scene_object_hash(quad, 0) != h);
        quad->vertices[2].position[1] = old;
        CHECK(gi_scene_object_hash(quad, 0) == h);
        uint32_t i0 = quad->indices[0];
        quad->indices[0] = quad->indices[1];
        quad->indices[1] = i0;
        CHECK(gi_scene_object_hash(quad, 0) != h); /* winding is part of the mesh */
    }
    gi_scene_free(quad);
    gi_scene_free(anim);
    gi_scene_free(tex);
}

static int remove_entry(const char *path, const struct stat *st, int flag, struct FTW *ftw)
{
    (void)st;
    (void)flag;
    (void)ftw;
    return remove(path);
}

static int count_entries(const char *dir)
{
    DIR *d = opendir(dir);
    int n = 0;
    for (struct dirent *e; d && (e = readdir(d));)
        n += strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0;
    if (d)
        closedir(d);
    return n;
}

static int is_dir(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 && S_ISDIR(st.st_mode);
}

static void test_cache_dir(const char *tmp)
{
    char want[600], env[600];
    gi_error err;
    snprintf(env, sizeof env, "%s/explicit/a/b", tmp);
    setenv("GIBENCH_CACHE", env, 1);
    char *dir = gi_cache_dir(&err);
    CHECK_MSG(dir && strcmp(dir, env) == 0 && is_dir(env), "%s", dir ? dir : err.text);
    free(dir);

    unsetenv("GIBENCH_CACHE");
    snprintf(env, sizeof env, "%s/xdg", tmp);
    setenv("XDG_CACHE_HOME", env, 1);
    snprintf(want, sizeof want, "%s/xdg/gibench", tmp);
    dir = gi_cache_dir(&err);
    CHECK_MSG(dir && strcmp(dir, want) == 0 && is_dir(want), "%s", dir ? dir : err.text);
    free(dir);

    setenv("XDG_CACHE_HOME", "relative/ignored", 1);
    snprintf(env, sizeof env, "%s/home", tmp);
    setenv("HOME", env, 1);
    snprintf(want, sizeof want, "%s/home/.cache/gibench", tmp);
    dir = gi_cache_dir(&err);
    CHECK_MSG(dir && strcmp(dir, want) == 0 && is_dir(want), "%s", dir ? dir : err.text);
    free(dir);

    unsetenv("XDG_CACHE_HOME");
    unsetenv("HOME");
    CHECK(gi_cache_dir(&err) == NULL && strstr(err.text, "no cache directory") != NULL);

    snprintf(env, sizeof env, "%s/plain-file", tmp);
    CHECK(gi_file_write_atomic(env, "x", 1, &err) == GI_OK);
    snprintf(env, sizeof env, "%s/plain-file/sub", tmp);
    setenv("GIBENCH_CACHE", env, 1);
    CHECK(gi_cache_dir(&err) == NULL && strstr(err.text, "exists and is not a directory") != NULL);
    unsetenv("GIBENCH_CACHE");

    char *p = gi_cache_path("/a/b", "csm-0123456789abcdef.bin");
    CHECK(p && strcmp(p, "/a/b/csm-0123456789abcdef.bin") == 0);
    free(p);
    p = gi_cache_path("/a/b/", "x");
    CHECK(p && strcmp(p, "/a/b/x") == 0);
    free(p);
}

static void test_atomic_write(const char *tmp)
{
    char dir[600], path[700];
    gi_error err;
    snprintf(dir, sizeof dir, "%s/entries", tmp);
    mkdir(dir, 0755);
    snprintf(path, sizeof path, "%s/entry.bin", dir);
    CHECK(gi_file_write_atomic(path, "hello", 5, &err) == GI_OK);
    size_t n = 0;
    char *data = gi_file_read_all(path, &n);
    CHECK(data && n == 5 && memcmp(data, "hello", 5) == 0 && data[5] == '\0');
    free(data);

    static unsigned char big[100000];
    for (size_t i = 0; i < sizeof big; i++)
        big[i] = (unsigned char)(i * 7);
    CHECK(gi_file_write_atomic(path, big, sizeof big, &err) == GI_OK); /* replaces */
    data = gi_file_read_all(path, &n);
    CHECK(data && n == sizeof big && memcmp(data, big, n) == 0);
    free(data);
    CHECK(count_entries(dir) == 1); /* no temporary file left behind */

    CHECK(gi_file_write_atomic(path, NULL, 0, &err) == GI_OK);
    data = gi_file_read_all(path, &n);
    CHECK(data && n == 0);
    free(data);

    snprintf(path, sizeof path, "%s/missing-dir/entry.bin", dir);
    CHECK(gi_file_write_atomic(path, "x", 1, &err) == GI_ERR_IO &&
          strstr(err.text, "missing-dir/entry.bin") != NULL);
    CHECK(gi_file_read_all(path, &n) == NULL && n == 0);
    CHECK(gi_file_read_all(dir, &n) == NULL); /* a directory is not a file */
}

int main(void)
{
    test_areas();
    test_spheres();
    test_weld();
    test_hash();
    char tmp[] = GI_BINARY_DIR "/tests/scene-cache-XXXXXX";
    CHECK(mkdtemp(tmp) != NULL);
    test_cache_dir(tmp);
    test_atomic_write(tmp);
    nftw(tmp, remove_entry, 16, FTW_DEPTH | FTW_PHYS);
    return gi_test_finish();
}
