/* The reference path tracer on the Cornell box (scenes/cornell_box.gltf,
 * 32x32): properties that hold without a closed form.
 *  - Estimators: light-only, BSDF-only and MIS direct light (max_bounces
 *    1) are three independent estimates of one image: their means agree
 *    within 3 combined standard errors; so do they with full GI.
 *  - Bounces: the image for B + 1 bounces adds the paths of exactly B + 1
 *    scattering events to the image for B, sharing every path prefix (same
 *    random numbers), so it is >= pixel by pixel and channel by channel,
 *    exactly; the added light shrinks about geometrically (by roughly the
 *    box's albedo) and B = 64 is the unlimited image.
 *  - Determinism: 1 and 3 threads, one pass or several, give the same
 *    bits; the same seed gives the same image; two seeds give images whose
 *    difference is consistent with the variance layer (z-scores ~ N(0, 1)
 *    once divided by the combined standard error).
 *  - A non-finite vertex is refused before Embree sees it. */
#include "check.h"
#include "reference.h"

#include "gi/image.h"

#include <stdlib.h>
#include <string.h>

#ifdef __SANITIZE_ADDRESS__
#define SPP_SCALE 8 /* under AddressSanitizer: fewer samples, same checks */
#else
#define SPP_SCALE 1
#endif

#define W 32
#define H 32
#define NPIX (W * H)

typedef struct render_out {
    gi_image *mean, *var;
    gi_ref_stats stats;
} render_out;

static uint32_t scaled(uint32_t spp)
{
    return spp / SPP_SCALE > 2 ? spp / SPP_SCALE : 2;
}

/* Renders in passes of pass_spp until spp; 0 on failure. */
static int render(const gi_scene *s, int max_bounces, gi_ref_strategy strategy, uint32_t seed,
                  uint32_t threads, uint32_t spp, uint32_t pass_spp, render_out *out)
{
    memset(out, 0, sizeof *out);
    gi_ref_desc d;
    gi_ref_desc_init(&d);
    d.scene = s;
    d.width = W;
    d.height = H;
    d.seed = seed;
    d.max_bounces = max_bounces;
    d.strategy = strategy;
    d.threads = threads;
    gi_ref *r;
    gi_error err;
    if (gi_ref_create(&d, &r, &err) != GI_OK) {
        fprintf(stderr, "gi_ref_create: %s\n", err.text);
        return 0;
    }
    int ok = 1;
    while (ok && gi_ref_spp(r) < spp) {
        uint32_t k =
            (uint32_t)(spp - gi_ref_spp(r)) < pass_spp ? (uint32_t)(spp - gi_ref_spp(r)) : pass_spp;
        ok = gi_ref_render(r, k, &err) == GI_OK;
    }
    out->mean = gi_ref_mean_image(r);
    out->var = gi_ref_variance_image(r);
    gi_ref_get_stats(r, &out->stats);
    gi_ref_free(r);
    return ok && out->mean && out->var;
}

static void release(render_out *o)
{
    gi_image_free(o->mean);
    gi_image_free(o->var);
    memset(o, 0, sizeof *o);
}

/* Image mean of channel c (3 = luminance) and its standard error. */
static void image_mean(const render_out *o, int c, double *mean, double *se)
{
    double m = 0, v = 0;
    for (int i = 0; i < NPIX; i++) {
        const float *p = o->mean->rgba + 4 * i;
        m += c < 3 ? p[c] : 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
        v += o->var->rgba[4 * i + c];
    }
    *mean = m / NPIX;
    *se = sqrt(v) / NPIX;
}

static int same_bits(const render_out *a, const render_out *b)
{
    size_t n = (size_t)NPIX * 4 * sizeof(float);
    return memcmp(a->mean->rgba, b->mean->rgba, n) == 0 &&
           memcmp(a->var->rgba, b->var->rgba, n) == 0;
}

