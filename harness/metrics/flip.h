/* LDR-FLIP: the perceptual difference of two display (sRGB) images.
 *
 * Andersson, Nilsson, Akenine-Möller, Oskarsson, Åström, Fairchild: "FLIP: A
 * Difference Evaluator for Alternating Images", Proc. ACM Comput. Graph.
 * Interact. Tech. 3(2), HPG 2020. Written here from the paper's description
 * (its §3 and §4); the symbols below are the paper's.
 *
 * gi_flip_map is the whole evaluator: two sRGB images in [0, 1], 3 floats a
 * pixel, the viewing distance as pixels per degree of visual angle, and out
 * comes one error in [0, 1] per pixel. gi_metrics_flip_map (metrics.h) feeds
 * it tonemapped linear images; the functions after it are its building blocks,
 * public so that tests can hold each one against hand-computed values.
 *
 *   colour pipeline  sRGB -> linear RGB -> XYZ -> YCxCz (opponent space);
 *                    each channel filtered with its contrast-sensitivity
 *                    kernel (clamped borders); -> linear RGB, clamped to
 *                    [0, 1]; -> CIELAB -> Hunt adjustment (a, b scaled by
 *                    0.01 L); HyAB distance; raised to qc and compressed to
 *                    [0, 1] (pc, pt, cmax)                       -> dE_c
 *   feature pipeline Y/Yn of the unfiltered images; edges and points from
 *                    first and second derivative-of-Gaussian filters in x and
 *                    y (std. deviation 0.5 w ppd); the larger difference of
 *                    the edge or point magnitudes, / sqrt 2, raised to qf
 *                                                                -> dE_f
 *   FLIP             dE_c ^ (1 - dE_f)
 *
 * Colorimetry: sRGB primaries, D65 white = the XYZ of linear RGB (1, 1, 1).
 */
#ifndef GI_HARNESS_FLIP_H
#define GI_HARNESS_FLIP_H

#include "gi/common.h"

/* The paper's constants. */
#define GI_FLIP_QC 0.7  /* exponent of the colour difference */
#define GI_FLIP_QF 0.5  /* exponent of the feature difference */
#define GI_FLIP_PC 0.4  /* fraction of cmax ... */
#define GI_FLIP_PT 0.95 /* ... mapped to this fraction of [0, 1] */
#define GI_FLIP_W 0.082 /* edge detector peak-to-trough width, degrees */
/* Pixels per degree of the paper's standard observer: a 0.7 m wide 3840-pixel
 * monitor seen from 0.7 m, 3840 * (0.7 / 0.7) * pi / 180 = 67.02. */
#define GI_FLIP_PPD_DEFAULT 67.02064327658226

/* Contrast-sensitivity parameters (the paper's values, after Johnson and
 * Fairchild 2003): channel 0 achromatic (A), 1 red-green (RG), 2 blue-yellow (BY).
 * The spatial kernel is S(x) = a1 sqrt(pi/b1) exp(-pi^2 |x|^2 / b1)
 *                            + a2 sqrt(pi/b2) exp(-pi^2 |x|^2 / b2),
 * x in degrees, sampled every 1/ppd and normalised to sum 1. */
typedef struct gi_flip_csf {
    double a1, b1, a2, b2;
} gi_flip_csf;
extern const gi_flip_csf gi_flip_csf_params[3];

/* Per-pixel FLIP of test against ref (w*h pixels, 3 floats each, sRGB values
 * in [0, 1]; values outside are clamped) into out[w*h]. ppd > 0.
 * GI_ERR_INVALID_ARGUMENT for a bad ppd, GI_ERR_OUT_OF_MEMORY. */
gi_result gi_flip_map(const float *test_srgb, const float *ref_srgb, uint32_t w, uint32_t h,
                      double ppd, float *out, gi_error *err);

