/* Helpers shared by the vlf plugin's test programs (vlf_order_tests.c,
 * vlf_transport_tests.c, vlf_lights_tests.c, vlf_storage_tests.c): scenes
 * loaded or built by hand, the settings the tests start from, a small
 * random generator, and the main() that runs the part named on the command
 * line. All static inline: check.h counts per translation unit, so load()'s
 * check counts in the program that calls it, and a program need not use
 * every helper. */
#ifndef VLF_TEST_UTIL_H
#define VLF_TEST_UTIL_H

#include "vlf_field.h"

#include "gi/scene.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#define EXPECT CHECK_MSG

static inline gi_scene *load(const char *rel)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", GI_SOURCE_DIR, rel);
    gi_error err;
    gi_scene *s = gi_scene_load(path, &err);
    EXPECT(s != NULL, "loading %s: %s", path, err.text);
    return s;
}

/* The plugin's defaults but l = 128 (the plugin's is the paper's 512): these
 * tests check mechanics (bookkeeping, order, lights), which do not depend on
 * l, and 4x the subfields would make them 4x slower. */
static inline vlf_settings defaults(void)
{
    return (vlf_settings){.l = 128,
                          .N = 64,
                          .m = 8,
                          .S = 2,
                          .density = 12,
                          .iterations = 8,
                          .seed = 1,
                          .order = VLF_ORDER_FACES,
                          .threads = 2,
                          .bsp_levels = 2,
                          .bsp_min = 4096,
                          .subdivide = 1};
}

static inline float frand(uint32_t *s)
{
    *s = *s * 1664525u + 1013904223u;
    return (float)(*s >> 8) / 16777216.0f;
}

static inline gi_vec3 rand_dir(uint32_t *s)
{
    float z = 2.0f * frand(s) - 1.0f, phi = 2.0f * GI_PI * frand(s);
    float r = sqrtf(fmaxf(0.0f, 1.0f - z * z));
    return gi_v3(r * cosf(phi), r * sinf(phi), z);
}

/* A hand-built test scene, zeroed: `triangles` triangles and `vertices`
 * vertices in one object on node 0, `materials` untextured black
 * materials, `nodes` identity nodes without parents. Freed by
 * gi_scene_free(). */
static inline gi_scene *bare_scene(uint32_t triangles, uint32_t vertices, uint32_t materials,
                                   uint32_t nodes)
{
    gi_scene *s = calloc(1, sizeof *s);
    s->triangle_count = triangles;
    s->vertex_count = vertices;
    s->vertices = calloc(vertices, sizeof *s->vertices);
    s->indices = calloc(3 * (size_t)triangles, sizeof *s->indices);
    s->material_count = materials;
    s->materials = calloc(materials, sizeof *s->materials);
    for (uint32_t m = 0; m < materials; m++)
        s->materials[m].albedo_texture = -1;
    s->node_count = nodes;
    s->nodes = calloc(nodes, sizeof *s->nodes);
    for (uint32_t n = 0; n < nodes; n++) {
        s->nodes[n].parent = -1;
        s->nodes[n].rotation[3] = 1.0f;
        s->nodes[n].scale[0] = s->nodes[n].scale[1] = s->nodes[n].scale[2] = 1.0f;
    }
    s->object_count = 1;
    s->objects = calloc(1, sizeof *s->objects);
    s->objects[0].triangle_count = triangles;
    s->objects[0].vertex_count = vertices;
    return s;
}

/* A scene of the triangles tri[0 .. 9 count) (3 corners each), one material. */
static inline gi_scene *triangle_scene(const float *tri, uint32_t count)
{
    gi_scene *s = bare_scene(count, 3 * count, 1, 1);
    s->materials[0].albedo[0] = s->materials[0].albedo[1] = s->materials[0].albedo[2] = 0.5f;
    float lo[3] = {FLT_MAX, FLT_MAX, FLT_MAX}, hi[3] = {-FLT_MAX, -FLT_MAX, -FLT_MAX};
    for (uint32_t k = 0; k < 3 * count; k++) {
        gi_vertex *v = &s->vertices[k];
        memcpy(v->position, tri + 3 * (size_t)k, 3 * sizeof(float));
        v->normal[2] = 1.0f;
        s->indices[k] = k;
        for (int a = 0; a < 3; a++)
            lo[a] = fminf(lo[a], v->position[a]), hi[a] = fmaxf(hi[a], v->position[a]);
    }
    for (int a = 0; a < 3; a++)
        s->objects[0].local_bounds[a] = lo[a], s->objects[0].local_bounds[3 + a] = hi[a];
    return s;
}

/* Quad q of scene s (vertices 4 q .. 4 q + 3, triangles 2 q and 2 q + 1):
 * corners a, b, c, d in order, of the given material. */
static inline void add_quad(gi_scene *s, uint32_t q, gi_vec3 a, gi_vec3 b, gi_vec3 c, gi_vec3 d,
                            uint32_t material)
{
    gi_vec3 v[4] = {a, b, c, d};
    for (int k = 0; k < 4; k++) {
        gi_vertex *x = &s->vertices[4 * q + (uint32_t)k];
        x->position[0] = v[k].x, x->position[1] = v[k].y, x->position[2] = v[k].z;
        x->normal[2] = 1.0f;
        x->material = material;
    }
    uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    for (int k = 0; k < 6; k++)
        s->indices[6 * q + (uint32_t)k] = 4 * q + idx[k];
}

/* A part of a test program: its name on the command line and what it runs. */
typedef struct vlf_test_part {
    const char *name;
    void (*run)(void);
} vlf_test_part;

/* Runs the part of parts[0 .. count) named by argv[1], or all of them
 * without an argument; prints check.h's counts and returns its status, 2
 * for an unknown part. */
static inline int vlf_test_main(const char *program, const vlf_test_part *parts, size_t count,
                                int argc, char **argv)
{
    const char *part = argc > 1 ? argv[1] : "all";
    int all = strcmp(part, "all") == 0, any = 0;
    for (size_t k = 0; k < count; k++)
        if (all || strcmp(part, parts[k].name) == 0)
            parts[k].run(), any = 1;
    if (!any) {
        fprintf(stderr, "%s: unknown part '%s' (", program, part);
        for (size_t k = 0; k < count; k++)
            fprintf(stderr, "%s%s", k ? ", " : "", parts[k].name);
        fprintf(stderr, ")\n");
        return 2;
    }
    return gi_test_finish();
}

#endif
