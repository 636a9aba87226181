/* Image-error metrics (harness/metrics/metrics.h) and LDR-FLIP (harness/metrics/flip.h) on
 * tiny synthetic images against values computed by hand. */
#include "check.h"
#include "flip.h"
#include "metrics.h"

#include "gi/cache.h"
#include "gi/tonemap.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static gi_image *constant(uint32_t w, uint32_t h, float r, float g, float b)
{
    gi_image *img = gi_image_create(w, h);
    for (size_t i = 0; i < (size_t)w * h; i++) {
        img->rgba[i * 4 + 0] = r;
        img->rgba[i * 4 + 1] = g;
        img->rgba[i * 4 + 2] = b;
        img->rgba[i * 4 + 3] = 1.0f;
    }
    return img;
}

static void set_px(gi_image *img, uint32_t x, uint32_t y, float r, float g, float b)
{
    float *p = img->rgba + ((size_t)y * img->width + x) * 4;
    p[0] = r;
    p[1] = g;
    p[2] = b;
}

/* A deterministic pattern with structure at several scales. */
static gi_image *pattern(uint32_t w, uint32_t h)
{
    gi_image *img = gi_image_create(w, h);
    uint32_t s = 12345;
    for (uint32_t y = 0; y < h; y++)
        for (uint32_t x = 0; x < w; x++) {
            s = s * 1664525u + 1013904223u;
            float n = (float)(s >> 8) / 16777216.0f;
            float base = ((x / 4 + y / 4) & 1) ? 0.6f : 0.1f;
            set_px(img, x, y, base + 0.2f * n, base * 0.5f + 0.1f * n, 0.3f * n);
        }
    return img;
}

static gi_metrics compute(const gi_image *t, const gi_image *r, float exposure)
{
    gi_metrics_opts o = {0};
    o.exposure = exposure;
    gi_metrics m;
    gi_error err;
    gi_result res = gi_metrics_compute(t, r, &o, &m, &err);
    CHECK_MSG(res == GI_OK, "%s", err.text);
    return m;
}

static void test_single_pixel(void)
{
    /* 2x2 black reference; the test has one white pixel. Per channel the
     * errors are {1, 0, 0, 0}. */
    gi_image *r = constant(2, 2, 0, 0, 0), *t = constant(2, 2, 0, 0, 0);
    set_px(t, 1, 0, 1, 1, 1);
    gi_metrics m = compute(t, r, 0);
    CHECK_NEAR(m.mse, 0.25, 1e-12);
    CHECK_NEAR(m.rmse, 0.5, 1e-12);
    CHECK_NEAR(m.mae, 0.25, 1e-12);
    CHECK_NEAR(m.relmse, 10000.0 / 4.0, 1e-6); /* 1^2 / 0.01^2 on one pixel of four */
    /* Tonemapped values are the same 0 and 1 (to float precision): mse_T =
     * 1/4, PSNR = 10 log10 4. */
    CHECK_NEAR(m.psnr, 10.0 * log10(4.0), 1e-5);
    CHECK_NEAR(m.psnr, 6.0206, 1e-4);
    CHECK(m.pixels == 4 && m.excluded == 0 && m.width == 2 && m.height == 2);
    CHECK_NEAR(m.mean_lum_test, 0.25, 1e-7); /* the weights sum to 1 */
    CHECK_NEAR(m.mean_lum_ref, 0.0, 0.0);
    CHECK(isnan(m.mean_lum_diff_pct)); /* undefined against a black reference */
    CHECK(m.ssim < 1.0 && m.ssim > -1.0);
    CHECK(m.flip > 0.0 && m.flip <= 1.0);

    /* Exposure acts on the tonemapped metrics only: 0.25 at +2 stops is 1. */
    set_px(t, 1, 0, 0.25f, 0.25f, 0.25f);
    m = compute(t, r, 2.0f);
    CHECK_NEAR(m.psnr, 10.0 * log10(4.0), 1e-6);
    CHECK_NEAR(m.rmse, 0.125, 1e-9);
    CHECK_NEAR(m.exposure, 2.0, 0.0);
    gi_image_free(r);
    gi_image_free(t);
}

static void test_constants(void)
{
    /* 4x4 constants: test (0.2, 0.4, 0.6), reference (0.1, 0.2, 0.3). */
    gi_image *t = constant(4, 4, 0.2f, 0.4f, 0.6f), *r = constant(4, 4, 0.1f, 0.2f, 0.3f);
    gi_metrics m = compute(t, r, 0);
    CHECK_NEAR(m.mse, (0.01 + 0.04 + 0.09) / 3.0, 1e-7);
    CHECK_NEAR(m.rmse, 0.2160247, 1e-6);
    CHECK_NEAR(m.mae, (0.1 + 0.2 + 0.3) / 3.0, 1e-7);
    CHECK_NEAR(m.relmse, (0.01 / (0.11 * 0.11) + 0.04 / (0.21 * 0.21) + 0.09 / (0.31 * 0.31)) / 3.0,
               1e-6);
    CHECK_NEAR(m.relmse, 0.889999, 1e-5);
    /* Y = 0.2126 R + 0.7152 G + 0.0722 B: 0.37192 and 0.18596; the test is
     * 100 % brighter. */
    CHECK_NEAR(m.mean_lum_test, 0.37192, 1e-6);
    CHECK_NEAR(m.mean_lum_ref, 0.18596, 1e-6);
    CHECK_NEAR(m.mean_lum_diff_pct, 100.0, 1e-4);
    gi_image_free(t);
    gi_image_free(r);

    /* Greys 0.25 against 0.5: -50 %; constant images leave SSIM's luminance
     * term (2 mx my + C1) / (mx^2 + my^2 + C1) with mx, my the sRGB values
     * 0.537099 and 0.735357 (1.055 v^(1/2.4) - 0.055). */
    t = constant(4, 4, 0.25f, 0.25f, 0.25f);
    r = constant(4, 4, 0.5f, 0.5f, 0.5f);
    m = compute(t, r, 0);
    CHECK_NEAR(m.mean_lum_diff_pct, -50.0, 1e-4);
    CHECK_NEAR(m.rmse, 0.25, 1e-7);
    CHECK_NEAR(m.relmse, 0.0625 / (0.51 * 0.51), 1e-7);
    const double mx = 0.537099, my = 0.735357, c1 = 1e-4;
    CHECK_NEAR(gi_tonemap(0.25f, 0), mx, 1e-6);
    CHECK_NEAR(gi_tonemap(0.5f, 0), my, 1e-6);
    CHECK_NEAR(m.ssim, (2 * mx * my + c1) / (mx * mx + my * my + c1), 2e-6);
    CHECK_NEAR(m.ssim, 0.952607, 1e-5);
    double dt = my - mx;
    CHECK_NEAR(m.psnr, 10.0 * log10(1.0 / (dt * dt)), 1e-4);
    gi_image_free(t);
    gi_image_free(r);
}

