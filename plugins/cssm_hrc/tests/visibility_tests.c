/* cssm_tests' part on the visibility of cssm_hrc's CSSM (§3.2.2):
 *   visibility  CSSM visibility against Embree occlusion between random
 *               Cornell-box texel / surface-point pairs, against the
 *               always-visible and never-visible answers */
#include "cssm_tests.h"

#include "check.h"

#include "gi/rng.h"

#include <stdio.h>

int cssm_test_visibility(void)
{
    cssm_fixture f;
    gi_error err = {0};
    if (cssm_fixture_open(&f, "scenes/cornell_box.gltf", 0.0f, 0.0f) ||
        cssm_maps_build(f.gs, &f.a, f.order, 32, NULL, &f.m, &err) != GI_OK) {
        if (f.order)
            fprintf(stderr, "FAIL: set-up: %s\n", err.text);
        cssm_fixture_close(&f);
        return 1;
    }
    const cssm_atlas *a = &f.a;
    const float bias = 0.004f * a->diameter; /* the plugin's default */
    const int pairs = 20000;
    int agree = 0, agree_pcf = 0, visible = 0, tried = 0, false_lit = 0, false_shadow = 0;
    uint32_t rng = gi_rng_init(7, 0, 0x715u);
    while (tried < pairs) {
        uint32_t j = gi_rng_next_u32(&rng) % a->count, i = gi_rng_next_u32(&rng) % a->count;
        gi_vec3 p, x, eye;
        if (i == j || !cssm_fixture_pair(&f, j, i, &rng, &p, &x, &eye))
            continue;
        tried++;
        int truth = cssm_fixture_truth(&f, f.rt0, eye, x);
        int v = cssm_visible(&f.m, j, x, bias, 0) > 0.5f;
        float vp = cssm_visible(&f.m, j, x, bias, 1);
        visible += truth;
        agree += v == truth;
        false_lit += v && !truth;
        false_shadow += !v && truth;
        agree_pcf += (vp > 0.5f) == truth;
    }
    double rate = (double)agree / tried, rate_pcf = (double)agree_pcf / tried;
    double always = (double)visible / tried, never = 1.0 - always;
    printf("visibility (Cornell box, atlas 32^2, 6 x 32 x 32, spiral, %d facing pairs): CSSM "
           "agrees with Embree on "
           "%.2f %% (PCF, thresholded at 1/2: %.2f %%); always-visible %.2f %%, never-visible %.2f "
           "%%\n",
           tried, 100 * rate, 100 * rate_pcf, 100 * always, 100 * never);
    printf("errors: %.2f %% lit where Embree finds an occluder, %.2f %% shadowed where it finds "
           "none\n",
           100.0 * false_lit / tried, 100.0 * false_shadow / tried);
    double trivial = always > never ? always : never;
    /* measured 96.25 % (PCF 96.41 %) against 72.48 % for always-visible
     * (README "Tests"): the misses, mostly false shadows, are the
     * discretisation of 32 x 32 faces and of the atlas (Fig. 14); maps by
     * the eye's rule fail it (91.87 %) */
    CHECK_MSG(rate >= 0.94, "CSSM agreement %.4f below 0.94", rate);
    CHECK_MSG(rate >= trivial + 0.20,
              "CSSM agreement %.4f not 20 points above the best trivial answer %.4f", rate,
              trivial);
    CHECK_MSG(rate_pcf >= 0.94, "PCF agreement %.4f below 0.94", rate_pcf);
    cssm_fixture_close(&f);
    return 0;
}
