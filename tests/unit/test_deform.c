/* Deforming geometry: glTF morph targets evaluated on the CPU (weights,
 * blended positions and normals, conservative bounds, world triangles),
 * placed by gi_rt at time t (hits move with the surface), written into the
 * GPU vertex buffer by gi_gpu_scene_set_time (equal to the CPU's vertices,
 * byte for byte), and caller-driven deformation through
 * gi_gpu_scene_update_vertices + gi_rt_refresh, with its error cases.
 * Hand-computed values come from tests/data/valid/morph.gltf (see
 * gen_scenes.py valid_morph) and scenes/cornell_deform.gltf
 * (scripts/make_scenes.py short_block_morph). */
#include "check.h"

#include "gi/gpu.h"
#include "gi/mesh.h"
#include "gi/raytrace.h"
#include "gi/scene.h"

#include <float.h>
#include <stdlib.h>
#include <string.h>

#define VALID GI_TEST_DATA "/valid/"

static gi_scene *load(const char *path)
{
    gi_error err;
    gi_scene *s = gi_scene_load(path, &err);
    if (!s) {
        fprintf(stderr, "%s\n", err.text);
        exit(1);
    }
    return s;
}

/* Object 0 'morphing' weights: LINEAR from [0, 0] at t = 0 to [1, 2] at
 * t = 2, held after; object 1 'posed': node.weights [0, 1] (overriding
 * mesh.weights [0.25, 0]). */
static void test_weights(const gi_scene *s)
{
    CHECK(s->object_count == 3 && gi_scene_deforms(s));
    CHECK(s->objects[0].morph_count == 2 && s->objects[0].morph_track.count == 2);
    CHECK(s->objects[1].morph_count == 2 && s->objects[1].morph_track.count == 0);
    CHECK(s->objects[2].morph_count == 0 && !s->objects[2].morph_positions);
    CHECK(s->objects[0].morph_normals != NULL);
    CHECK_NEAR(s->animation_length, 2.0, 0.0);
    const float ts[] = {-1.0f, 0.0f, 0.5f, 1.0f, 2.0f, 7.0f};
    const float w0[] = {0.0f, 0.0f, 0.25f, 0.5f, 1.0f, 1.0f};
    for (size_t i = 0; i < sizeof ts / sizeof ts[0]; i++) {
        float w[2] = {-9, -9};
        gi_scene_morph_weights(s, 0, ts[i], w);
        CHECK_NEAR(w[0], w0[i], 1e-7);
        CHECK_NEAR(w[1], 2.0f * w0[i], 1e-7);
        gi_scene_morph_weights(s, 1, ts[i], w);
        CHECK(w[0] == 0.0f && w[1] == 1.0f);
    }
}

/* At t = 1 (weights [0.5, 1]): every vertex + (0, 0, 0.5), vertex 2 also
 * + (1, 0, 0); normals normalize((0, 0, 1) + 0.5 (0, 0.5, 0)). */