static void test_identical(void)
{
    gi_image *a = pattern(40, 24), *b = pattern(40, 24);
    gi_metrics m = compute(a, b, 0);
    CHECK(m.mse == 0.0 && m.rmse == 0.0 && m.relmse == 0.0 && m.mae == 0.0);
    CHECK(isinf(m.psnr) && m.psnr > 0);
    CHECK(m.ssim == 1.0);
    CHECK(m.flip == 0.0);
    CHECK(m.mean_lum_diff_pct == 0.0);
    /* and the metrics see a difference when there is one */
    set_px(b, 20, 12, 0.9f, 0.9f, 0.9f);
    m = compute(a, b, 0);
    CHECK(m.rmse > 0.0 && m.ssim < 1.0 && m.flip > 0.0 && isfinite(m.psnr));
    gi_image_free(a);
    gi_image_free(b);
}

static void test_nonfinite(void)
{
    /* 2x2: test NaN at pixel 0, reference +Inf at pixel 1, the other two
     * pixels 0.3 against 0.2. */
    gi_image *t = constant(2, 2, 0.3f, 0.3f, 0.3f), *r = constant(2, 2, 0.2f, 0.2f, 0.2f);
    set_px(t, 0, 0, NAN, 0.3f, 0.3f);
    set_px(r, 1, 0, 0.2f, INFINITY, 0.2f);
    gi_metrics m = compute(t, r, 0);
    CHECK(m.nonfinite_test == 1 && m.nonfinite_ref == 1);
    CHECK(m.excluded == 2 && m.pixels == 2);
    CHECK_NEAR(m.rmse, 0.1, 1e-7);
    CHECK_NEAR(m.mae, 0.1, 1e-7);
    CHECK_NEAR(m.relmse, 0.01 / (0.21 * 0.21), 1e-6);
    CHECK_NEAR(m.mean_lum_diff_pct, 50.0, 1e-4);
    CHECK(isfinite(m.psnr) && isfinite(m.ssim) && isfinite(m.flip));
    float map[4];
    gi_error err;
    CHECK(gi_metrics_relerr_map(t, r, map, &err) == GI_OK);
    CHECK(isnan(map[0]) && isnan(map[1]));
    CHECK_NEAR(map[2], 0.1 / 0.21, 1e-6);
    double mean = 0;
    CHECK(gi_metrics_flip_map(t, r, NULL, map, &mean, &err) == GI_OK);
    CHECK(isnan(map[0]) && isnan(map[1]) && isfinite(map[2]) && isfinite(map[3]));
    CHECK_NEAR(mean, 0.5 * (map[2] + map[3]), 1e-6);

    /* An excluded pixel carries no difference into its neighbours: a NaN in
     * an otherwise identical pair leaves every metric at "no error". */
    gi_image *a = pattern(16, 16), *b = pattern(16, 16);
    set_px(a, 8, 8, NAN, NAN, NAN);
    m = compute(a, b, 0);
    CHECK(m.excluded == 1 && m.pixels == 255);
    CHECK(m.rmse == 0.0 && m.ssim == 1.0 && m.flip == 0.0);
    gi_image_free(a);
    gi_image_free(b);

    /* Nothing left to compare: every metric NaN, no error. */
    set_px(t, 0, 1, INFINITY, 0, 0);
    set_px(t, 1, 1, 0, -INFINITY, 0);
    m = compute(t, r, 0);
    CHECK(m.pixels == 0 && m.excluded == 4 && m.nonfinite_test == 3);
    CHECK(isnan(m.rmse) && isnan(m.relmse) && isnan(m.mae) && isnan(m.psnr) && isnan(m.ssim) &&
          isnan(m.flip));
    gi_image_free(t);
    gi_image_free(r);
}

static void test_errors(void)
{
    gi_image *a = constant(4, 4, 0, 0, 0), *b = constant(4, 2, 0, 0, 0);
    gi_metrics m;
    gi_error err;
    err.text[0] = '\0';
    CHECK(gi_metrics_compute(a, b, NULL, &m, &err) == GI_ERR_INVALID_ARGUMENT);
    CHECK_MSG(strstr(err.text, "image sizes differ: test 4x4, reference 4x2") != NULL, "%s",
              err.text);
    float map[16];
    CHECK(gi_metrics_relerr_map(a, b, map, &err) == GI_ERR_INVALID_ARGUMENT);
    CHECK(gi_metrics_flip_map(a, b, NULL, map, NULL, &err) == GI_ERR_INVALID_ARGUMENT);
    gi_metrics_opts o = {0};
    o.flip_ppd = -3.0f;
    CHECK(gi_metrics_compute(a, a, &o, &m, &err) == GI_ERR_INVALID_ARGUMENT);
    o.flip_ppd = 0.0f;
    o.exposure = NAN;
    CHECK(gi_metrics_compute(a, a, &o, &m, &err) == GI_ERR_INVALID_ARGUMENT);
    o.exposure = 0.0f;
    o.skip_flip = 1;
    CHECK(gi_metrics_compute(a, a, &o, &m, &err) == GI_OK && isnan(m.flip) && m.ssim == 1.0);
    gi_image_free(a);
    gi_image_free(b);
}

