/* avg_tests punctual: point and spot lights through their VPLs
 * (Bashford-Rogers et al. 2011 §III-B "weighted by the power of the light
 * source") against their closed-form direct light. */
#include "avg_tests.h"

#include "gi/lights.h"

#include <math.h>
#include <stdio.h>

/* EXPECT(cond, fmt, ...): CHECK_MSG of the unit tests' check.h, which
 * counts failures in gi_test_failed (this file's). */
#include "check.h"
#define EXPECT CHECK_MSG

/* tests/data/valid/lights.gltf (an emissive quad, a point, a spot and a
 * directional light over a floor) with direct light only, no visibility,
 * M = 1: the image must equal emission + albedo/pi x (the area-light VPLs'
 * sum + the exact point and spot light irradiance). The point light's VPLs
 * each cover one hemisphere at twice the intensity and the paths are split
 * among the lights by power, so this holds the split and the hemispheres
 * to the closed form (up to the rounding of path counts: 4096 paths). The
 * directional light is ignored by the method and by this sum. */
static void punctual_case(gi_gpu *gpu)
{
    avg_test_fixture fx;
    if (!avg_test_load_fixture(gpu, GI_SOURCE_DIR "/tests/data/valid/lights.gltf", &fx))
        return;
    const gi_scene *s = fx.s;
    gi_gpu_scene *gs = fx.gs;
    const char *kv[] = {"vpls=4096", "bounces=0",    "grid=16",
                        "M=1",       "filter=false", "visibility=false"};
    avg *a = avg_test_make_avg(&fx.host, gs, kv, 6);
    if (!a) {
        EXPECT(0, "cannot make the avg instance");
        return;
    }
    uint32_t w = 48, h = 48;
    avg_test_target t = avg_test_render_frame(a, s, w, h);
    gi_image *img = gi_gpu_read_texture(t.tex, w, h);
    avg_test_gbuffer gb = avg_test_read_gbuffer(a, w, h);
    const gi_image *pos = gb.pos, *nrm = gb.nrm, *alb = gb.alb, *emi = gb.emi;
    float dmin2 = a->clamp * a->grid->h * a->clamp * a->grid->h;
    double worst = 0.0, sum_got = 0.0, sum_expect = 0.0, punctual_share = 0.0;
    uint32_t lit = 0;
    for (size_t i = 0; i < (size_t)w * h; i++) {
        /* Receivers only: the lamp seen directly is exact either way. */
        if (pos->rgba[4 * i + 3] <= 0.0f ||
            emi->rgba[4 * i] + emi->rgba[4 * i + 1] + emi->rgba[4 * i + 2] > 0.0f)
            continue;
        gi_vec3 x = gi_v3_load(&pos->rgba[4 * i]),
                n = gi_v3_normalize(gi_v3_load(&nrm->rgba[4 * i]));
        double S[3] = {0, 0, 0}, P[3] = {0, 0, 0};
        for (uint32_t j = 0; j < a->vpl_count; j++) {
            if ((a->cpu_vpls[j].kind & 0xFFu) != AVG_VPL_DIFFUSE)
                continue;
            float c3[3], nn[3] = {n.x, n.y, n.z};
            avg_vpl_contribution(&a->cpu_vpls[j], &pos->rgba[4 * i], nn, dmin2, c3);
            for (int c = 0; c < 3; c++)
                S[c] += c3[c];
        }
        for (uint32_t l = 0; l < s->light_count; l++) {
            const gi_light *L = &s->lights[l];
            if (L->type == GI_LIGHT_DIRECTIONAL)
                continue;
            gi_light_frame f = gi_scene_light_at(s, l, 0.0f);
            gi_vec3 d = gi_v3_sub(f.position, x);
            float d2 = gi_v3_dot(d, d), dist = sqrtf(d2);
            gi_vec3 wl = gi_v3_scale(d, 1.0f / dist);
            float cx = gi_v3_dot(n, wl);
            if (cx <= 0.0f)
                continue;
            float g = cx / fmaxf(d2, dmin2) * gi_range_window(dist, L->range);
            if (L->type == GI_LIGHT_SPOT)
                g *= gi_spot_falloff(-gi_v3_dot(wl, f.direction), cosf(L->inner_cone),
                                     cosf(L->outer_cone));
            for (int c = 0; c < 3; c++)
                P[c] += L->intensity[c] * g;
        }
        for (int c = 0; c < 3; c++) {
            double expect = emi->rgba[4 * i + c] + alb->rgba[4 * i + c] / GI_PI * (S[c] + P[c]);
            double got = img->rgba[4 * i + c];
            sum_got += got;
            sum_expect += expect;
            punctual_share += alb->rgba[4 * i + c] / GI_PI * P[c];
            double rel = fabs(got - expect) / (fabs(expect) + 1e-3);
            worst = rel > worst ? rel : worst;
        }
        lit++;
    }
    printf("punctual: %u receiver pixels, %u VPLs, point and spot lights %.0f %% of their light; "
           "image sum %.5g against the "
           "closed form %.5g (%+.3f %%), largest pixel difference %.2f %%\n",
           lit, a->vpl_count, 100.0 * punctual_share / sum_expect, sum_got, sum_expect,
           100.0 * (sum_got - sum_expect) / sum_expect, 100.0 * worst);
    EXPECT(punctual_share > 0.2 * sum_expect,
           "the punctual lights carry too little of the light to test them");
    EXPECT(fabs(sum_got - sum_expect) < 0.01 * sum_expect, "image sum off by more than 1 %%");
    EXPECT(worst < 0.03, "a pixel differs by %.3g (relative)", worst);
    gi_image_free(img);
    avg_test_free_gbuffer(&gb);
    gi_method_entry(GI_ABI_VERSION)->destroy(a);
    avg_test_free_fixture(&fx);
}

int avg_test_punctual(gi_gpu *gpu)
{
    punctual_case(gpu);
    return gi_test_failed;
}