static void test_strategies(const gi_scene *s)
{
    static const gi_ref_strategy st[3] = {GI_REF_STRATEGY_MIS, GI_REF_STRATEGY_LIGHT,
                                          GI_REF_STRATEGY_BSDF};
    /* Direct light (B = 1) and full GI (unlimited). Each strategy has its
     * own seed, so the three estimates are independent. BSDF sampling finds
     * the small light rarely and needs more samples. Much of the standard
     * error comes from pixels on the light's edge (antialiasing), the same
     * for every strategy. */
    static const int bounces[2] = {1, GI_REF_UNLIMITED};
    static const uint32_t spp[2][3] = {{256, 256, 2048}, {128, 128, 1024}};
    for (int b = 0; b < 2; b++) {
        double m[3][4], e[3][4];
        int ok = 1;
        for (int k = 0; k < 3; k++) {
            render_out o;
            ok &= render(s, bounces[b], st[k], 11 + (uint32_t)k, 0, scaled(spp[b][k]), 256, &o);
            if (ok) {
                for (int c = 0; c < 4; c++)
                    image_mean(&o, c, &m[k][c], &e[k][c]);
                CHECK(o.stats.nonfinite == 0);
            }
            release(&o);
            if (ok)
                printf("B=%-2d %-5s luminance %.5f +- %.5f (%.2f%%)\n", bounces[b],
                       gi_ref_strategy_name(st[k]), m[k][3], e[k][3], 100.0 * e[k][3] / m[k][3]);
        }
        CHECK(ok);
        if (!ok)
            continue;
        for (int k = 0; k < 3; k++)
            for (int j = k + 1; j < 3; j++)
                for (int c = 0; c < 4; c++) {
                    /* Luminance (c = 3) within 3 combined standard errors,
                     * each of R, G, B within 4. */
                    double z =
                        fabs(m[k][c] - m[j][c]) / sqrt(e[k][c] * e[k][c] + e[j][c] * e[j][c]);
                    if (c == 3)
                        printf("B=%-2d %s vs %s: %.2f standard errors apart\n", bounces[b],
                               gi_ref_strategy_name(st[k]), gi_ref_strategy_name(st[j]), z);
                    CHECK_MSG(z < (c == 3 ? 3.0 : 4.0),
                              "B=%d channel %d: %s %.5f vs %s %.5f is %.2f standard errors",
                              bounces[b], c, gi_ref_strategy_name(st[k]), m[k][c],
                              gi_ref_strategy_name(st[j]), m[j][c], z);
                }
    }
}

static void test_bounces(const gi_scene *s)
{
    enum { NB = 8 };
    render_out o[NB], unlimited, b64;
    int ok = 1;
    for (int b = 0; b < NB; b++)
        ok &= render(s, b, GI_REF_STRATEGY_MIS, 5, 0, scaled(64), 64, &o[b]);
    ok &= render(s, 64, GI_REF_STRATEGY_MIS, 5, 0, scaled(64), 64, &b64);
    ok &= render(s, GI_REF_UNLIMITED, GI_REF_STRATEGY_MIS, 5, 0, scaled(64), 64, &unlimited);
    CHECK(ok);
    if (ok) {
        double mean[NB], se;
        for (int b = 0; b < NB; b++)
            image_mean(&o[b], 3, &mean[b], &se);
        for (int b = 0; b + 1 < NB; b++) {
            int nested = 1;
            for (int i = 0; i < NPIX * 4; i++)
                nested &= o[b + 1].mean->rgba[i] >= o[b].mean->rgba[i];
            CHECK_MSG(nested, "image(B=%d) is not >= image(B=%d) everywhere", b + 1, b);
            CHECK_MSG(mean[b + 1] > mean[b], "B=%d mean %.5f, B=%d mean %.5f", b, mean[b], b + 1,
                      mean[b + 1]);
        }
        printf("bounce means:");
        for (int b = 0; b < NB; b++)
            printf(" %.5f", mean[b]);
        printf("\nadded per bounce, and ratio to the bounce before:");
        for (int b = 1; b < NB; b++) {
            double d = mean[b] - mean[b - 1], prev = b > 1 ? mean[b - 1] - mean[b - 2] : 0.0;
            printf(" %.5f", d);
            if (b > 1)
                printf(" (%.3f)", d / prev);
            /* The walls reflect 0.05..0.73 per bounce; from the second
             * indirect bounce on the added light shrinks steadily. */
            if (b >= 3)
                CHECK_MSG(d / prev > 0.2 && d / prev < 0.8, "bounce %d adds %.5f after %.5f", b, d,
                          prev);
        }
        printf("\n");
        double m64, mu, e64, eu;
        image_mean(&b64, 3, &m64, &e64);
        image_mean(&unlimited, 3, &mu, &eu);
        printf("B=64 %.6f, unlimited %.6f, B=%d %.6f\n", m64, mu, NB - 1, mean[NB - 1]);
        CHECK_NEAR(m64, mu, 1e-6 * mu);
        CHECK(mu >= mean[NB - 1]);
        /* The bounces past NB - 1 add a geometric tail: with a ratio below
         * 0.75 it is under 3 times what the last bounce added. */
        CHECK_MSG(mu - mean[NB - 1] < 3.0 * (mean[NB - 1] - mean[NB - 2]), "tail %.6f after %.6f",
                  mu - mean[NB - 1], mean[NB - 1] - mean[NB - 2]);
    }
    for (int b = 0; b < NB; b++)
        release(&o[b]);
    release(&b64);
    release(&unlimited);
}