static void test_ssim_plane(void)
{
    /* Constant planes through the plane function: the luminance term. */
    double x[36], y[36];
    for (int i = 0; i < 36; i++) {
        x[i] = 0.2;
        y[i] = 0.6;
    }
    double s;
    gi_error err;
    CHECK(gi_metrics_ssim_plane(x, y, NULL, 6, 6, &s, &err) == GI_OK);
    CHECK_NEAR(s, (2 * 0.2 * 0.6 + 1e-4) / (0.04 + 0.36 + 1e-4), 1e-9);
    /* Contrast reversed (y = 1 - x on a zero-mean-about-0.5 checkerboard):
     * SSIM is negative. */
    for (int i = 0; i < 36; i++) {
        x[i] = ((i % 6 + i / 6) & 1) ? 0.8 : 0.2;
        y[i] = 1.0 - x[i];
    }
    CHECK(gi_metrics_ssim_plane(x, y, NULL, 6, 6, &s, &err) == GI_OK);
    CHECK_MSG(s < -0.5, "%g", s);
}

/* ---- FLIP ---- */

static void test_flip_colour(void)
{
    /* CIELAB of the sRGB primaries (published: green 87.73, -86.18, 83.18;
     * blue 32.30, 79.19, -107.86). */
    const double green[3] = {0, 1, 0}, blue[3] = {0, 0, 1}, white[3] = {1, 1, 1};
    double xyz[3], lab[3], hg[3], hb[3];
    gi_flip_linrgb_to_xyz(green, xyz);
    gi_flip_xyz_to_lab(xyz, lab);
    CHECK_NEAR(lab[0], 87.73, 0.01);
    CHECK_NEAR(lab[1], -86.18, 0.01);
    CHECK_NEAR(lab[2], 83.18, 0.01);
    gi_flip_linrgb_to_xyz(blue, xyz);
    gi_flip_xyz_to_lab(xyz, lab);
    CHECK_NEAR(lab[0], 32.30, 0.01);
    CHECK_NEAR(lab[1], 79.19, 0.01);
    CHECK_NEAR(lab[2], -107.86, 0.01);
    gi_flip_linrgb_to_xyz(white, xyz);
    gi_flip_xyz_to_lab(xyz, lab);
    CHECK_NEAR(lab[0], 100.0, 1e-9);
    CHECK_NEAR(lab[1], 0.0, 1e-9);
    CHECK_NEAR(lab[2], 0.0, 1e-9);
    /* YCxCz round trip */
    double opp[3], back[3];
    gi_flip_linrgb_to_xyz(green, xyz);
    gi_flip_xyz_to_ycxcz(xyz, opp);
    gi_flip_ycxcz_to_xyz(opp, back);
    gi_flip_xyz_to_linrgb(back, lab);
    CHECK_NEAR(lab[0], 0.0, 1e-6);
    CHECK_NEAR(lab[1], 1.0, 1e-6);
    CHECK_NEAR(lab[2], 0.0, 1e-6);

    /* Hunt adjustment scales a, b by L/100: green (87.73, -75.61, 72.98),
     * blue (32.30, 25.58, -34.84). HyAB = |87.73 - 32.30| +
     * sqrt(101.19^2 + 107.82^2) = 55.43 + 147.87 = 203.30. */
    gi_flip_linrgb_to_hunt_lab(green, hg);
    gi_flip_linrgb_to_hunt_lab(blue, hb);
    CHECK_NEAR(hg[1], -75.61, 0.01);
    CHECK_NEAR(hb[2], -34.84, 0.01);
    CHECK_NEAR(gi_flip_hyab(hg, hb), 203.30, 0.02);
    CHECK_NEAR(gi_flip_hyab(hb, hg), gi_flip_hyab(hg, hb), 1e-12);
    CHECK_NEAR(gi_flip_cmax(), pow(203.30, 0.7), 0.01); /* 41.275 */

    /* Compression: pc cmax maps to pt, cmax to 1, 0 to 0, continuous. */
    double cmax = gi_flip_cmax();
    CHECK_NEAR(gi_flip_compress(0.0, cmax), 0.0, 0.0);
    CHECK_NEAR(gi_flip_compress(0.4 * cmax, cmax), 0.95, 1e-12);
    CHECK_NEAR(gi_flip_compress(0.4 * cmax - 1e-9, cmax), 0.95, 1e-8);
    CHECK_NEAR(gi_flip_compress(cmax, cmax), 1.0, 1e-12);
    CHECK_NEAR(gi_flip_compress(0.2 * cmax, cmax), 0.475, 1e-12);
}

