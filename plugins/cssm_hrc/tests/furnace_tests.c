/* cssm_tests' furnace parts on cssm_hrc's lighting (§4.1) and final
 * gather (§4.4; the Monte Carlo alternative of §4.6):
 *   furnace          inside a closed emitting sphere (Le = 1, rho = 0.5)
 *                    the atlas holds Le sum_{k<=n} rho^k and a final
 *                    gather Le sum_{k<=n+1} rho^k, within 2 %, for
 *                    n = 1, 2, 3
 *   compact_furnace  the same with nodes=compact (§4.2.1) */
#include "cssm_tests.h"

#include "check.h"

#include "gi/rng.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

static const double rho = 0.5, Le = 1.0;
static const int P = 200; /* final-gather receivers per n */

/* The furnace scene with its atlas (24^2), tree (packed too with
 * compact), greedy order and maps (6 x 16 x 16), the light arrays, the
 * gathers' options. */
typedef struct furnace {
    gi_gpu *gpu;
    gi_scene *s;
    gi_gpu_scene *gs;
    cssm_atlas a;
    cssm_maps m;
    cssm_tree t;
    cssm_ctree ct;
    uint32_t *order;
    float *L, *NL; /* per texel, per node */
    cssm_gather_opts o;
} furnace;

/* 0 on success; 1 with the message printed. */
static int furnace_open(furnace *f, int compact)
{
    f->gpu = NULL;
    f->s = NULL;
    f->gs = NULL;
    if (!cssm_test_load_gpu("tests/data/conformance/furnace_050.gltf", &f->gpu, &f->s, &f->gs))
        return 1;
    gi_error err;
    f->ct = (cssm_ctree){0};
    if (cssm_atlas_build(f->s, 0.0f, 24, 0, &f->a, &err) != GI_OK ||
        cssm_tree_build(&f->a, &f->t, &err) != GI_OK ||
        (compact && cssm_ctree_build(&f->t, &f->a, &f->ct, &err) != GI_OK)) {
        fprintf(stderr, "FAIL: %s\n", err.text);
        return 1;
    }
    f->order = cssm_traverse(&f->a, CSSM_GREEDY);
    if (!f->order || cssm_maps_build(f->gs, &f->a, f->order, 16, NULL, &f->m, &err) != GI_OK) {
        fprintf(stderr, "FAIL: %s\n", f->order ? err.text : "traverse");
        return 1;
    }
    f->L = malloc(3 * f->a.count * sizeof *f->L), f->NL = malloc(3 * f->t.count * sizeof *f->NL);
    f->o = (cssm_gather_opts){.threshold = 0.1f,
                              .max_cut = 1024,
                              /* the plugin's defaults */ .clamp = 0.02f * f->a.diameter,
                              .bias = 0.004f * f->a.diameter};
    return 0;
}

static void furnace_close(furnace *f)
{
    cssm_ctree_free(&f->ct);
    free(f->L);
    free(f->NL);
    free(f->order);
    cssm_maps_free(&f->m);
    cssm_tree_free(&f->t);
    cssm_atlas_free(&f->a);
    gi_gpu_scene_free(f->gs);
    gi_gpu_destroy(f->gpu);
    gi_scene_free(f->s);
}

/* The atlas' mean radiance (grey) and its worst texel's relative error
 * against `expect`. */
static double furnace_atlas_mean(const furnace *f, double expect, double *worst_out)
{
    double mean = 0, worst = 0;
    for (uint32_t i = 0; i < f->a.count; i++) {
        double v = (f->L[3 * i] + f->L[3 * i + 1] + f->L[3 * i + 2]) / 3.0;
        mean += v;
        worst = fmax(worst, fabs(v / expect - 1.0));
    }
    mean /= f->a.count;
    *worst_out = worst;
    return mean;
}

/* The mean of Le + the final gather at P receivers just inside the
 * sphere (random texels from rng), seen from the centre. */
