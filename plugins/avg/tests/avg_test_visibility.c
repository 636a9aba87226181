/* avg_tests visibility: the light VPLs' shadow maps (Bashford-Rogers et al.
 * 2011 §III-C; core depth atlas, paraboloid and perspective; and the maps
 * of the shadow_lod=0.1 copy on the Cornell box and Cornell moving)
 * against Embree shadow rays through the full scene for every receiver
 * pixel (the VPLs at hits lie inside voxels, behind their surface, by
 * design, and are not comparable with exact rays). */
#include "avg_tests.h"

#include "gi/algo/simplify.h"
#include "gi/raytrace.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* EXPECT(cond, fmt, ...): CHECK_MSG of the unit tests' check.h, which
 * counts failures in gi_test_failed (this file's). */
#include "check.h"
#define EXPECT CHECK_MSG
#include "vis_score.h"

/* The shadow-map test of avg_visibility.glsl on the CPU (same offsets and
 * biases as avg.c), given the atlas tiles read back: 1 visible, 0 shadowed. */
static int map_visible(const avg *a, const float *tiles, uint32_t j, gi_vec3 x, gi_vec3 n,
                       float bias_abs, float bias_rel)
{
    const gi_depth_atlas_desc *d = gi_depth_atlas_get_desc(a->atlas);
    uint32_t tx, ty;
    float zp;
    gi_vec3 xo = gi_v3_add(x, gi_v3_scale(n, bias_abs));
    if (!gi_depth_atlas_texel(&a->views[j], d->projection, d->metric, d->tile, xo, &tx, &ty, &zp))
        return 1;
    float zmap = tiles[(size_t)j * d->tile * d->tile + (size_t)ty * d->tile + tx];
    gi_vec3 w = gi_v3_normalize(gi_v3_sub(gi_v3_load(a->cpu_vpls[j].position), x));
    float c = fminf(fmaxf(gi_v3_dot(n, w), 0.05f), 1.0f);
    float slope = fminf(sqrtf(1.0f - c * c) / c, 10.0f);
    return zp <= zmap + bias_abs + bias_rel * (1.0f + slope) * zp;
}

static void visibility_case(gi_gpu *gpu, const char *scene, const char *projection, const char *lod)
{
    gi_error err;
    avg_test_fixture fx;
    if (!avg_test_load_fixture(gpu, scene, &fx))
        return;
    const gi_scene *s = fx.s;
    gi_gpu_scene *gs = fx.gs;
    char pkv[64], lkv[64];
    snprintf(pkv, sizeof pkv, "projection=%s", projection);
    snprintf(lkv, sizeof lkv, "shadow_lod=%s", lod);
    const char *kv[] = {"vpls=256", "grid=32", pkv, lkv};
    avg *a = avg_test_make_avg(&fx.host, gs, kv, 4);
    gi_rt *rt = NULL;
    if (!a || gi_rt_create(s, 0.0f, &rt, &err) != GI_OK) {
        EXPECT(0, "cannot make the avg instance or the ray caster");
        return;
    }
    uint32_t w = 32, h = 32;
    avg_test_render_frame(a, s, w, h);
    const gi_depth_atlas_desc *d = gi_depth_atlas_get_desc(a->atlas);
    float *tiles = malloc((size_t)a->vpl_count * d->tile * d->tile * sizeof *tiles);
    for (uint32_t j = 0; j < a->vpl_count; j++) {
        float *tile = gi_depth_atlas_read_tile(a->atlas, j);
        memcpy(tiles + (size_t)j * d->tile * d->tile, tile,
               (size_t)d->tile * d->tile * sizeof *tiles);
        free(tile);
    }
    avg_test_gbuffer gb = avg_test_read_gbuffer(a, w, h);
    const gi_image *pos = gb.pos, *nrm = gb.nrm;
    uint32_t pairs = 0, agree = 0, false_shadow = 0, false_light = 0;
    vis_score score = {0};
    float bias_abs = 0.5f * a->grid->h, bias_rel = 1.0f / (float)a->tile; /* AVG_BIAS_* in avg.c */
    for (size_t i = 0; i < (size_t)w * h; i++) {
        if (pos->rgba[4 * i + 3] <= 0.0f)
            continue;
        gi_vec3 x = gi_v3_load(&pos->rgba[4 * i]),
                n = gi_v3_normalize(gi_v3_load(&nrm->rgba[4 * i]));
        for (uint32_t j = 0; j < a->vpl_count; j++) {
            float c3[3];
            avg_vpl_contribution(&a->cpu_vpls[j], &pos->rgba[4 * i], &nrm->rgba[4 * i], 0.0f, c3);
            if (c3[0] + c3[1] + c3[2] <= 0.0f || (a->cpu_vpls[j].kind >> 8 & 0xFFu) != 0)
                continue;
            gi_vec3 y = gi_v3_load(a->cpu_vpls[j].position);
            gi_vec3 dir = gi_v3_sub(y, x);
            float dist = gi_v3_length(dir);
            /* Ray from just off the receiver to just short of the VPL. */
            int blocked = gi_rt_occluded(rt, gi_v3_add(x, gi_v3_scale(n, 1e-3f)),
                                         gi_v3_scale(dir, 1.0f / dist), 0.0f, dist - 1e-2f);
            int vis = map_visible(a, tiles, j, x, n, bias_abs, bias_rel);
            pairs++;
            agree += vis == !blocked;
            vis_add(&score, !blocked, vis);
            false_shadow += !vis && !blocked;
            false_light += vis && blocked;
        }
    }
    const char *used = gi_depth_atlas_get_desc(a->atlas)->projection == GI_PROJ_PARABOLOID
                           ? "paraboloid"
                           : "perspective";
    printf("visibility %s %s (%s maps) shadow_lod=%s (%u triangles a map): %u receiver-VPL pairs, "
           "shadow maps agree "
           "with Embree on %.2f %% (%u falsely shadowed, %u falsely lit)\n",
           strrchr(scene, '/') + 1, projection, used, lod,
           a->lod ? a->lod->triangle_count : s->triangle_count, pairs,
           100.0 * agree / (pairs ? pairs : 1), false_shadow, false_light);
    EXPECT(agree >= pairs - pairs / 20, "shadow maps agree with ray casting on only %u of %u pairs",
           agree, pairs);
    EXPECT(pairs > 10000, "too few pairs (%u)", pairs);
    char what[96];
    snprintf(what, sizeof what, "visibility %s shadow_lod=%s, light-VPL shadow maps vs Embree",
             projection, lod);
    gi_test_failed += vis_check(&score, what, VIS_MARGIN, 1000);
    free(tiles);
    avg_test_free_gbuffer(&gb);
    gi_rt_free(rt);
    gi_method_entry(GI_ABI_VERSION)->destroy(a);
    avg_test_free_fixture(&fx);
}

int avg_test_visibility(gi_gpu *gpu)
{
    visibility_case(gpu, GI_SOURCE_DIR "/scenes/cornell_box.gltf", "paraboloid", "1");
    visibility_case(gpu, GI_SOURCE_DIR "/scenes/cornell_box.gltf", "perspective", "1");
    /* Maps of the lower-detail copy (the auto rule then picks
     * perspective maps) against rays through the full scene. */
    visibility_case(gpu, GI_SOURCE_DIR "/scenes/cornell_box.gltf", "auto", "0.1");
    visibility_case(gpu, GI_SOURCE_DIR "/scenes/cornell_moving.gltf", "auto", "0.1");
    return gi_test_failed;
}