static void test_flip_kernels(void)
{
    const double ppd = GI_FLIP_PPD_DEFAULT;
    /* Radii at 67 ppd: colour ceil(3 sqrt(0.04 / (2 pi^2)) 67.02) = ceil(9.05) = 10;
     * features sd = 0.5 * 0.082 * 67.02 = 2.748, ceil(3 sd) = 9. */
    CHECK(gi_flip_csf_radius(ppd) == 10);
    CHECK(gi_flip_feature_radius(ppd) == 9);
    int r = gi_flip_csf_radius(ppd), n = 2 * r + 1;
    double *k = malloc((size_t)n * n * sizeof *k);
    for (int c = 0; c < 3; c++) {
        gi_flip_csf_kernel(ppd, c, k);
        /* Against the paper's formula S(x) = a1 sqrt(pi/b1) exp(-pi^2 x^2/b1)
         * + a2 sqrt(pi/b2) exp(-pi^2 x^2/b2), normalised over the grid. */
        const gi_flip_csf *p = &gi_flip_csf_params[c];
        double total = 0, sum = 0;
        for (int y = -r; y <= r; y++)
            for (int x = -r; x <= r; x++) {
                double d2 = (x * x + y * y) / (ppd * ppd);
                total += p->a1 * sqrt(M_PI / p->b1) * exp(-M_PI * M_PI * d2 / p->b1) +
                         p->a2 * sqrt(M_PI / p->b2) * exp(-M_PI * M_PI * d2 / p->b2);
            }
        int offs[4][2] = {{0, 0}, {1, 0}, {3, 2}, {10, 10}};
        for (int i = 0; i < 4; i++) {
            int x = offs[i][0], y = offs[i][1];
            double d2 = (x * x + y * y) / (ppd * ppd);
            double s = p->a1 * sqrt(M_PI / p->b1) * exp(-M_PI * M_PI * d2 / p->b1) +
                       p->a2 * sqrt(M_PI / p->b2) * exp(-M_PI * M_PI * d2 / p->b2);
            CHECK_NEAR(k[(y + r) * n + (x + r)], s / total, 1e-12);
        }
        for (int i = 0; i < n * n; i++)
            sum += k[i];
        CHECK_NEAR(sum, 1.0, 1e-12);
    }
    free(k);
    /* The achromatic kernel is narrower than the blue-yellow one: a bigger
     * share of its weight sits at the centre. */
    double ka[21 * 21], kb[21 * 21];
    gi_flip_csf_kernel(ppd, 0, ka);
    gi_flip_csf_kernel(ppd, 2, kb);
    CHECK(ka[10 * 21 + 10] > kb[10 * 21 + 10]);

    int fr = gi_flip_feature_radius(ppd), fn = 2 * fr + 1;
    double edge[64], point[64], gauss[64];
    gi_flip_feature_kernels(ppd, edge, point, gauss);
    double ep = 0, en = 0, pp = 0, pn = 0, gs = 0;
    for (int i = 0; i < fn; i++) {
        ep += edge[i] > 0 ? edge[i] : 0;
        en += edge[i] < 0 ? edge[i] : 0;
        pp += point[i] > 0 ? point[i] : 0;
        pn += point[i] < 0 ? point[i] : 0;
        gs += gauss[i];
    }
    /* 2-D positive weights sum to 1 and negative ones to -1: x factor times
     * a y factor of sum 1. */
    CHECK_NEAR(gs, 1.0, 1e-12);
    CHECK_NEAR(ep, 1.0, 1e-12);
    CHECK_NEAR(en, -1.0, 1e-12);
    CHECK_NEAR(pp, 1.0, 1e-12);
    CHECK_NEAR(pn, -1.0, 1e-12);
    CHECK(edge[fr] == 0.0 && edge[0] > 0 && edge[fn - 1] < 0); /* -x g(x) */
    CHECK(point[fr] < 0 && point[0] > 0);                      /* (x^2/sd^2 - 1) g(x) */
}

static double flip_of(const gi_image *t, const gi_image *r)
{
    gi_metrics_opts o = {0};
    size_t n = (size_t)t->width * t->height;
    float *map = malloc(n * sizeof *map);
    double mean = NAN;
    gi_error err;
    CHECK_MSG(gi_metrics_flip_map(t, r, &o, map, &mean, &err) == GI_OK, "%s", err.text);
    free(map);
    return mean;
}

