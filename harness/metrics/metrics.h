/* Image-error metrics of a test image against a reference (gibench diff,
 * and the compare and study runners). Library gi_metrics.
 *
 * Use
 * ---
 *   gi_metrics_opts o = {0};              zero fields mean defaults
 *   gi_metrics m;
 *   if (gi_metrics_compute(test, ref, &o, &m, &err)) ... err.text
 * Nothing to free. Per-pixel maps (gi_metrics_relerr_map,
 * gi_metrics_flip_map) fill a width*height float buffer that you own; turn
 * one into a picture with gi_heatmap_render (heatmap.h).
 *
 * Inputs are gi_image (linear RGBA32F); alpha is ignored. Both images must
 * have the same size, else GI_ERR_INVALID_ARGUMENT ("image sizes differ:
 * test WxH, reference WxH").
 *
 * Non-finite pixels: a pixel whose R, G or B is NaN or ±Inf in either image
 * is excluded from every metric: the means below run over the N remaining
 * pixels. nonfinite_test / nonfinite_ref count them per image, `excluded`
 * their union. For the windowed metrics (SSIM, FLIP) an excluded pixel is
 * also made to carry no difference into its neighbours' windows: both images
 * get the same value there (the reference's tonemapped value if it is
 * finite, else the test's, else 0). With N = 0 every metric is NaN.
 *
 * Definitions (x = test, r = reference, sums over the N pixels p and the
 * channels c in {R, G, B}; Y = 0.2126 R + 0.7152 G + 0.0722 B, Rec. 709 /
 * sRGB luminance; T(v) = gi_tonemap(v, exposure): 2^exposure v, clamped to
 * [0, 1], sRGB-encoded, as in PNG output):
 *   mse            (1/3N) sum (x - r)^2                     linear values
 *   rmse           sqrt(mse)                                linear values
 *   relmse         (1/3N) sum (x - r)^2 / (r + 0.01)^2      linear values
 *   mae            (1/3N) sum |x - r|                       linear values
 *   psnr           10 log10(1 / mse_T), mse_T the mse of T(x) and T(r):
 *                  peak 1 on TONEMAPPED values; +Inf when mse_T = 0
 *   ssim           mean over the N pixels of SSIM (Wang, Bovik, Sheikh,
 *                  Simoncelli 2004) of the tonemapped luminances T(Y(x)),
 *                  T(Y(r)): 11x11 Gaussian window, sigma 1.5, cut at the
 *                  image border and renormalised; K1 = 0.01, K2 = 0.03,
 *                  L = 1 (C1 = (K1 L)^2, C2 = (K2 L)^2):
 *                  ((2 mx my + C1)(2 sxy + C2)) / ((mx^2 + my^2 + C1)(sx^2 + sy^2 + C2))
 *   mean_lum_*     (1/N) sum Y, linear values
 *   mean_lum_diff_pct  100 (mean_lum_test - mean_lum_ref) / mean_lum_ref;
 *                  0 when both means are 0, NaN when only the reference's is
 *   flip           mean over the N pixels of LDR-FLIP (flip.h) of the
 *                  tonemapped sRGB images T(x), T(r) at flip_ppd pixels per
 *                  degree
 *   hdr_flip       mean over the N pixels of HDR-FLIP (flip.h,
 *                  gi_flip_hdr_map) of the linear images x, r at flip_ppd:
 *                  its own exposures from the reference, so `exposure`
 *                  does not change it; hdr_flip_start, _stop, _exposures
 *                  the exposures it used
 *   leaked_energy  light the test puts where the reference is dark: the
 *                  dark pixels D are those with Y(r) < dark_threshold *
 *                  mean Y(r) (dark_threshold relative, default 0.01);
 *                  leaked_energy = sum over D of max(Y(x), 0) / sum over all
 *                  N pixels of Y(r); NaN when the reference is black
 *   dark_fraction  |D| / N
 *   dark_energy_ref  the same sum of the reference's own luminance over D
 *                  divided by its total: what the reference itself has there
 *                  (at most dark_threshold * dark_fraction), the baseline
 *                  a leak is read against
 */