/* HDR-FLIP (Andersson, Nilsson, Shirley, Akenine-Möller: "Visualizing
 * Errors in Rendered High Dynamic Range Images", Eurographics 2021 short
 * papers), written from the paper: both linear images are exposed by 2^c
 * for `count` exposures c evenly spaced from `start` to `stop`, tone mapped
 * by the ACES fit of Narkowicz (2015) after a pre-exposure of 0.6, clamped
 * to [0, 1], and compared by LDR-FLIP; a pixel's HDR-FLIP is its largest
 * LDR-FLIP over the exposures. The range comes from the reference: with
 * x_max the radiance the tone curve maps to 0.85, start = log2(x_max /
 * Y_max) and stop = log2(x_max / Y_median) (Y the luminance, Rec. 709
 * weights; the median the (n/2)-th smallest of the n pixels), and count =
 * max(2, ceil(stop - start)). A black reference gives start = stop = 0;
 * a median of 0 gives stop = start. */
typedef struct gi_flip_hdr_info {
    double start, stop; /* exposures in stops */
    int count;
} gi_flip_hdr_info;

/* Per-pixel HDR-FLIP of test against ref (w*h pixels, 3 linear floats each;
 * a non-finite value counts as 0) into out[w*h]; info (may be NULL) gets the
 * exposures used. GI_ERR_INVALID_ARGUMENT for a bad ppd, GI_ERR_OUT_OF_MEMORY. */
gi_result gi_flip_hdr_map(const float *test_linear, const float *ref_linear, uint32_t w, uint32_t h,
                          double ppd, float *out, gi_flip_hdr_info *info, gi_error *err);
/* The exposure range of HDR-FLIP for a reference (as gi_flip_hdr_map uses it). */
gi_flip_hdr_info gi_flip_hdr_exposures(const float *ref_linear, uint32_t w, uint32_t h);
/* The tone curve: ACES (Narkowicz) of 0.6 x, not clamped. */
double gi_flip_hdr_tonemap(double x);

/* --- building blocks --- */

/* Radius in pixels of the colour kernels: ceil(3 sqrt(b_max / (2 pi^2)) ppd),
 * b_max the widest of the six b parameters, so all three share one size. */
int gi_flip_csf_radius(double ppd);
/* The 2-D kernel of a channel, (2r+1)^2 weights row by row, r =
 * gi_flip_csf_radius(ppd), built from the separable terms the filter uses. */
void gi_flip_csf_kernel(double ppd, int channel, double *out);
/* Feature kernels: standard deviation sd = 0.5 w ppd pixels, radius
 * ceil(3 sd). edge[] is -x g(x), point[] is (x^2/sd^2 - 1) g(x), with
 * g(x) = exp(-x^2 / (2 sd^2)); each with its positive taps scaled to sum 1
 * and its negative ones to -1. gauss[] is g normalised to sum 1, the
 * kernel's other axis. Arrays hold 2r+1 taps; returns r. */
int gi_flip_feature_radius(double ppd);
void gi_flip_feature_kernels(double ppd, double *edge, double *point, double *gauss);

void gi_flip_linrgb_to_xyz(const double rgb[3], double xyz[3]);
void gi_flip_xyz_to_linrgb(const double xyz[3], double rgb[3]);
void gi_flip_xyz_to_ycxcz(const double xyz[3], double ycxcz[3]);
void gi_flip_ycxcz_to_xyz(const double ycxcz[3], double xyz[3]);
void gi_flip_xyz_to_lab(const double xyz[3], double lab[3]);
/* Linear RGB -> CIELAB -> Hunt-adjusted (L, 0.01 L a, 0.01 L b). */
void gi_flip_linrgb_to_hunt_lab(const double rgb[3], double hlab[3]);
/* HyAB distance: |dL| + sqrt(da^2 + db^2). */
double gi_flip_hyab(const double x[3], const double y[3]);
/* cmax = HyAB(Hunt-Lab green, Hunt-Lab blue) ^ qc: the largest colour
 * difference, between the primaries that lie farthest apart. */
double gi_flip_cmax(void);
/* The paper's compression of e = HyAB^qc to [0, 1]: e < pc cmax maps
 * linearly to [0, pt), the rest linearly from pt to 1 at e = cmax. */
double gi_flip_compress(double e, double cmax);

#endif