static void test_flip_values(void)
{
    /* Black against white, constant: no features, the spatial filters keep
     * constants, HyAB = |100 - 0| = 100, FLIP = compress(100^0.7)
     * = 0.95 + (25.119 - 16.510) / (41.275 - 16.510) * 0.05 = 0.9674. */
    gi_image *black = constant(8, 8, 0, 0, 0), *white = constant(8, 8, 1, 1, 1);
    double f = flip_of(black, white);
    double e = pow(100.0, 0.7), cmax = pow(203.2973, 0.7);
    CHECK_NEAR(f, 0.95 + (e - 0.4 * cmax) / (0.6 * cmax) * 0.05, 1e-5);
    CHECK_NEAR(f, 0.9674, 1e-4);
    CHECK_NEAR(flip_of(white, black), f, 1e-6);
    gi_image_free(black);
    gi_image_free(white);

    /* Greys 0.25 and 0.5: L* = 116 cbrt(Y) - 16 = 57.0755 and 76.0693;
     * HyAB 18.9938, ^0.7 = 7.8524, below pc cmax: 0.95 / (0.4 cmax) 7.8524 = 0.4518. */
    gi_image *g1 = constant(8, 8, 0.25f, 0.25f, 0.25f), *g2 = constant(8, 8, 0.5f, 0.5f, 0.5f);
    double dl = (116.0 * cbrt(0.5) - 16.0) - (116.0 * cbrt(0.25) - 16.0);
    CHECK_NEAR(dl, 18.9938, 1e-4);
    CHECK_NEAR(flip_of(g1, g2), 0.95 / (0.4 * cmax) * pow(dl, 0.7), 1e-5);
    CHECK_NEAR(flip_of(g1, g2), 0.4518, 1e-4);
    gi_image_free(g1);
    gi_image_free(g2);

    /* Monotonic in the size of a perturbation: a 4x4 patch brightened by d
     * in a 24x24 grey image. */
    double last = 0.0;
    const float ds[] = {0.01f, 0.03f, 0.1f, 0.2f, 0.4f};
    gi_image *ref = constant(24, 24, 0.3f, 0.3f, 0.3f);
    for (size_t k = 0; k < sizeof ds / sizeof ds[0]; k++) {
        gi_image *t = constant(24, 24, 0.3f, 0.3f, 0.3f);
        for (uint32_t y = 10; y < 14; y++)
            for (uint32_t x = 10; x < 14; x++)
                set_px(t, x, y, 0.3f + ds[k], 0.3f + ds[k], 0.3f + ds[k]);
        double v = flip_of(t, ref);
        CHECK_MSG(v > last, "d = %g: FLIP %g after %g", (double)ds[k], v, last);
        last = v;
        gi_image_free(t);
    }
    /* ... and in its extent */
    last = 0.0;
    for (uint32_t size = 1; size <= 8; size *= 2) {
        gi_image *t = constant(24, 24, 0.3f, 0.3f, 0.3f);
        for (uint32_t y = 0; y < size; y++)
            for (uint32_t x = 0; x < size; x++)
                set_px(t, 8 + x, 8 + y, 0.6f, 0.6f, 0.6f);
        double v = flip_of(t, ref);
        CHECK_MSG(v > last, "size %u: FLIP %g after %g", size, v, last);
        last = v;
        gi_image_free(t);
    }

    /* A firefly: one bright pixel on grey is the worst pixel of the map,
     * and the feature pipeline raises it above its colour error alone. */
    gi_image *t = constant(24, 24, 0.3f, 0.3f, 0.3f);
    set_px(t, 12, 12, 1.0f, 1.0f, 1.0f);
    float map[24 * 24];
    gi_error err;
    CHECK(gi_metrics_flip_map(t, ref, NULL, map, NULL, &err) == GI_OK);
    int worst = 0;
    for (int i = 1; i < 24 * 24; i++)
        if (map[i] > map[worst])
            worst = i;
    CHECK(worst == 12 * 24 + 12);
    CHECK(map[0] >= 0.0f && map[0] < 1e-6f); /* far from the firefly: no difference */
    for (int i = 0; i < 24 * 24; i++)
        CHECK(map[i] >= 0.0f && map[i] <= 1.0f);
    gi_image_free(t);
    gi_image_free(ref);

    /* Seen from farther away (more pixels per degree) the filters are wider
     * in pixels: a one-pixel checkerboard blurs towards its mean grey and
     * its difference fades. */
    gi_image *a = constant(32, 32, 0.5f, 0.5f, 0.5f), *b = constant(32, 32, 0.5f, 0.5f, 0.5f);
    for (uint32_t y = 0; y < 32; y++)
        for (uint32_t x = 0; x < 32; x++)
            if ((x + y) & 1)
                set_px(b, x, y, 0.2f, 0.2f, 0.2f);
            else
                set_px(b, x, y, 0.8f, 0.8f, 0.8f);
    float m32[32 * 32];
    double near_ppd, far_ppd;
    gi_metrics_opts o = {0};
    o.flip_ppd = 10.0f;
    CHECK(gi_metrics_flip_map(b, a, &o, m32, &near_ppd, &err) == GI_OK);
    o.flip_ppd = 120.0f;
    CHECK(gi_metrics_flip_map(b, a, &o, m32, &far_ppd, &err) == GI_OK);
    CHECK_MSG(far_ppd < near_ppd, "ppd 120: %g, ppd 10: %g", far_ppd, near_ppd);
    gi_image_free(a);
    gi_image_free(b);
}

/* A direct transcription of the paper for comparison: full 2-D kernels from
 * its formulas (no separation), correlated with clamped borders. */
static double clamp01(double v)
{
    return v < 0 ? 0 : v > 1 ? 1 : v;
}

static void conv2d(const double *in, double *out, int w, int h, const double *k, int r)
{
    int n = 2 * r + 1;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double acc = 0;
            for (int j = -r; j <= r; j++)
                for (int i = -r; i <= r; i++) {
                    int xx = x + i < 0 ? 0 : x + i >= w ? w - 1 : x + i;
                    int yy = y + j < 0 ? 0 : y + j >= h ? h - 1 : y + j;
                    acc += k[(j + r) * n + (i + r)] * in[yy * w + xx];
                }
            out[y * w + x] = acc;
        }
}