static void test_determinism(const gi_scene *s)
{
    render_out one, three, passes, again, other;
    int ok = render(s, GI_REF_UNLIMITED, GI_REF_STRATEGY_MIS, 3, 1, scaled(64), 64, &one);
    ok &= render(s, GI_REF_UNLIMITED, GI_REF_STRATEGY_MIS, 3, 3, scaled(64), 64, &three);
    ok &= render(s, GI_REF_UNLIMITED, GI_REF_STRATEGY_MIS, 3, 2, scaled(64), 5, &passes);
    ok &= render(s, GI_REF_UNLIMITED, GI_REF_STRATEGY_MIS, 3, 0, scaled(64), 64, &again);
    ok &= render(s, GI_REF_UNLIMITED, GI_REF_STRATEGY_MIS, 4, 0, scaled(64), 64, &other);
    CHECK(ok);
    if (ok) {
        CHECK(one.stats.threads == 1 && three.stats.threads == 3);
        CHECK_MSG(same_bits(&one, &three), "1 and 3 threads differ");
        CHECK_MSG(same_bits(&one, &passes), "one pass and passes of 5 spp differ");
        CHECK_MSG(same_bits(&one, &again), "the same seed gave another image");
        CHECK_MSG(!same_bits(&one, &other), "seeds 3 and 4 gave the same image");
        CHECK(one.stats.rays == three.stats.rays);
        /* z = (a - b) / sqrt(var_a + var_b) per pixel and channel. */
        double zs = 0, zz = 0;
        long n = 0, within = 0;
        for (int i = 0; i < NPIX; i++)
            for (int c = 0; c < 3; c++) {
                double v = (double)one.var->rgba[4 * i + c] + other.var->rgba[4 * i + c];
                if (!(v > 0))
                    continue;
                double z = (one.mean->rgba[4 * i + c] - other.mean->rgba[4 * i + c]) / sqrt(v);
                zs += z;
                zz += z * z;
                within += fabs(z) < 1.959964;
                n++;
            }
        double zm = zs / n, zv = zz / n - zm * zm, frac = (double)within / n;
        printf("seed 3 vs 4: %ld z-scores, mean %.3f, variance %.3f, %.1f%% within 1.96\n", n, zm,
               zv, 100.0 * frac);
        CHECK(n > NPIX * 2);
        CHECK_MSG(fabs(zm) < 0.1, "mean z %.3f", zm);
        CHECK_MSG(zv > 0.8 && zv < 1.25, "z variance %.3f", zv);
        CHECK_MSG(frac > 0.92 && frac < 0.975, "%.3f within 1.96", frac);
    }
    release(&one);
    release(&three);
    release(&passes);
    release(&again);
    release(&other);
}

static void test_rejects(gi_scene *s)
{
    gi_ref_desc d;
    gi_ref_desc_init(&d);
    d.scene = s;
    d.width = 8;
    d.height = 8;
    gi_ref *r = NULL;
    gi_error err;
    d.width = 0;
    CHECK(gi_ref_create(&d, &r, &err) == GI_ERR_INVALID_ARGUMENT && r == NULL);
    d.width = 8;
    d.max_bounces = -2;
    CHECK(gi_ref_create(&d, &r, &err) == GI_ERR_INVALID_ARGUMENT && r == NULL);
    d.max_bounces = GI_REF_UNLIMITED;
    /* A NaN vertex (the loader refuses them in files; a caller's own scene
     * may still carry one) is bad input, never a silently missing triangle. */
    float saved = s->vertices[5].position[1];
    s->vertices[5].position[1] = NAN;
    gi_result res = gi_ref_create(&d, &r, &err);
    CHECK_MSG(res == GI_ERR_INVALID_ARGUMENT && r == NULL, "NaN vertex: %s", err.text);
    CHECK(strstr(err.text, "not finite") != NULL);
    s->vertices[5].position[1] = INFINITY;
    CHECK(gi_ref_create(&d, &r, &err) == GI_ERR_INVALID_ARGUMENT && r == NULL);
    s->vertices[5].position[1] = saved;
    CHECK(gi_ref_create(&d, &r, &err) == GI_OK && r != NULL);
    CHECK(gi_ref_spp(r) == 0 && gi_ref_mean_rel_se(r) == INFINITY);
    CHECK(strncmp(gi_ref_renderer(r), "embree 3.", 9) == 0);
    gi_ref_free(r);
    CHECK(gi_ref_strategy_parse("bsdf") == GI_REF_STRATEGY_BSDF &&
          gi_ref_strategy_parse("nope") == -1);
}

int main(void)
{
    gi_error err;
    gi_scene *s = gi_scene_load(GI_SOURCE_DIR "/scenes/cornell_box.gltf", &err);
    CHECK_MSG(s != NULL, "%s", err.text);
    if (!s)
        return gi_test_finish();
    test_strategies(s);
    test_bounces(s);
    test_determinism(s);
    test_rejects(s);
    gi_scene_free(s);
    return gi_test_finish();
}
