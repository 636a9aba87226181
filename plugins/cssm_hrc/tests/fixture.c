/* The GL scene fixture of cssm_tests' visibility, motion and escape parts
 * (cssm_tests.h): a scene with its GL context and Embree, its atlas and
 * spiral order; a facing texel / point pair and Embree's answer for it. */
#include "cssm_tests.h"

#include "gi/rng.h"
#include "gi/sampling.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int cssm_fixture_open(cssm_fixture *f, const char *rel, float t0, float t1)
{
    memset(f, 0, sizeof *f);
    if (!cssm_test_load_gpu(rel, &f->gpu, &f->s, &f->gs))
        return 1;
    gi_error err = {0};
    if (gi_rt_create(f->s, t0, &f->rt0, &err) != GI_OK ||
        (t1 != t0 && gi_rt_create(f->s, t1, &f->rt1, &err) != GI_OK)) {
        fprintf(stderr, "FAIL: set-up: %s\n", err.text);
        return 1;
    }
    if (cssm_atlas_build(f->s, t0, 32, 0, &f->a, &err) != GI_OK) {
        fprintf(stderr, "FAIL: set-up: atlas: %s\n", err.text);
        return 1;
    }
    f->order = cssm_traverse(&f->a, CSSM_SPIRAL);
    if (!f->order) {
        fprintf(stderr, "FAIL: set-up: traverse\n");
        return 1;
    }
    return 0;
}

void cssm_fixture_close(cssm_fixture *f)
{
    free(f->order);
    cssm_maps_free(&f->m);
    cssm_motion_free(&f->mo);
    cssm_atlas_free(&f->a);
    gi_rt_free(f->rt0);
    gi_rt_free(f->rt1);
    gi_gpu_scene_free(f->gs);
    gi_gpu_destroy(f->gpu);
    gi_scene_free(f->s);
}

int cssm_fixture_pair(const cssm_fixture *f, uint32_t j, uint32_t i, uint32_t *rng, gi_vec3 *p,
                      gi_vec3 *x, gi_vec3 *eye)
{
    const cssm_texel *tj = &f->a.texels[j], *ti = &f->a.texels[i];
    gi_vec3 tu, tv;
    gi_onb(ti->n, &tu, &tv);
    float side = sqrtf(ti->area);
    *p =
        gi_v3_add(ti->p, gi_v3_add(gi_v3_scale(tu, (gi_rng_next_float(rng) - 0.5f) * side * 0.9f),
                                   gi_v3_scale(tv, (gi_rng_next_float(rng) - 0.5f) * side * 0.9f)));
    *x = cssm_receiver_point(&f->m, &f->a, *p, ti->n);
    *eye = cssm_motion_eye(f->m.motion, &f->m, j);
    gi_vec3 d = gi_v3_sub(*x, *eye);
    return gi_v3_dot(d, tj->n) > 0.0f && gi_v3_dot(d, ti->n) < 0.0f;
}

int cssm_fixture_truth(const cssm_fixture *f, const gi_rt *rt, gi_vec3 eye, gi_vec3 x)
{
    /* cast from x toward the eye, as the reference casts a ray from a
     * receiver toward the light it gathers (the rule for sides, gi/scene.h,
     * makes visibility depend on the direction) */
    gi_vec3 d = gi_v3_sub(eye, x);
    float len = gi_v3_length(d);
    d = gi_v3_scale(d, 1.0f / len);
    return !gi_rt_occluded(rt, x, d, 1e-4f * f->a.diameter, len * (1.0f - 1e-4f));
}
