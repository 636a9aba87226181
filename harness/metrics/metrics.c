/* Image-error metrics (RMSE, relMSE, MAE, PSNR, SSIM, mean luminance, FLIP)
 * and per-pixel error maps; definitions in metrics.h. */
#include "metrics.h"

#include "filter.h"
#include "flip.h"
#include "gi/tonemap.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static inline int finite3(const float *p)
{
    return isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]);
}

static inline double lum(const float *p)
{
    return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
}

static gi_result check_pair(const gi_image *test, const gi_image *ref, gi_error *err)
{
    assert(test && ref && test->rgba && ref->rgba);
    if (test->width != ref->width || test->height != ref->height)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "image sizes differ: test %ux%u, reference %ux%u", test->width,
                            test->height, ref->width, ref->height);
    return GI_OK;
}

static gi_result check_opts(const gi_metrics_opts *o, gi_error *err)
{
    if (!isfinite(o->exposure) || fabsf(o->exposure) > 64.0f)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "exposure %g is not in [-64, 64] stops",
                            (double)o->exposure);
    if (o->dark_threshold != 0.0f && (!(o->dark_threshold > 0.0f) || !(o->dark_threshold <= 1.0f)))
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "dark threshold %g is not in (0, 1]",
                            (double)o->dark_threshold);
    if (o->flip_ppd != 0.0f &&
        (!(o->flip_ppd > 0.0f) || !isfinite(o->flip_ppd) || o->flip_ppd > 1e4f))
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "FLIP pixels per degree %g is not in (0, 10000]", (double)o->flip_ppd);
    return GI_OK;
}

static double ppd_of(const gi_metrics_opts *o)
{
    return o->flip_ppd > 0.0f ? (double)o->flip_ppd : GI_FLIP_PPD_DEFAULT;
}

/* The pixel whose values both images take at an excluded pixel (see
 * metrics.h): the reference's if finite, else the test's, else NULL (0). */
static const float *shared_pixel(const float *x, const float *r)
{
    return finite3(r) ? r : finite3(x) ? x : NULL;
}

/* ---- SSIM ---- */

gi_result gi_metrics_ssim_plane(const double *x, const double *y, const uint8_t *mask, uint32_t w,
                                uint32_t h, double *mean, gi_error *err)
{
    size_t n = (size_t)w * h;
    double k[2 * GI_SSIM_RADIUS + 1], ksum = 0.0;
    for (int i = -GI_SSIM_RADIUS; i <= GI_SSIM_RADIUS; i++)
        ksum += k[i + GI_SSIM_RADIUS] =
            exp(-(double)(i * i) / (2.0 * GI_SSIM_SIGMA * GI_SSIM_SIGMA));
    for (int i = 0; i < 2 * GI_SSIM_RADIUS + 1; i++)
        k[i] /= ksum;

    double *mx = malloc(n * sizeof *mx), *my = malloc(n * sizeof *my),
           *sxx = malloc(n * sizeof *sxx), *syy = malloc(n * sizeof *syy),
           *sxy = malloc(n * sizeof *sxy), *tmp = malloc(n * sizeof *tmp);
    gi_result res = GI_OK;
    if (!mx || !my || !sxx || !syy || !sxy || !tmp) {
        res =
            gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "SSIM: out of memory for a %ux%u image", w, h);
        goto done;
    }
#define WINDOW(in, out)                                                                            \
    gi_filter_separable(in, out, tmp, w, h, k, GI_SSIM_RADIUS, k, GI_SSIM_RADIUS,                  \
                        GI_BORDER_RENORMALISE)
    WINDOW(x, mx);
    WINDOW(y, my);
    for (size_t i = 0; i < n; i++)
        sxx[i] = x[i] * x[i];
    WINDOW(sxx, sxx);
    for (size_t i = 0; i < n; i++)
        syy[i] = y[i] * y[i];
    WINDOW(syy, syy);
    for (size_t i = 0; i < n; i++)
        sxy[i] = x[i] * y[i];
    WINDOW(sxy, sxy);
