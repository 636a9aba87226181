/* Error heat maps with a colour bar (gibench diff --heatmap, reports).
 *
 * gi_heatmap_render turns a per-pixel map (e.g. gi_metrics_relerr_map) into
 * a new gi_image you own (gi_image_free): the map in colour at the top left,
 * and to its right a vertical colour bar, low values at the bottom, with
 * tick marks, numeric labels and an optional title in a built-in 3x5 pixel
 * font. Pixels that are NaN in the map (excluded, non-finite) are mid grey.
 *
 * The image holds LINEAR values: each colour is the sRGB-decoded value of the
 * intended display colour, so gi_image_write(".png", exposure 0), which
 * sRGB-encodes, shows exactly the colour map's sRGB colours.
 *
 * Scales: linear, t = (v - lo) / (hi - lo), or log10, t = (log10 v - log10
 * lo) / (log10 hi - log10 lo); t is clamped to [0, 1] (v <= 0 is t = 0 on a
 * log scale). Ticks: every decade on a log scale, lo + k (hi - lo) / 4 on a
 * linear one.
 */
#ifndef GI_HARNESS_HEATMAP_H
#define GI_HARNESS_HEATMAP_H

#include "gi/image.h"

typedef enum gi_colormap {
    GI_COLORMAP_VIRIDIS = 0, /* dark blue -> green -> yellow */
    GI_COLORMAP_MAGMA = 1,   /* black -> purple -> orange -> pale yellow (FLIP's maps) */
} gi_colormap;

/* Defaults of the relative-error heat map of gibench diff. */
#define GI_HEATMAP_RELERR_LO 1e-3f
#define GI_HEATMAP_RELERR_HI 10.0f

typedef struct gi_heatmap_opts {
    gi_colormap colormap;
    int log_scale;     /* nonzero: log10 scale (lo > 0 needed) */
    float lo, hi;      /* range; both 0 = default: log 1e-3..10, linear 0..1 */
    const char *title; /* above the bar: A-Z, 0-9, . - + % ( ) / and space; NULL = none */
} gi_heatmap_opts;

/* The sRGB colour (each in [0, 1]) of t in [0, 1] (clamped; NaN gives t = 0).
 * Piecewise linear between 17 samples of matplotlib's map (CC0) at t = k/16. */
void gi_colormap_srgb(gi_colormap map, float t, float srgb[3]);

/* NULL + err (GI_ERR_INVALID_ARGUMENT) for a bad range, NULL on out of memory. */
gi_image *gi_heatmap_render(const float *values, uint32_t width, uint32_t height,
                            const gi_heatmap_opts *opts, gi_error *err);

/* The built-in font, for tests: 1 if the glyph of ch has its pixel (col, row)
 * set (col 0..2, row 0..4, row 0 at the top); 0 otherwise or for a
 * character it does not have. */
int gi_heatmap_glyph_pixel(char ch, int col, int row);

#endif