static void test_vertices(const gi_scene *s)
{
    static const float quad[4][3] = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
    gi_vertex v[6]; /* 'rigid' has no NORMAL: flat, 3 vertices a triangle */
    gi_scene_object_vertices(s, 0, 1.0f, v);
    float nl = sqrtf(0.25f * 0.25f + 1.0f);
    for (int i = 0; i < 4; i++) {
        CHECK_NEAR(v[i].position[0], quad[i][0] + (i == 2 ? 1.0f : 0.0f), 1e-6);
        CHECK_NEAR(v[i].position[1], quad[i][1], 1e-6);
        CHECK_NEAR(v[i].position[2], 0.5f, 1e-6);
        CHECK_NEAR(v[i].normal[0], 0.0f, 1e-6);
        CHECK_NEAR(v[i].normal[1], 0.25f / nl, 1e-6);
        CHECK_NEAR(v[i].normal[2], 1.0f / nl, 1e-6);
        CHECK(v[i].object == 0 && v[i].material == s->vertices[i].material);
        gi_vec3 p = gi_scene_vertex_position(s, (uint32_t)i, 1.0f); /* the same blend */
        CHECK(p.x == v[i].position[0] && p.y == v[i].position[1] && p.z == v[i].position[2]);
    }
    /* 'posed' at any t: only target 1 at weight 1; the rest pose is stored unchanged. */
    gi_scene_object_vertices(s, 1, 0.0f, v);
    CHECK_NEAR(v[2].position[0], 2.0f, 1e-6);
    CHECK_NEAR(v[0].position[2], 0.0f, 0.0);
    CHECK(s->vertices[s->objects[1].first_vertex + 2].position[0] == 1.0f);
    /* the rigid object is a plain copy */
    CHECK(s->objects[2].vertex_count == 6);
    gi_scene_object_vertices(s, 2, 1.0f, v);
    CHECK(memcmp(v, s->vertices + s->objects[2].first_vertex, 6 * sizeof *v) == 0);
    /* world triangle of 'posed' (translation 0, 0, -3): triangle 2 = (0, 1, 2) */
    gi_vec3 p[3];
    gi_scene_triangle_world(s, s->objects[1].first_triangle, 5.0f, p);
    CHECK_NEAR(p[2].x, 2.0f, 1e-6);
    CHECK_NEAR(p[2].z, -3.0f, 1e-6);
    /* Triangle areas follow the morph: 'posed' triangle 0 = (-1,-1) (1,-1) (2,1): area 2. */
    float areas[6];
    gi_mesh_triangle_areas(s, 1.0f, areas);
    CHECK_NEAR(areas[s->objects[1].first_triangle], 2.0f, 1e-6);
    CHECK_NEAR(areas[s->objects[2].first_triangle], 2.0f, 1e-6);
    CHECK_NEAR(areas[s->objects[2].first_triangle + 1], 2.0f, 1e-6);
    CHECK_NEAR(areas[s->objects[1].first_triangle + 1], 3.0f, 1e-6); /* (-1,-1) (2,1) (-1,1) */
    /* Bounds over the weights reached: x up to 1 + 2, z 0 .. 1 (morphing). */
    const float *lb = s->objects[0].local_bounds;
    CHECK(lb[0] == -1.0f && lb[3] == 3.0f && lb[2] == 0.0f && lb[5] == 1.0f);
    lb = s->objects[1].local_bounds;
    CHECK(lb[3] == 2.0f && lb[2] == 0.0f && lb[5] == 0.0f);
}

/* The .glb twin holds the same morph data. */
static void test_glb(const gi_scene *s)
{
    gi_scene *g = load(VALID "morph.glb");
    for (uint32_t o = 0; o < 2; o++) {
        const gi_object *a = &s->objects[o], *b = &g->objects[o];
        size_t n = (size_t)a->morph_count * a->vertex_count * 3;
        CHECK(a->morph_count == b->morph_count && a->vertex_count == b->vertex_count);
        CHECK(memcmp(a->morph_positions, b->morph_positions, n * sizeof(float)) == 0);
        CHECK(!a->morph_normals == !b->morph_normals);
        CHECK(memcmp(a->morph_weights, b->morph_weights, a->morph_count * sizeof(float)) == 0);
        CHECK(a->morph_track.count == b->morph_track.count);
    }
    gi_scene_free(g);
    gi_scene *q = load(VALID "quad.gltf");
    CHECK(!gi_scene_deforms(q));
    gi_scene_free(q);
}

/* gi_rt follows the morph: a ray down -Z through (0, 0) hits z = w0(t). */
static void test_raytrace(const gi_scene *s)
{
    gi_error err;
    gi_rt *rt = NULL;
    CHECK(gi_rt_create(s, 0.0f, &rt, &err) == GI_OK);
    if (!rt)
        return;
    const float ts[] = {0.0f, 1.0f, 2.0f, 0.5f};
    for (size_t i = 0; i < sizeof ts / sizeof ts[0]; i++) {
        CHECK(gi_rt_set_time(rt, ts[i], &err) == GI_OK);
        float w[2];
        gi_scene_morph_weights(s, 0, ts[i], w);
        gi_rt_hit h;
        int hit = gi_rt_intersect(rt, gi_v3(0.0f, 0.0f, 5.0f), gi_v3(0.0f, 0.0f, -1.0f), 0.0f,
                                  INFINITY, &h);
        CHECK(hit && h.object == 0);
        CHECK_NEAR(h.t, 5.0f - w[0], 1e-5);
        /* every placed vertex equals the CPU blend, placed by the transform */
        const float *pos = gi_rt_positions(rt);
        int same = 1;
        for (uint32_t v = 0; v < s->vertex_count; v++) {
            float m[16];
            gi_scene_object_transform(s, s->vertices[v].object, ts[i], m);
            gi_vec3 p = gi_mat4_point(m, gi_scene_vertex_position(s, v, ts[i]));
            same &= p.x == pos[3 * v] && p.y == pos[3 * v + 1] && p.z == pos[3 * v + 2];
        }
        CHECK(same);
    }
    gi_rt_free(rt);
}