static void brute_prepare(const float *srgb, int w, int h, double ppd, double *hlab[3],
                          double *edge, double *point)
{
    int np = w * h;
    double *opp[3], *yn = malloc(np * sizeof(double)), *t1 = malloc(np * sizeof(double)),
                    *t2 = malloc(np * sizeof(double));
    for (int c = 0; c < 3; c++)
        opp[c] = malloc(np * sizeof(double));
    for (int i = 0; i < np; i++) {
        double rgb[3], xyz[3], o[3];
        for (int c = 0; c < 3; c++)
            rgb[c] = gi_srgb_decode(srgb[i * 3 + c]);
        gi_flip_linrgb_to_xyz(rgb, xyz);
        gi_flip_xyz_to_ycxcz(xyz, o);
        for (int c = 0; c < 3; c++)
            opp[c][i] = o[c];
        yn[i] = (o[0] + 16.0) / 116.0;
    }
    /* CSF kernels straight from S(x) */
    int r = gi_flip_csf_radius(ppd), n = 2 * r + 1;
    double *k = malloc((size_t)n * n * sizeof *k);
    for (int c = 0; c < 3; c++) {
        const gi_flip_csf *p = &gi_flip_csf_params[c];
        double total = 0;
        for (int y = -r; y <= r; y++)
            for (int x = -r; x <= r; x++) {
                double d2 = (x * x + y * y) / (ppd * ppd);
                double v = p->a1 * sqrt(M_PI / p->b1) * exp(-M_PI * M_PI * d2 / p->b1) +
                           p->a2 * sqrt(M_PI / p->b2) * exp(-M_PI * M_PI * d2 / p->b2);
                k[(y + r) * n + (x + r)] = v;
                total += v;
            }
        for (int i = 0; i < n * n; i++)
            k[i] /= total;
        conv2d(opp[c], hlab[c], w, h, k, r);
    }
    free(k);
    for (int i = 0; i < np; i++) {
        double o[3] = {hlab[0][i], hlab[1][i], hlab[2][i]}, xyz[3], rgb[3], hl[3];
        gi_flip_ycxcz_to_xyz(o, xyz);
        gi_flip_xyz_to_linrgb(xyz, rgb);
        for (int c = 0; c < 3; c++)
            rgb[c] = clamp01(rgb[c]);
        gi_flip_linrgb_to_hunt_lab(rgb, hl);
        for (int c = 0; c < 3; c++)
            hlab[c][i] = hl[c];
    }
    /* feature kernels: 2-D derivatives of a Gaussian, +/- sums normalised */
    double sd = 0.5 * 0.082 * ppd;
    int fr = (int)ceil(3 * sd), fn = 2 * fr + 1;
    double *ke = malloc((size_t)fn * fn * sizeof *ke), *kp = malloc((size_t)fn * fn * sizeof *kp),
           *kt = malloc((size_t)fn * fn * sizeof *kt);
    double ep = 0, en = 0, pp = 0, pn = 0;
    for (int y = -fr; y <= fr; y++)
        for (int x = -fr; x <= fr; x++) {
            double g = exp(-(x * x + y * y) / (2 * sd * sd));
            double e = -x * g, p = (x * x / (sd * sd) - 1) * g;
            ke[(y + fr) * fn + x + fr] = e;
            kp[(y + fr) * fn + x + fr] = p;
            if (e > 0)
                ep += e;
            else
                en -= e;
            if (p > 0)
                pp += p;
            else
                pn -= p;
        }
    for (int i = 0; i < fn * fn; i++) {
        ke[i] /= ke[i] > 0 ? ep : en;
        kp[i] /= kp[i] > 0 ? pp : pn;
    }
    double *kk[2] = {ke, kp}, *res[2] = {edge, point};
    for (int f = 0; f < 2; f++) {
        for (int y = 0; y < fn; y++)
            for (int x = 0; x < fn; x++)
                kt[y * fn + x] = kk[f][x * fn + y]; /* transposed: the y detector */
        conv2d(yn, t1, w, h, kk[f], fr);
        conv2d(yn, t2, w, h, kt, fr);
        for (int i = 0; i < np; i++)
            res[f][i] = sqrt(t1[i] * t1[i] + t2[i] * t2[i]);
    }
    free(ke);
    free(kp);
    free(kt);
    for (int c = 0; c < 3; c++)
        free(opp[c]);
    free(yn);
    free(t1);
    free(t2);
}