#undef WINDOW

    const double c1 = (GI_SSIM_K1 * 1.0) * (GI_SSIM_K1 * 1.0),
                 c2 = (GI_SSIM_K2 * 1.0) * (GI_SSIM_K2 * 1.0);
    double sum = 0.0;
    uint64_t count = 0;
    for (size_t i = 0; i < n; i++) {
        if (mask && !mask[i])
            continue;
        double vx = sxx[i] - mx[i] * mx[i], vy = syy[i] - my[i] * my[i],
               cxy = sxy[i] - mx[i] * my[i];
        double s = ((2.0 * mx[i] * my[i] + c1) * (2.0 * cxy + c2)) /
                   ((mx[i] * mx[i] + my[i] * my[i] + c1) * (vx + vy + c2));
        sum += s;
        count++;
    }
    *mean = count ? sum / (double)count : NAN;

done:
    free(mx);
    free(my);
    free(sxx);
    free(syy);
    free(sxy);
    free(tmp);
    return res;
}

/* ---- maps ---- */

gi_result gi_metrics_relerr_map(const gi_image *test, const gi_image *ref, float *map,
                                gi_error *err)
{
    gi_result res = check_pair(test, ref, err);
    if (res)
        return res;
    size_t n = (size_t)test->width * test->height;
    for (size_t i = 0; i < n; i++) {
        const float *x = test->rgba + i * 4, *r = ref->rgba + i * 4;
        if (!finite3(x) || !finite3(r)) {
            map[i] = NAN;
            continue;
        }
        double s = 0.0;
        for (int c = 0; c < 3; c++)
            s += fabs((double)x[c] - r[c]) / ((double)r[c] + 0.01);
        map[i] = (float)(s / 3.0);
    }
    return GI_OK;
}

/* The mean of a per-pixel map over the pixels finite in both images (NaN
 * if none; mean may be NULL), the others set to NaN. */
static void mean_of_map(const gi_image *test, const gi_image *ref, size_t n, float *map,
                        double *mean)
{
    double sum = 0.0;
    uint64_t count = 0;
    for (size_t i = 0; i < n; i++) {
        if (finite3(test->rgba + i * 4) && finite3(ref->rgba + i * 4)) {
            sum += map[i];
            count++;
        } else {
            map[i] = NAN;
        }
    }
    if (mean)
        *mean = count ? sum / (double)count : NAN;
}

/* The RGB planes FLIP compares (new arrays in *ts and *rs), checked first:
 * each image's pixels, tone mapped at the exposure when `tonemap` (LDR-FLIP)
 * or linear (HDR-FLIP picks its own exposures); a pixel that is not finite
 * in one image takes the other's value in both (shared_pixel), or 0. */
static gi_result flip_planes(const gi_image *test, const gi_image *ref, const gi_metrics_opts *o,
                             int tonemap, const char *what, float **ts, float **rs, gi_error *err)
{
    gi_result res = check_pair(test, ref, err);
    if (!res)
        res = check_opts(o, err);
    if (res)
        return res;
    size_t n = (size_t)test->width * test->height;
    float *t = malloc(n * 3 * sizeof *t), *r = malloc(n * 3 * sizeof *r);
    if (!t || !r) {
        free(t);
        free(r);
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "%s: out of memory for a %ux%u image", what,
                            test->width, test->height);
    }
    for (size_t i = 0; i < n; i++) {
        const float *x = test->rgba + i * 4, *y = ref->rgba + i * 4;
        int shared = !(finite3(x) && finite3(y));
        const float *s = shared ? shared_pixel(x, y) : NULL;
        for (int c = 0; c < 3; c++) {
            float a = shared ? (s ? s[c] : 0.0f) : x[c], b = shared ? (s ? s[c] : 0.0f) : y[c];
            int keep = shared && !s; /* no value in either: 0 in both, not tone mapped */
            t[i * 3 + c] = tonemap && !keep ? gi_tonemap(a, o->exposure) : a;
            r[i * 3 + c] = tonemap && !keep ? gi_tonemap(b, o->exposure) : b;
        }
    }
    *ts = t;
    *rs = r;
    return GI_OK;
}