/* The GPU vertex buffer after set_time(t) holds exactly the CPU vertices. */
static int gpu_matches(const gi_gpu_scene *gs, const gi_scene *s, float t)
{
    gi_vertex *gpu = malloc(s->vertex_count * sizeof *gpu),
              *cpu = malloc(s->vertex_count * sizeof *cpu);
    if (!gpu || !cpu)
        exit(1);
    glGetNamedBufferSubData(gs->vbo, 0, (GLsizeiptr)(s->vertex_count * sizeof *gpu), gpu);
    for (uint32_t o = 0; o < s->object_count; o++)
        gi_scene_object_vertices(s, o, t, cpu + s->objects[o].first_vertex);
    int same = memcmp(gpu, cpu, s->vertex_count * sizeof *gpu) == 0;
    free(gpu);
    free(cpu);
    return same;
}

static void test_gpu(gi_gpu *gpu, gi_scene *s)
{
    gi_error err;
    gi_gpu_scene *gs = gi_gpu_scene_upload(gpu, s, &err);
    CHECK(gs != NULL);
    if (!gs)
        return;
    CHECK(gs->deforming);
    CHECK(gpu_matches(gs, s, 0.0f));
    const float ts[] = {1.0f, 2.0f, 0.25f, 0.0f};
    for (size_t i = 0; i < sizeof ts / sizeof ts[0]; i++) {
        gi_gpu_scene_set_time(gs, ts[i]);
        CHECK_MSG(gpu_matches(gs, s, ts[i]), "t = %g", (double)ts[i]);
    }
    gi_gpu_scene_set_time(gs, 1.0f);
    CHECK(!gpu_matches(gs, s, 0.0f)); /* the comparison can fail */

    /* Caller-driven deformation of the rigid object: lift it by 0.5 in y in
     * the scene we own, upload, refresh gi_rt: both see it. */
    const gi_object *o = &s->objects[2];
    gi_vertex *v = s->vertices + o->first_vertex;
    gi_rt *rt = NULL;
    CHECK(gi_rt_create(s, 1.0f, &rt, &err) == GI_OK);
    gi_rt_hit h;
    /* rigid quad at y - 3: a ray down -Z through (0, -3.9) hits it, later misses */
    CHECK(rt &&
          gi_rt_intersect(rt, gi_v3(0.0f, -3.9f, 5.0f), gi_v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY,
                          &h) &&
          h.object == 2);
    for (uint32_t i = 0; i < o->vertex_count; i++)
        v[i].position[1] += 0.5f;
    CHECK(gi_gpu_scene_update_vertices(gs, o->first_vertex, o->vertex_count, v, &err) == GI_OK);
    CHECK(gpu_matches(gs, s, 1.0f));
    CHECK(gi_rt_set_time(rt, 1.0f, &err) == GI_OK); /* same time: no re-placement ... */
    CHECK(rt && gi_rt_intersect(rt, gi_v3(0.0f, -3.9f, 5.0f), gi_v3(0.0f, 0.0f, -1.0f), 0.0f,
                                INFINITY, &h));
    CHECK(gi_rt_refresh(rt, &err) == GI_OK); /* ... until refreshed */
    CHECK(rt &&
          !gi_rt_occluded(rt, gi_v3(0.0f, -3.9f, 5.0f), gi_v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY));
    CHECK(rt &&
          gi_rt_intersect(rt, gi_v3(0.0f, -3.4f, 5.0f), gi_v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY,
                          &h) &&
          h.object == 2);
    gi_rt_free(rt);

    /* errors: past the end, object changed, NaN, NULL */
    gi_vertex bad = v[0];
    CHECK(gi_gpu_scene_update_vertices(gs, s->vertex_count, 1, &bad, &err) ==
          GI_ERR_INVALID_ARGUMENT);
    CHECK(strstr(err.text, "past the") != NULL);
    CHECK(gi_gpu_scene_update_vertices(gs, UINT32_MAX, 2, &bad, &err) == GI_ERR_INVALID_ARGUMENT);
    bad.object = 0;
    CHECK(gi_gpu_scene_update_vertices(gs, o->first_vertex, 1, &bad, &err) ==
          GI_ERR_INVALID_ARGUMENT);
    CHECK(strstr(err.text, "changes its object") != NULL);
    bad = v[0];
    bad.position[0] = NAN;
    CHECK(gi_gpu_scene_update_vertices(gs, o->first_vertex, 1, &bad, &err) ==
          GI_ERR_INVALID_ARGUMENT);
    CHECK(strstr(err.text, "not finite") != NULL);
    CHECK(gi_gpu_scene_update_vertices(gs, 0, 1, NULL, &err) == GI_ERR_INVALID_ARGUMENT);
    CHECK(gpu_matches(gs, s, 1.0f)); /* failures wrote nothing */
    gi_gpu_scene_free(gs);
}