static void brute_flip(const float *ts, const float *rs, int w, int h, double ppd, float *out)
{
    int np = w * h;
    double *ht[3], *hr[3], *et = malloc(np * sizeof(double)), *pt = malloc(np * sizeof(double)),
                           *er = malloc(np * sizeof(double)), *pr = malloc(np * sizeof(double));
    for (int c = 0; c < 3; c++) {
        ht[c] = malloc(np * sizeof(double));
        hr[c] = malloc(np * sizeof(double));
    }
    brute_prepare(ts, w, h, ppd, ht, et, pt);
    brute_prepare(rs, w, h, ppd, hr, er, pr);
    double cmax = pow(203.2973, 0.7);
    for (int i = 0; i < np; i++) {
        double a[3] = {ht[0][i], ht[1][i], ht[2][i]}, b[3] = {hr[0][i], hr[1][i], hr[2][i]};
        double hy =
            fabs(a[0] - b[0]) + sqrt((a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
        double e = pow(hy, 0.7), dc;
        if (e < 0.4 * cmax)
            dc = 0.95 / (0.4 * cmax) * e;
        else
            dc = 0.95 + (e - 0.4 * cmax) / (cmax - 0.4 * cmax) * 0.05;
        double df = pow(fmax(fabs(er[i] - et[i]), fabs(pr[i] - pt[i])) / sqrt(2.0), 0.5);
        out[i] = (float)pow(dc, 1.0 - df);
    }
    for (int c = 0; c < 3; c++) {
        free(ht[c]);
        free(hr[c]);
    }
    free(et);
    free(pt);
    free(er);
    free(pr);
}

static void test_flip_against_direct(void)
{
    /* Random colours with edges, non-square so that x and y cannot be
     * confused, at a low and the default ppd. */
    const int w = 23, h = 17;
    float *ts = malloc(w * h * 3 * sizeof *ts), *rs = malloc(w * h * 3 * sizeof *rs);
    float *fast = malloc(w * h * sizeof *fast), *slow = malloc(w * h * sizeof *slow);
    uint32_t s = 777;
    for (int i = 0; i < w * h * 3; i++) {
        s = s * 1664525u + 1013904223u;
        float n = (float)(s >> 8) / 16777216.0f;
        int x = (i / 3) % w, y = (i / 3) / w;
        rs[i] = (x < 11 ? 0.2f : 0.7f) + 0.1f * (float)((i % 3) == (y % 3));
        ts[i] = rs[i] + (n - 0.5f) * 0.3f; /* outside [0, 1] now and then: clamped */
    }
    const double ppds[2] = {20.0, GI_FLIP_PPD_DEFAULT};
    for (int k = 0; k < 2; k++) {
        gi_error err;
        CHECK_MSG(gi_flip_map(ts, rs, w, h, ppds[k], fast, &err) == GI_OK, "%s", err.text);
        for (int i = 0; i < w * h * 3; i++) { /* the direct version does not clamp its input */
            ts[i] = ts[i] < 0 ? 0 : ts[i] > 1 ? 1 : ts[i];
        }
        brute_flip(ts, rs, w, h, ppds[k], slow);
        double worst = 0, mean = 0;
        for (int i = 0; i < w * h; i++) {
            worst = fmax(worst, fabs((double)fast[i] - slow[i]));
            mean += slow[i];
        }
        CHECK_MSG(worst < 1e-5, "ppd %g: separable and direct FLIP differ by %g", ppds[k], worst);
        CHECK(mean / (w * h) > 0.05); /* there is something to see */
    }
    free(ts);
    free(rs);
    free(fast);
    free(slow);
}

/* Leaked energy: a reference half lit (grey 1) and half dark (0 and a faint
 * 0.005, below 1 % of its mean 0.5); the test puts 0.2 into the dark half.
 * Known answers, then the trivial images: the reference itself leaks only
 * its own faint light, a black image nothing, an always-lit one the most. */
static void test_leaked_energy(void)
{
    const uint32_t w = 8, h = 4;
    gi_image *ref = gi_image_create(w, h), *t = gi_image_create(w, h),
             *black = gi_image_create(w, h), *lit = gi_image_create(w, h);
    for (uint32_t y = 0; y < h; y++)
        for (uint32_t x = 0; x < w; x++) {
            int dark = x >= w / 2;
            float r = dark ? (x == w - 1 ? 0.005f : 0.0f) : 1.0f;
            set_px(ref, x, y, r, r, r);
            set_px(t, x, y, dark ? 0.2f : 1.0f, dark ? 0.2f : 1.0f, dark ? 0.2f : 1.0f);
            set_px(black, x, y, 0, 0, 0);
            set_px(lit, x, y, 1, 1, 1);
        }
    /* reference: 16 pixels of 1, 4 of 0.005, 12 of 0; total 16.02, mean 0.500625 */
    double total = 16.0 + 4 * 0.005;
    gi_metrics m = compute(t, ref, 0);
    CHECK_NEAR(m.dark_fraction, 0.5, 1e-12);
    CHECK_NEAR(m.leaked_energy, 16 * 0.2 / total, 1e-6);
    CHECK_NEAR(m.dark_energy_ref, 4 * 0.005 / total, 1e-6);
    CHECK_NEAR(m.dark_threshold, 0.01, 1e-7);
    gi_metrics self = compute(ref, ref, 0), none = compute(black, ref, 0),
               all = compute(lit, ref, 0);
    CHECK_NEAR(self.leaked_energy, self.dark_energy_ref, 1e-12);
    CHECK(none.leaked_energy == 0.0);
    CHECK_NEAR(all.leaked_energy, 16.0 / total, 1e-6);
    CHECK(m.leaked_energy > 10 * self.leaked_energy && m.leaked_energy < all.leaked_energy);
    /* a threshold of 0.5 x mean takes the faint pixels in, and no lit one */
    gi_metrics_opts o = {0};
    o.dark_threshold = 0.5f;
    gi_error err;
    CHECK(gi_metrics_compute(t, ref, &o, &m, &err) == GI_OK);
    CHECK_NEAR(m.dark_fraction, 0.5, 1e-12);
    o.dark_threshold = 2.0f;
    CHECK(gi_metrics_compute(t, ref, &o, &m, &err) == GI_ERR_INVALID_ARGUMENT);
    /* a negative test value is no energy; a black reference has no leak */
    set_px(t, w - 2, 0, -5.0f, -5.0f, -5.0f);
    m = compute(t, ref, 0);
    CHECK_NEAR(m.leaked_energy, 15 * 0.2 / total, 1e-6);
    m = compute(t, black, 0);
    CHECK(isnan(m.leaked_energy));
    gi_image_free(ref);
    gi_image_free(t);
    gi_image_free(black);
    gi_image_free(lit);
}

/* A PFM of tests/data/flip/ ("PF", little-endian, rows bottom first, as
 * make_flip_data.py writes it), read here so that the test needs no image
 * module; NULL when it is not one. */
static gi_image *read_pfm(const char *path)
{
    FILE *f = fopen(path, "rb");
    unsigned w = 0, h = 0;
    float scale = 0.0f;
    gi_image *img = NULL;
    if (f && fscanf(f, "PF %u %u %f", &w, &h, &scale) == 3 && scale < 0.0f && fgetc(f) == '\n' &&
        w > 0 && h > 0 && w <= 4096 && h <= 4096 && (img = gi_image_create(w, h)) != NULL) {
        for (unsigned y = 0; y < h; y++)
            for (unsigned x = 0; x < w; x++) {
                float *p = img->rgba + ((size_t)(h - 1 - y) * w + x) * 4;
                if (fread(p, sizeof(float), 3, f) != 3) {
                    gi_image_free(img);
                    img = NULL;
                    y = h;
                    break;
                }
                p[3] = 1.0f;
            }
    }
    if (f)
        fclose(f);
    return img;
}

/* The mean of pair `name` in section `section` ("ldr"/"hdr") of
 * tests/data/flip/reference.json, NaN when absent. */
static double nvidia_mean(const char *json, const char *section, const char *name)
{
    char key[64];
    snprintf(key, sizeof key, "\"%s\": {", section);
    const char *p = strstr(json, key);
    snprintf(key, sizeof key, "\"%s\": {", name);
    p = p ? strstr(p, key) : NULL;
    p = p ? strstr(p, "\"mean\": ") : NULL;
    return p ? strtod(p + 8, NULL) : NAN;
}

/* LDR-FLIP against NVIDIA's own implementation (FLIP v1.6, its C++ tool;
 * tests/data/flip/PROVENANCE.md): the mean of three 32x32 pairs (a noisy
 * gradient, shifted edges, dark noise) within 5e-5 (the tool prints six
 * decimals), and the per-pixel map of the edge pair within 0.004 (the
 * tool's map is an 8-bit PNG: half a step is 0.002). */
static void test_flip_nvidia(void)
{
    size_t n = 0;
    char *json = gi_file_read_all(GI_TEST_DATA "/flip/reference.json", &n);
    CHECK_MSG(json != NULL, "tests/data/flip/reference.json not readable");
    if (!json)
        return;
    const char *pairs[] = {"noise", "edges", "dark"};
    for (int k = 0; k < 3; k++) {
        char path[1024];
        gi_error err;
        snprintf(path, sizeof path, GI_TEST_DATA "/flip/%s_ref.pfm", pairs[k]);
        gi_image *ref = read_pfm(path);
        snprintf(path, sizeof path, GI_TEST_DATA "/flip/%s_test.pfm", pairs[k]);
        gi_image *test = read_pfm(path);
        CHECK_MSG(ref && test, "%s: the pair's PFMs are not readable", pairs[k]);
        double want = nvidia_mean(json, "ldr", pairs[k]), mean = NAN;
        CHECK_MSG(isfinite(want), "%s: no mean in reference.json", pairs[k]);
        float *map = ref ? malloc((size_t)ref->width * ref->height * sizeof *map) : NULL;
        gi_metrics_opts o = {0};
        if (ref && test && map)
            CHECK(gi_metrics_flip_map(test, ref, &o, map, &mean, &err) == GI_OK);
        CHECK_MSG(fabs(mean - want) <= 5e-5, "%s: gibench %.6f, NVIDIA %.6f", pairs[k], mean, want);
        gi_image *nv = k == 1 ? read_pfm(GI_TEST_DATA "/flip/edges_flip_map.pfm") : NULL;
        if (k == 1) {
            CHECK_MSG(nv && ref && nv->width == ref->width && nv->height == ref->height,
                      "edges_flip_map.pfm: not readable or not the pair's size");
            double worst = 0.0;
            for (size_t i = 0; nv && map && i < (size_t)nv->width * nv->height; i++)
                worst = fmax(worst, fabs(map[i] - nv->rgba[i * 4]));
            CHECK_MSG(worst <= 0.004, "edges: per-pixel FLIP differs by up to %.4f", worst);
        }
        gi_image_free(nv);
        free(map);
        gi_image_free(ref);
        gi_image_free(test);
    }
    free(json);
}

/* HDR-FLIP against NVIDIA's tool (FLIP v1.6, EXR inputs, its defaults: ACES,
 * exposures from the reference) on a gibench render and its reference: the
 * exposure range within 1e-3 stops and the mean within 5e-5 (six decimals). */
static void test_flip_hdr_nvidia(void)
{
    size_t n = 0;
    char *json = gi_file_read_all(GI_TEST_DATA "/flip/reference.json", &n);
    CHECK_MSG(json != NULL, "tests/data/flip/reference.json not readable");
    gi_error err;
    gi_image *ref = gi_image_read(GI_TEST_DATA "/flip/render_ref.exr", &err);
    gi_image *test = gi_image_read(GI_TEST_DATA "/flip/render_test.exr", &err);
    CHECK_MSG(ref && test, "%s", err.text);
    if (!json || !ref || !test) {
        free(json);
        gi_image_free(ref);
        gi_image_free(test);
        return;
    }
    size_t px = (size_t)ref->width * ref->height;
    float *r3 = malloc(px * 3 * sizeof *r3), *t3 = malloc(px * 3 * sizeof *t3);
    float *map = malloc(px * sizeof *map);
    for (size_t i = 0; r3 && t3 && i < px; i++)
        for (int c = 0; c < 3; c++) {
            r3[i * 3 + c] = ref->rgba[i * 4 + c];
            t3[i * 3 + c] = test->rgba[i * 4 + c];
        }
    gi_flip_hdr_info info = {0};
    double mean = NAN;
    if (r3 && t3 && map &&
        gi_flip_hdr_map(t3, r3, ref->width, ref->height, GI_FLIP_PPD_DEFAULT, map, &info, &err) ==
            GI_OK) {
        mean = 0.0;
        for (size_t i = 0; i < px; i++)
            mean += map[i];
        mean /= (double)px;
    }
    const char *e = strstr(json, "\"Start exposure\": \"");
    double start = e ? strtod(e + 19, NULL) : NAN;
    e = strstr(json, "\"Stop exposure\": \"");
    double stop = e ? strtod(e + 18, NULL) : NAN, want = nvidia_mean(json, "hdr", "render");
    CHECK_MSG(fabs(info.start - start) <= 1e-3 && fabs(info.stop - stop) <= 1e-3,
              "exposures %.4f..%.4f, NVIDIA %.4f..%.4f", info.start, info.stop, start, stop);
    CHECK_MSG(info.count == 10, "%d exposures, NVIDIA 10", info.count);
    CHECK_MSG(fabs(mean - want) <= 5e-5, "HDR-FLIP: gibench %.6f, NVIDIA %.6f", mean, want);
    free(r3);
    free(t3);
    free(map);
    gi_image_free(ref);
    gi_image_free(test);
    free(json);
}

int main(void)
{
    test_single_pixel();
    test_constants();
    test_identical();
    test_nonfinite();
    test_errors();
    test_ssim_plane();
    test_flip_colour();
    test_flip_kernels();
    test_flip_values();
    test_flip_against_direct();
    test_flip_nvidia();
    test_flip_hdr_nvidia();
    test_leaked_energy();
    return gi_test_finish();
}