gi_result gi_metrics_flip_map(const gi_image *test, const gi_image *ref,
                              const gi_metrics_opts *opts, float *map, double *mean, gi_error *err)
{
    gi_metrics_opts defaults = {0};
    const gi_metrics_opts *o = opts ? opts : &defaults;
    float *ts = NULL, *rs = NULL;
    gi_result res = flip_planes(test, ref, o, 1, "FLIP", &ts, &rs, err);
    if (res)
        return res;
    res = gi_flip_map(ts, rs, test->width, test->height, ppd_of(o), map, err);
    if (!res)
        mean_of_map(test, ref, (size_t)test->width * test->height, map, mean);
    free(ts);
    free(rs);
    return res;
}

/* HDR-FLIP (Andersson et al. 2021) takes the linear images themselves: it
 * picks its exposures from the reference and tone maps each one itself. */
gi_result gi_metrics_hdr_flip_map(const gi_image *test, const gi_image *ref,
                                  const gi_metrics_opts *opts, float *map, double *mean,
                                  gi_flip_hdr_info *info, gi_error *err)
{
    gi_metrics_opts defaults = {0};
    const gi_metrics_opts *o = opts ? opts : &defaults;
    float *tl = NULL, *rl = NULL;
    gi_result res = flip_planes(test, ref, o, 0, "HDR-FLIP", &tl, &rl, err);
    if (res)
        return res;
    res = gi_flip_hdr_map(tl, rl, test->width, test->height, ppd_of(o), map, info, err);
    if (!res)
        mean_of_map(test, ref, (size_t)test->width * test->height, map, mean);
    free(tl);
    free(rl);
    return res;
}

/* ---- everything ---- */

/* The sums over the pixels finite in both images. */
typedef struct pixel_sums {
    double se, rel, ae, se_t, sum_lx, sum_lr;
} pixel_sums;

/* One pass over the pixels: the excluded ones counted and masked out, the
 * sums of the others, and each pixel's tonemapped luminance for SSIM. */
static void sum_pixels(const gi_image *test, const gi_image *ref, const gi_metrics_opts *o,
                       size_t n, gi_metrics *out, uint8_t *mask, double *lx, double *lr,
                       pixel_sums *sums)
{
    double se = 0.0, rel = 0.0, ae = 0.0, se_t = 0.0, sum_lx = 0.0, sum_lr = 0.0;
    for (size_t i = 0; i < n; i++) {
        const float *x = test->rgba + i * 4, *r = ref->rgba + i * 4;
        int fx = finite3(x), fr = finite3(r);
        out->nonfinite_test += !fx;
        out->nonfinite_ref += !fr;
        mask[i] = (uint8_t)(fx && fr);
        if (!mask[i]) {
            out->excluded++;
            const float *s = shared_pixel(x, r);
            lx[i] = lr[i] = s ? gi_tonemap((float)lum(s), o->exposure) : 0.0;
            continue;
        }
        for (int c = 0; c < 3; c++) {
            double d = (double)x[c] - r[c], q = (double)r[c] + 0.01;
            se += d * d;
            rel += d * d / (q * q);
            ae += fabs(d);
            double dt = (double)gi_tonemap(x[c], o->exposure) - gi_tonemap(r[c], o->exposure);
            se_t += dt * dt;
        }
        sum_lx += lum(x);
        sum_lr += lum(r);
        lx[i] = gi_tonemap((float)lum(x), o->exposure);
        lr[i] = gi_tonemap((float)lum(r), o->exposure);
    }
    *sums = (pixel_sums){se, rel, ae, se_t, sum_lx, sum_lr};
}

/* The error and luminance metrics from the sums (out->pixels > 0). */
static void metrics_from_sums(const pixel_sums *sums, gi_metrics *out)
{
    double samples = 3.0 * (double)out->pixels;
    out->mse = sums->se / samples;
    out->rmse = sqrt(out->mse);
    out->relmse = sums->rel / samples;
    out->mae = sums->ae / samples;
    double mse_t = sums->se_t / samples;
    out->psnr = mse_t > 0.0 ? 10.0 * log10(1.0 / mse_t) : INFINITY;
    out->mean_lum_test = sums->sum_lx / (double)out->pixels;
    out->mean_lum_ref = sums->sum_lr / (double)out->pixels;
    if (out->mean_lum_ref != 0.0)
        out->mean_lum_diff_pct =
            100.0 * (out->mean_lum_test - out->mean_lum_ref) / out->mean_lum_ref;
    else
        out->mean_lum_diff_pct = out->mean_lum_test == 0.0 ? 0.0 : NAN;
}

