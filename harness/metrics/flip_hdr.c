/* HDR-FLIP: LDR-FLIP (flip.c) over a range of exposures of a filmic tone
 * curve, the largest error per pixel. See flip.h. */
#include "flip.h"

#include "gi/tonemap.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ACES filmic fit (Narkowicz 2015), x (2.51 x + 0.03) / (x (2.43 x + 0.59)
 * + 0.14), of 0.6 x: the paper's pre-exposure, which cancels the fit's
 * built-in brightening. As a ratio of quadratics in x: */
static const double TA = 0.6 * 0.6 * 2.51, TB = 0.6 * 0.03, TD = 0.6 * 0.6 * 2.43, TE = 0.6 * 0.59,
                    TF = 0.14;

double gi_flip_hdr_tonemap(double x)
{
    return (TA * x * x + TB * x) / (TD * x * x + TE * x + TF);
}

static double finite_or_zero(float v)
{
    return isfinite(v) ? (double)v : 0.0;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

gi_flip_hdr_info gi_flip_hdr_exposures(const float *ref, uint32_t w, uint32_t h)
{
    gi_flip_hdr_info info = {0.0, 0.0, 2};
    size_t n = (size_t)w * h;
    double *lum = n ? malloc(n * sizeof *lum) : NULL;
    if (!lum)
        return info;
    double ymax = 0.0;
    for (size_t i = 0; i < n; i++) {
        const float *p = ref + i * 3;
        lum[i] = 0.2126 * finite_or_zero(p[0]) + 0.7152 * finite_or_zero(p[1]) +
                 0.0722 * finite_or_zero(p[2]);
        ymax = fmax(ymax, lum[i]);
    }
    qsort(lum, n, sizeof *lum, cmp_double);
    double ymed = lum[n / 2];
    free(lum);
    /* x_max: the larger root of T(x) = 0.85, (TA - t TD) x^2 + (TB - t TE) x - t TF = 0 */
    const double t = 0.85, a = TA - t * TD, b = TB - t * TE, c = -t * TF;
    double d1 = -0.5 * b / a, xmax = d1 + sqrt(d1 * d1 - c / a);
    if (ymax > 0.0) {
        info.start = log2(xmax / ymax);
        info.stop = ymed > 0.0 ? log2(xmax / ymed) : info.start;
    }
    double span = ceil(info.stop - info.start);
    info.count = span > 2.0 ? (int)fmin(span, 64.0) : 2;
    return info;
}

/* The display values LDR-FLIP takes: exposed, tone mapped, clamped, sRGB-encoded. */
static void expose_tonemap(const float *lin, size_t n, double scale, float *srgb)
{
    for (size_t i = 0; i < n * 3; i++) {
        double v = gi_flip_hdr_tonemap(finite_or_zero(lin[i]) * scale);
        srgb[i] = gi_srgb_encode((float)fmin(fmax(v, 0.0), 1.0));
    }
}

gi_result gi_flip_hdr_map(const float *test, const float *ref, uint32_t w, uint32_t h, double ppd,
                          float *out, gi_flip_hdr_info *info_out, gi_error *err)
{
    gi_flip_hdr_info info = gi_flip_hdr_exposures(ref, w, h);
    if (info_out)
        *info_out = info;
    size_t n = (size_t)w * h;
    if (!(ppd > 0.0) || !isfinite(ppd) || ppd > 1e4)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "HDR-FLIP: pixels per degree %g is not in (0, 10000]", ppd);
    if (n == 0)
        return GI_OK;
    float *ts = malloc(n * 3 * sizeof *ts), *rs = malloc(n * 3 * sizeof *rs);
    float *map = malloc(n * sizeof *map);
    gi_result res = GI_OK;
    if (!ts || !rs || !map)
        res = gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "HDR-FLIP: out of memory for a %ux%u image",
                           w, h);
    for (size_t i = 0; res == GI_OK && i < n; i++)
        out[i] = 0.0f;
    double step = (info.stop - info.start) / (info.count - 1);
    for (int k = 0; res == GI_OK && k < info.count; k++) {
        double scale = exp2(info.start + k * step);
        expose_tonemap(test, n, scale, ts);
        expose_tonemap(ref, n, scale, rs);
        res = gi_flip_map(ts, rs, w, h, ppd, map, err);
        for (size_t i = 0; res == GI_OK && i < n; i++)
            out[i] = fmaxf(out[i], map[i]);
    }
    free(ts);
    free(rs);
    free(map);
    return res;
}
