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
#include <string.h>

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

/* Mean radiance the floor texels (normal up, y below 1 cm) gather from
 * the nodes' light NL with options o, jittered (§4.5) 8 times each as
 * the final gather of 8 frames does; maps NULL: unshadowed. */
static double floor_gather(const cssm_atlas *a, const cssm_tree *t, const cssm_maps *m,
                           const float *NL, cssm_gather_opts o)
{
    double sum = 0;
    uint32_t n = 0, rng = gi_rng_init(7, 0, 0x4e9u);
    o.rng = &rng;
    for (uint32_t i = 0; i < a->count; i++) {
        const cssm_texel *x = &a->texels[i];
        if (x->n.y < 0.9f || x->p.y > 0.01f)
            continue;
        cssm_receiver rc = {.x = cssm_receiver_point(m, a, x->p, x->n), .n = x->n, .self = -1};
        memcpy(rc.kd, x->albedo, sizeof rc.kd);
        for (int k = 0; k < 8; k++) {
            float out[3];
            cssm_gather(t, a, m, NL, &rc, &o, out, NULL);
            sum += (out[0] + out[1] + out[2]) / 3.0;
            n++;
        }
    }
    return n ? sum / n : 0.0;
}

/* Issue 28: a cluster must send its light from where its light is. On
 * box_light (a 0.3 m area light 5 cm under the ceiling, 2 m room, block)
 * the floor gathers the emission (the direct light of the first bounce)
 * through cuts of at most max_cut = 1, 4, 16 nodes, jittered (§4.5): a
 * node's light sent from a leaf drawn by intensity (hrc.c pick_leaf)
 * keeps the direct light of the leaf-level gather (every texel its own
 * sender and cube map) however coarse the cut; drawn uniformly over the
 * leaves (rep=centroid, the code before) it is sent from anywhere in the
 * cluster (the root: the whole room). Unshadowed and black printed beside
 * it; the cut must be 4 x closer than the better of them. */
int cssm_test_representative(void)
{
    gi_gpu *gpu = NULL;
    gi_scene *s = NULL;
    gi_gpu_scene *gs = NULL;
    if (!cssm_test_load_gpu("tests/data/truth/box_light.gltf", &gpu, &s, &gs))
        return 1;
    gi_error err;
    cssm_atlas a;
    cssm_tree t;
    cssm_maps m;
    if (cssm_atlas_build(s, 0.0f, 32, 0, &a, &err) != GI_OK ||
        cssm_tree_build(&a, &t, &err) != GI_OK) {
        fprintf(stderr, "FAIL: %s\n", err.text);
        return 1;
    }
    uint32_t *order = cssm_traverse(&a, CSSM_SPIRAL);
    if (!order || cssm_maps_build(gs, &a, order, 16, NULL, &m, &err) != GI_OK) {
        fprintf(stderr, "FAIL: %s\n", order ? err.text : "traverse");
        return 1;
    }
    float *E = malloc(3 * a.count * sizeof *E), *NL = malloc(3 * t.count * sizeof *NL);
    for (uint32_t i = 0; i < a.count; i++)
        memcpy(&E[3 * i], a.texels[i].emission, sizeof a.texels[i].emission);
    cssm_tree_pull(&t, &a, E, NL);
    cssm_gather_opts o = {.threshold = 0.1f,
                          .max_cut = 65536,
                          /* the plugin's defaults */ .clamp = 0.02f * a.diameter,
                          .bias = 0.004f * a.diameter};
    cssm_gather_opts leaf = o;
    leaf.threshold = 0.0f;
    double truth = floor_gather(&a, &t, &m, NL, leaf);
    double open = floor_gather(&a, &t, NULL, NL, leaf);
    double e_open = fabs(open / truth - 1);
    CHECK_MSG(truth > 0.0, "the floor gets no light at the leaf level");
    printf("box_light floor, direct light of the area light (atlas 32^2, M = 16): leaf level %.5f, "
           "unshadowed %+.2f %%, black -100 %%\n",
           truth, 100 * (open / truth - 1));
    const uint32_t cuts[3] = {1, 4, 16};
    for (int k = 0; k < 3; k++) {
        cssm_gather_opts ci = o, ca = o;
        ci.max_cut = ca.max_cut = cuts[k];
        ca.rep_centroid = 1;
        double e_int = floor_gather(&a, &t, &m, NL, ci) / truth - 1;
        double e_area = floor_gather(&a, &t, &m, NL, ca) / truth - 1;
        printf("  max_cut %2u: representatives by intensity %+.2f %%, by area (rep=centroid) "
               "%+.2f %%\n",
               cuts[k], 100 * e_int, 100 * e_area);
        CHECK_MSG(fabs(e_int) <= 0.05 && fabs(e_int) <= 0.25 * fmin(1.0, e_open),
                  "max_cut %u: the cut's direct light is off the leaf level by more than 5 %% or "
                  "not 4 x closer than the better trivial answer",
                  cuts[k]);
    }
    free(E), free(NL), free(order);
    cssm_maps_free(&m);
    cssm_tree_free(&t);
    cssm_atlas_free(&a);
    gi_gpu_scene_free(gs);
    gi_gpu_destroy(gpu);
    gi_scene_free(s);
    return 0;
}