static double furnace_final_gather(const furnace *f, int compact, uint32_t *rng)
{
    double pmean = 0;
    for (int k = 0; k < P; k++) {
        const cssm_texel *x = &f->a.texels[gi_rng_next_u32(rng) % f->a.count];
        cssm_receiver rc = {
            .x = cssm_receiver_point(&f->m, &f->a, x->p, x->n), .n = x->n, .self = -1, .glossy = 1};
        for (int c = 0; c < 3; c++)
            rc.kd[c] = (float)rho;
        rc.wo = x->n;
        float out[3];
        if (compact)
            cssm_cgather(&f->ct, &f->a, &f->m, &rc, &f->o, out, NULL);
        else
            cssm_gather(&f->t, &f->a, &f->m, f->NL, &rc, &f->o, out, NULL);
        pmean += Le + (out[0] + out[1] + out[2]) / 3.0;
    }
    pmean /= P;
    return pmean;
}

/* The same final gather by Monte Carlo from the atlas as a pdf (Sec.
 * 4.6), 64 texels per receiver, checked against `expect`. */
static void furnace_mc(const furnace *f, uint32_t n, uint32_t *rng, double expect)
{
    double *cdf = malloc((f->a.count + 1) * sizeof *cdf);
    double mc = 0;
    cssm_pdf_build(&f->a, f->L, cdf);
    for (int k = 0; k < P; k++) {
        const cssm_texel *x = &f->a.texels[gi_rng_next_u32(rng) % f->a.count];
        cssm_receiver rc = {
            .x = cssm_receiver_point(&f->m, &f->a, x->p, x->n), .n = x->n, .self = -1};
        for (int c = 0; c < 3; c++)
            rc.kd[c] = (float)rho;
        cssm_gather_opts om = f->o;
        om.rng = rng;
        float out[3];
        cssm_gather_mc(&f->a, &f->m, f->L, cdf, 64, &rc, &om, out);
        mc += Le + (out[0] + out[1] + out[2]) / 3.0;
    }
    mc /= P;
    free(cdf);
    printf("furnace n = %u: Monte Carlo final gather (64 texels x %d receivers) %.4f (%+.2f %%)\n",
           n, P, mc, 100 * (mc / expect - 1));
    CHECK_MSG(fabs(mc / expect - 1) <= 0.02,
              "n = %u: Monte Carlo final gather off by more than 2 %%", n);
}

int cssm_test_furnace(int compact)
{
    furnace f;
    if (furnace_open(&f, compact))
        return 1;
    const char *how = compact ? " (nodes=compact)" : "";
    printf("furnace: %u surface samples on the sphere\n", f.a.count);
    for (uint32_t n = 1; n <= 3; n++) {
        cssm_gather_stats st = {0};
        gi_error err;
        if (cssm_solve_ex(&f.t, compact ? &f.ct : NULL, &f.a, &f.m, &f.o, n, NULL, NULL, f.L, f.NL,
                          &st, &err) != GI_OK) {
            fprintf(stderr, "FAIL: %s\n", err.text);
            return 1;
        }
        double atlas_expect = 0, pixel_expect = 0;
        for (uint32_t k = 0; k <= n; k++)
            atlas_expect += Le * pow(rho, k);
        pixel_expect = atlas_expect + Le * pow(rho, n + 1);
        double worst;
        double mean = furnace_atlas_mean(&f, atlas_expect, &worst);
        uint32_t rng = gi_rng_init(n, 0, 0xf00u);
        double pmean = furnace_final_gather(&f, compact, &rng);
        printf("furnace%s n = %u: atlas mean %.4f (expected %.4f, %+.2f %%, worst texel %.2f %%), "
               "final gather %.4f "
               "(expected %.4f, %+.2f %%); emission only %+.1f %%, black -100 %%; mean cut %.1f\n",
               how, n, mean, atlas_expect, 100 * (mean / atlas_expect - 1), 100 * worst, pmean,
               pixel_expect, 100 * (pmean / pixel_expect - 1), 100 * (Le / pixel_expect - 1),
               (double)st.nodes / st.receivers);
        CHECK_MSG(fabs(mean / atlas_expect - 1) <= 0.02, "n = %u: atlas off by more than 2 %%", n);
        CHECK_MSG(fabs(pmean / pixel_expect - 1) <= 0.02,
                  "n = %u: final gather off by more than 2 %%", n);
        if (compact) /* the Monte Carlo gather reads no hierarchy */
            continue;
        furnace_mc(&f, n, &rng, pixel_expect);
    }
    furnace_close(&f);
    return 0;
}