/* leaked energy: the test's light where the reference is dark */
static void leaked_energy(const gi_image *test, const gi_image *ref, const uint8_t *mask, size_t n,
                          double sum_lr, gi_metrics *out)
{
    double dark_below = (double)out->dark_threshold * out->mean_lum_ref, leak = 0.0, own = 0.0;
    uint64_t dark = 0;
    for (size_t i = 0; i < n; i++) {
        if (!mask[i])
            continue;
        double yr = lum(ref->rgba + i * 4);
        if (yr < dark_below) {
            double yx = lum(test->rgba + i * 4);
            leak += yx > 0.0 ? yx : 0.0;
            own += yr > 0.0 ? yr : 0.0;
            dark++;
        }
    }
    out->dark_fraction = (double)dark / (double)out->pixels;
    out->leaked_energy = sum_lr > 0.0 ? leak / sum_lr : NAN;
    out->dark_energy_ref = sum_lr > 0.0 ? own / sum_lr : NAN;
}

gi_result gi_metrics_compute(const gi_image *test, const gi_image *ref, const gi_metrics_opts *opts,
                             gi_metrics *out, gi_error *err)
{
    assert(out);
    gi_metrics_opts defaults = {0};
    const gi_metrics_opts *o = opts ? opts : &defaults;
    gi_result res = check_pair(test, ref, err);
    if (!res)
        res = check_opts(o, err);
    if (res)
        return res;

    memset(out, 0, sizeof *out);
    out->width = test->width;
    out->height = test->height;
    out->exposure = o->exposure;
    out->flip_ppd = (float)ppd_of(o);
    out->dark_threshold = o->dark_threshold > 0.0f ? o->dark_threshold : GI_DARK_THRESHOLD_DEFAULT;
    size_t n = (size_t)test->width * test->height;

    uint8_t *mask = malloc(n);
    double *lx = malloc(n * sizeof *lx), *lr = malloc(n * sizeof *lr);
    float *fmap = o->skip_flip ? NULL : malloc(n * sizeof *fmap);
    if (!mask || !lx || !lr || (!o->skip_flip && !fmap)) {
        res = gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "metrics: out of memory for a %ux%u image",
                           test->width, test->height);
        goto done;
    }

    pixel_sums sums;
    sum_pixels(test, ref, o, n, out, mask, lx, lr, &sums);
    out->pixels = n - out->excluded;

    if (out->pixels == 0) {
        out->mse = out->rmse = out->relmse = out->mae = out->psnr = out->ssim = NAN;
        out->mean_lum_test = out->mean_lum_ref = out->mean_lum_diff_pct = out->flip = NAN;
        out->hdr_flip = out->hdr_flip_start = out->hdr_flip_stop = NAN;
        out->leaked_energy = out->dark_fraction = out->dark_energy_ref = NAN;
        goto done;
    }
    metrics_from_sums(&sums, out);
    leaked_energy(test, ref, mask, n, sums.sum_lr, out);

    res = gi_metrics_ssim_plane(lx, lr, mask, test->width, test->height, &out->ssim, err);
    if (res)
        goto done;
    out->flip = out->hdr_flip = out->hdr_flip_start = out->hdr_flip_stop = NAN;
    if (!o->skip_flip)
        res = gi_metrics_flip_map(test, ref, o, fmap, &out->flip, err);
    if (!res && !o->skip_flip) {
        gi_flip_hdr_info info = {0};
        res = gi_metrics_hdr_flip_map(test, ref, o, fmap, &out->hdr_flip, &info, err);
        out->hdr_flip_start = info.start;
        out->hdr_flip_stop = info.stop;
        out->hdr_flip_exposures = info.count;
    }

done:
    free(mask);
    free(lx);
    free(lr);
    free(fmap);
    return res;
}
