/* Separable 2-D filtering of one double-precision image plane, shared by the
 * FLIP (flip.c) and SSIM (metrics.c) code of the gi_metrics library.
 *
 * The kernels are correlations: out(x, y) = sum_i sum_j kx[i + rx] ky[j + ry]
 * in(x + i, y + j), first along x, then along y. Borders:
 *   GI_BORDER_CLAMP        outside pixels repeat the nearest edge pixel
 *                          (what the FLIP paper's filters assume);
 *   GI_BORDER_RENORMALISE  the kernel is cut at the border and its remaining
 *                          weights rescaled to their original sum (SSIM: the
 *                          local statistics are those of the pixels inside).
 * Both are exact for separable kernels: clamping and cutting act per axis.
 */
#ifndef GI_HARNESS_FILTER_H
#define GI_HARNESS_FILTER_H

#include <stdint.h>

typedef enum gi_border { GI_BORDER_CLAMP = 0, GI_BORDER_RENORMALISE = 1 } gi_border;

/* in, out and tmp hold w*h values each; out may equal in, tmp must differ
 * from both. kx has 2*rx+1 taps, ky 2*ry+1. */
void gi_filter_separable(const double *in, double *out, double *tmp, uint32_t w, uint32_t h,
                         const double *kx, int rx, const double *ky, int ry, gi_border border);

#endif