/* The Cornell box's short block: stretch d = (0, 0.5 y, 0), bulge
 * d = 0.2 sin(pi y / h) (x, 0, z); weights (0,0) (1,0) (1,1) (0,1) (0,0) at
 * t = 0..4. At t = 1 the top is at 1.5 h; at t = 3 the heights are back
 * and mid-height points moved out by 1.2. */
static void test_cornell(gi_gpu *gpu)
{
    gi_scene *s = load(GI_SOURCE_DIR "/scenes/cornell_deform.gltf");
    uint32_t ob = UINT32_MAX;
    for (uint32_t o = 0; o < s->object_count; o++)
        if (strcmp(s->objects[o].name, "short_block") == 0)
            ob = o;
    CHECK(ob != UINT32_MAX && s->objects[ob].morph_count == 2);
    if (ob == UINT32_MAX)
        return;
    const gi_object *o = &s->objects[ob];
    gi_vertex *v1 = malloc(o->vertex_count * sizeof *v1),
              *v3 = malloc(o->vertex_count * sizeof *v3);
    gi_scene_object_vertices(s, ob, 1.0f, v1);
    gi_scene_object_vertices(s, ob, 3.0f, v3);
    float h = 0.0f;
    for (uint32_t i = 0; i < o->vertex_count; i++)
        h = fmaxf(h, s->vertices[o->first_vertex + i].position[1]);
    double e1 = 0.0, e3 = 0.0;
    for (uint32_t i = 0; i < o->vertex_count; i++) {
        const float *r = s->vertices[o->first_vertex + i].position;
        float b = 0.2f * sinf(GI_PI * r[1] / h);
        e1 = fmax(e1, fabs(v1[i].position[1] - 1.5 * r[1]) + fabs(v1[i].position[0] - r[0]));
        e3 =
            fmax(e3, fabs(v3[i].position[0] - (1 + b) * r[0]) +
                         fabs(v3[i].position[2] - (1 + b) * r[2]) + fabs(v3[i].position[1] - r[1]));
    }
    CHECK_MSG(e1 < 1e-5 && e3 < 1e-5, "max error %g (t = 1), %g (t = 3)", e1, e3);
    /* bounds hold every pose */
    int inside = 1;
    for (float t = 0.0f; t <= 4.0f; t += 0.125f) {
        gi_scene_object_vertices(s, ob, t, v1);
        for (uint32_t i = 0; i < o->vertex_count; i++)
            for (int k = 0; k < 3; k++)
                inside &= v1[i].position[k] >= o->local_bounds[k] &&
                          v1[i].position[k] <= o->local_bounds[k + 3];
    }
    CHECK(inside);
    free(v1);
    free(v3);
    gi_error err;
    gi_gpu_scene *gs = gi_gpu_scene_upload(gpu, s, &err);
    CHECK(gs != NULL);
    if (gs) {
        gi_gpu_scene_set_time(gs, 2.5f);
        CHECK(gpu_matches(gs, s, 2.5f));
        gi_gpu_scene_free(gs);
    }
    gi_scene_free(s);
}

int main(void)
{
    gi_scene *s = load(VALID "morph.gltf");
    test_weights(s);
    test_vertices(s);
    test_glb(s);
    test_raytrace(s);
    gi_error err;
    gi_gpu *gpu = gi_gpu_create(NULL, &err);
    CHECK(gpu != NULL);
    if (gpu) {
        test_gpu(gpu, s);
        test_cornell(gpu);
        gi_gpu_destroy(gpu);
    }
    gi_scene_free(s);
    return gi_test_finish();
}