#ifndef GI_HARNESS_METRICS_H
#define GI_HARNESS_METRICS_H

#include "gi/image.h"

#include <stdint.h>

typedef struct gi_metrics_opts {
    float exposure;       /* stops, applied before tonemapping (psnr, ssim, flip); 0 = none */
    float flip_ppd;       /* FLIP pixels per degree; 0 = GI_FLIP_PPD_DEFAULT (67.02) */
    int skip_flip;        /* nonzero: leave flip and hdr_flip NaN (the slowest metrics) */
    float dark_threshold; /* leaked energy: dark = Y(r) below this times mean Y(r); 0 =
                             GI_DARK_THRESHOLD_DEFAULT */
} gi_metrics_opts;

/* Dark pixels of leaked_energy: luminance below 1 % of the reference's mean. */
#define GI_DARK_THRESHOLD_DEFAULT 0.01f

typedef struct gi_metrics {
    uint32_t width, height;
    uint64_t nonfinite_test, nonfinite_ref; /* pixels with a non-finite R, G or B */
    uint64_t excluded;                      /* pixels non-finite in either image */
    uint64_t pixels;                        /* N: the pixels compared */
    double mse, rmse, relmse, mae;
    double psnr;
    double ssim;
    double mean_lum_test, mean_lum_ref, mean_lum_diff_pct;
    double flip;
    double hdr_flip, hdr_flip_start, hdr_flip_stop;
    int hdr_flip_exposures;
    double leaked_energy, dark_fraction, dark_energy_ref;
    float exposure, flip_ppd, dark_threshold; /* the options in effect */
} gi_metrics;

/* SSIM constants. */
#define GI_SSIM_RADIUS 5 /* 11x11 window */
#define GI_SSIM_SIGMA 1.5
#define GI_SSIM_K1 0.01
#define GI_SSIM_K2 0.03

/* All metrics of test against ref. GI_ERR_INVALID_ARGUMENT on a size
 * mismatch or a bad option, GI_ERR_OUT_OF_MEMORY. */
gi_result gi_metrics_compute(const gi_image *test, const gi_image *ref, const gi_metrics_opts *opts,
                             gi_metrics *out, gi_error *err);

/* Per-pixel relative error, mean over R, G, B of |x - r| / (r + 0.01), into
 * map[width*height]; NaN at excluded pixels. */
gi_result gi_metrics_relerr_map(const gi_image *test, const gi_image *ref, float *map,
                                gi_error *err);

/* Per-pixel FLIP of the tonemapped images into map[width*height]; NaN at
 * excluded pixels. mean (may be NULL) receives the mean over the others
 * (NaN if none). */
gi_result gi_metrics_flip_map(const gi_image *test, const gi_image *ref,
                              const gi_metrics_opts *opts, float *map, double *mean, gi_error *err);

/* Per-pixel HDR-FLIP of the linear images into map[width*height]; NaN at
 * excluded pixels (which carry no difference into their neighbours, as in
 * gi_metrics_flip_map). mean (may be NULL) receives the mean over the
 * others (NaN if none), info (may be NULL) the exposures used. */
struct gi_flip_hdr_info;
gi_result gi_metrics_hdr_flip_map(const gi_image *test, const gi_image *ref,
                                  const gi_metrics_opts *opts, float *map, double *mean,
                                  struct gi_flip_hdr_info *info, gi_error *err);

/* Mean SSIM of two luminance planes (w*h values each, nominally in [0, 1]),
 * over the pixels where mask is nonzero (mask may be NULL: all). */
gi_result gi_metrics_ssim_plane(const double *x, const double *y, const uint8_t *mask, uint32_t w,
                                uint32_t h, double *mean, gi_error *err);

#endif
