/* The core's CSM precomputation loop (gi/algo/csm_precompute.h) on the Cornell
 * box: cube maps at three points compressed face by face (six codec
 * streams, batches that straddle cube maps) hold, per face and point, the
 * depths of the same face rendered on its own (the codec's lossless bound
 * z1 <= z_avg < z2); the callbacks see each map index once, in order, with
 * its own view; bad descs and a cancelling host fail with nothing owned. */
#include "check.h"
#include "gpu_fixture.h"
#include "gi/algo/csm_precompute.h"

#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAPSIZE 16u
#define POINTS 3u

typedef struct ctx {
    gi_vec3 eye[POINTS];
    uint32_t next_view, next_depths; /* the map index each callback expects next */
    int order_ok, view_ok;
} ctx;

static void cube_view(void *c, uint32_t q, gi_depth_view *out)
{
    ctx *x = c;
    x->order_ok &= q == x->next_view++;
    gi_depth_cube_view(x->eye[q / 6], 0.01f, 50.0f, (int)(q % 6), out);
}

static void plain_depths(void *c, uint32_t q, const gi_depth_view *v, const float *map, float *z1,
                         float *z2)
{
    ctx *x = c;
    x->order_ok &= q == x->next_depths++;
    gi_depth_view want;
    gi_depth_cube_view(x->eye[q / 6], 0.01f, 50.0f, (int)(q % 6), &want);
    x->view_ok &= memcmp(want.view, v->view, sizeof want.view) == 0;
    for (uint32_t t = 0; t < MAPSIZE * MAPSIZE; t++) {
        z1[t] = map[4 * t];
        z2[t] = map[4 * t] >= FLT_MAX ? FLT_MAX : map[4 * t + 1];
    }
}

/* The skip option: cube map 1 is not drawn; its faces reach `depths`
 * without view or map and are stored as "any value". */
static int skip_cube1(void *c, uint32_t q)
{
    (void)c;
    return q / 6 == 1;
}

static void cube_view_skipping(void *c, uint32_t q, gi_depth_view *out)
{
    ctx *x = c;
    x->view_ok &= q / 6 != 1; /* never asked for a skipped map's view */
    cube_view(c, q, out);
    x->next_view += q / 6 == 0 && q % 6 == 5 ? 6 : 0; /* the views of cube 1 are not asked for */
}

static void skipping_depths(void *c, uint32_t q, const gi_depth_view *v, const float *map,
                            float *z1, float *z2)
{
    ctx *x = c;
    if (q / 6 != 1) {
        x->view_ok &= v != NULL && map != NULL;
        if (map)
            plain_depths(c, q, v, map, z1, z2);
        return;
    }
    x->order_ok &= q == x->next_depths++;
    x->view_ok &= v == NULL && map == NULL;
    for (uint32_t t = 0; t < MAPSIZE * MAPSIZE; t++)
        z1[t] = -FLT_MAX, z2[t] = FLT_MAX;
}

static int calls_cancelled(const gi_host *h)
{
    (void)h;
    return 1;
}
static void no_stage(const gi_host *h, const char *name)
{
    (void)h, (void)name;
}
static void no_progress(const gi_host *h, const char *task, float f)
{
    (void)h, (void)task, (void)f;
}

int main(void)
{
    gi_error err;
    gi_gpu *gpu;
    gi_scene *s;
    gi_gpu_scene *gs;
    if (!gpu_fixture_load(GI_SOURCE_DIR "/scenes/cornell_box.gltf", &gpu, &s, &gs))
        return gi_test_finish();
    ctx x = {.order_ok = 1, .view_ok = 1};
    float cx = 0.5f * (s->bounds[0] + s->bounds[3]), cy = 0.5f * (s->bounds[1] + s->bounds[4]);
    float cz = 0.5f * (s->bounds[2] + s->bounds[5]), dx = 0.2f * (s->bounds[3] - s->bounds[0]);
    for (uint32_t k = 0; k < POINTS; k++)
        x.eye[k] = gi_v3(cx + dx * ((float)k - 1.0f), cy, cz);

    gi_csm_precompute_desc d = {
        .depth = {.size = MAPSIZE, .surfaces = 2, .metric = GI_DEPTH_RADIAL},
        .count = 6 * POINTS,
        .streams = 6,
        .batch = 5, /* batches straddle cube maps */
        .view = cube_view,
        .depths = plain_depths,
        .ctx = &x,
        .who = "test",
        .what = "cube faces"};
    gi_csm_data face[6];
    CHECK_MSG(gi_csm_precompute(gs, &d, face, &err) == GI_OK, "%s", err.text);
    CHECK(x.order_ok && x.view_ok && x.next_view == 6 * POINTS && x.next_depths == 6 * POINTS);

    /* each face of each cube map rendered on its own */
    gi_depth_renderer *dr = gi_depth_renderer_create(&d.depth, &err);
    CHECK_MSG(dr != NULL, "%s", err.text);
    GLuint tex = gi_depth_texture_create(dr, 6);
    uint32_t bad = 0, finite = 0;
    for (uint32_t k = 0; k < POINTS; k++) {
        gi_depth_view cube[6];
        gi_depth_cube_views(x.eye[k], 0.01f, 50.0f, cube);
        CHECK(gi_depth_render(dr, gs, cube, 6, tex, 0, &err) == GI_OK);
        for (uint32_t f = 0; f < 6; f++) {
            CHECK(face[f].M == MAPSIZE && face[f].N == POINTS);
            float *map = gi_depth_read_layer(tex, MAPSIZE, f);
            for (uint32_t t = 0; map && t < MAPSIZE * MAPSIZE; t++) {
                float z1 = map[4 * t], z2 = z1 >= FLT_MAX ? FLT_MAX : map[4 * t + 1];
                float z = gi_csm_lookup(&face[f], t, k);
                finite += z1 < FLT_MAX;
                bad += !(z1 <= z && (z < z2 || (z2 >= FLT_MAX && z <= z2) || z == z1));
            }
            free(map);
        }
    }
    printf(
        "6 streams x %u cube maps of %u^2: %u of %u texels outside [z1, z2) (%u with a surface)\n",
        POINTS, MAPSIZE, bad, 6 * POINTS * MAPSIZE * MAPSIZE, finite);
    CHECK(bad == 0);
    CHECK(finite >= 6 * POINTS * MAPSIZE * MAPSIZE * 3 / 4); /* the box is open at the front only */
    for (int f = 0; f < 6; f++)
        gi_csm_data_free(&face[f]);

    /* cube map 1 skipped: cubes 0 and 2 as before, cube 1 any value */
    x = (ctx){.order_ok = 1, .view_ok = 1, .eye = {x.eye[0], x.eye[1], x.eye[2]}};
    gi_csm_precompute_desc sk = d;
    sk.view = cube_view_skipping;
    sk.depths = skipping_depths;
    sk.skip = skip_cube1;
    CHECK_MSG(gi_csm_precompute(gs, &sk, face, &err) == GI_OK, "%s", err.text);
    CHECK(x.order_ok && x.view_ok && x.next_view == 6 * POINTS && x.next_depths == 6 * POINTS);
    uint32_t skip_bad = 0;
    for (uint32_t k = 0; k < POINTS; k++) {
        gi_depth_view cube[6];
        gi_depth_cube_views(x.eye[k], 0.01f, 50.0f, cube);
        CHECK(gi_depth_render(dr, gs, cube, 6, tex, 0, &err) == GI_OK);
        for (uint32_t f = 0; f < 6; f++) {
            float *map = gi_depth_read_layer(tex, MAPSIZE, f);
            for (uint32_t t = 0; map && t < MAPSIZE * MAPSIZE; t++) {
                float z1 = map[4 * t], z2 = z1 >= FLT_MAX ? FLT_MAX : map[4 * t + 1];
                float z = gi_csm_lookup(&face[f], t, k);
                if (k == 1) /* any value: the codec keeps whatever run passes through */
                    continue;
                skip_bad += !(z1 <= z && (z < z2 || (z2 >= FLT_MAX && z <= z2) || z == z1));
            }
            free(map);
        }
    }
    printf("cube map 1 skipped: %u texels of cubes 0 and 2 outside [z1, z2)\n", skip_bad);
    CHECK(skip_bad == 0);
    for (int f = 0; f < 6; f++)
        gi_csm_data_free(&face[f]);
    glDeleteTextures(1, &tex);
    gi_depth_renderer_free(dr);

    /* bad descs: nothing rendered, nothing owned */
    gi_csm_precompute_desc b = d;
    b.streams = 7;
    CHECK(gi_csm_precompute(gs, &b, face, &err) == GI_ERR_INVALID_ARGUMENT);
    b = d;
    b.count = 6 * POINTS + 1;
    CHECK(gi_csm_precompute(gs, &b, face, &err) == GI_ERR_INVALID_ARGUMENT);
    CHECK(face[0].offsets == NULL && face[5].offsets == NULL);
    printf("bad desc: %s\n", err.text);

    /* a host that cancels: GI_ERR_CANCELLED before the first batch */
    gi_host host = {.struct_size = sizeof host,
                    .progress = no_progress,
                    .stage_begin = no_stage,
                    .stage_end = no_stage,
                    .cancelled = calls_cancelled};
    b = d;
    b.host = &host;
    x.next_view = x.next_depths = 0;
    CHECK(gi_csm_precompute(gs, &b, face, &err) == GI_ERR_CANCELLED);
    CHECK(x.next_view == 0 && face[0].offsets == NULL && face[5].z_avg == NULL);

    CHECK(gi_gl_check("csm_precompute", &err) == GI_OK);
    gi_gpu_scene_free(gs);
    gi_scene_free(s);
    gi_gpu_destroy(gpu);
    return gi_test_finish();
}
