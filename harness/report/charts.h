/* Charts for the reports: x-y line and scatter plots written as PNG files,
 * drawn by VTK (the charts shim, harness/report/charts.cpp; no C++ type leaves it).
 *
 * Use:
 *     gi_chart_series s[2] = {
 *         {"csm", time_ms, rmse, n, GI_CHART_LINE_MARKERS},
 *         {"path tracer", pt_time, pt_rmse, m, GI_CHART_DASHED},
 *     };
 *     gi_chart_desc d = {"Cornell box: error vs time", "time [ms]", "RMSE", 1, 1, 0, 0};
 *     if (gi_chart_write_png("out/error_time.png", &d, s, 2, &err)) ... err.text says why
 *
 * Ownership: the caller keeps every string and array; nothing is retained
 * after a call returns.
 *
 * Points: x[i], y[i] for i < count, joined in the order given. A point with a
 * NaN or infinite coordinate, or with a coordinate <= 0 on a log axis, is not
 * drawn; when that happens a warning names the series and the number of
 * points dropped (gi_log, level WARN). gi_chart_points_kept says in advance
 * how many points of a series will be drawn. A series with no points left is
 * still listed in the legend. Series get colours from a fixed colour-blind-
 * safe palette (Okabe & Ito) and marker shapes in a fixed order, both by
 * position in the array, so the same method keeps its look across charts
 * when it keeps its position.
 *
 * Rendering is headless: an EGL context of its own (Mesa's surfaceless
 * platform, else an EGL device) made current for the duration of the call
 * and destroyed afterwards; no X server is needed. A GL context the caller
 * has current on this thread is made current again before returning. Calls
 * are serialised internally (VTK keeps process-wide state); a chart takes
 * a few hundred milliseconds on llvmpipe.
 *
 * The file is written atomically: a temporary file in the destination
 * directory, renamed into place, so a reader never sees a partial PNG.
 */
#ifndef GIBENCH_CHARTS_H
#define GIBENCH_CHARTS_H

#include "gi/common.h"

#ifdef __cplusplus
extern "C" {
#endif

enum {
    GI_CHART_LINE_MARKERS = 0, /* solid line through the points, a marker at each */
    GI_CHART_MARKERS = 1,      /* markers only */
    GI_CHART_DASHED = 2,       /* dashed line, no markers (reference curves) */
    GI_CHART_THIN = 3,         /* thin, faint line with small markers and no legend entry
                                  (the many runs behind a series that carries the legend) */
    GI_CHART_REFERENCE = 4,    /* a reference curve (the path tracer's): grey, no markers, in
                                  greys and dash patterns of its own that no palette colour
                                  shares; `color` k > 0 picks the k-th of them (dark to light),
                                  0 the position among the chart's reference series */
};

typedef struct gi_chart_series {
    const char *label; /* legend text; NULL = "series <k>" */
    const double *x;   /* count values each; may be NULL when count == 0 */
    const double *y;
    uint32_t count;
    int style; /* GI_CHART_* */
    int color; /* 0: colour and marker by position in the array; k > 0: those of position k - 1
                  (so that a method's runs and its front share a look) */
    /* Error bars (the spread of repeats), each NULL or `count` values:
     * a horizontal bar from x_lo[i] to x_hi[i] at y[i] and a vertical one
     * from y_lo[i] to y_hi[i] at x[i], in the series' colour, without a
     * legend entry. A NaN end (or one <= 0 on a log axis) leaves that
     * point's bar out. Bars count toward the axis ranges. */
    const double *x_lo, *x_hi, *y_lo, *y_hi;
} gi_chart_series;

/* Zero means default in every field. */
typedef struct gi_chart_desc {
    const char *title, *x_label, *y_label; /* NULL = none */
    int log_x, log_y;                      /* non-zero: logarithmic axis */
    uint32_t width, height;                /* pixels; 0 = 900 (width), 600 (height); at most 4096 */
    /* Tick marks on the x axis at exactly these values (e.g. the swept
     * values of a parameter), labelled "%g"; NULL or 0: chosen from the
     * range. Values outside the axis range are left out. */
    const double *x_ticks;
    uint32_t x_tick_count;
} gi_chart_desc;

/* Axis ranges. Each axis spans the drawn points and bars, widened by 4 %
 * of the span on each side. The y axis does not magnify noise: a linear
 * y axis spans at least 20 % of its largest magnitude and a logarithmic
 * one at least a factor of 2, so that values 2 % apart fill a tenth of a
 * linear axis instead of all of it. */

/* Renders the chart and writes it to `path` (which must end in ".png") as
 * an 8-bit RGB PNG of width x height pixels. desc may be NULL (all
 * defaults). n may be 0 (empty axes); series may be NULL only then.
 * Errors, each with "path: reason" in err: GI_ERR_INVALID_ARGUMENT (bad
 * style, size, extension, NULL arrays with count > 0), GI_ERR_IO (the file
 * cannot be created or written), GI_ERR_UNSUPPORTED (no EGL context with
 * OpenGL 3.2), GI_ERR_GL (VTK reported an error while drawing; its text),
 * GI_ERR_OUT_OF_MEMORY. */
gi_result gi_chart_write_png(const char *path, const gi_chart_desc *desc,
                             const gi_chart_series *series, uint32_t n, gi_error *err);

/* GI_OK if charts can be rendered in this process (an EGL context with
 * OpenGL 3.2 or newer can be made and VTK draws into it); otherwise
 * GI_ERR_UNSUPPORTED and the reason in err. Renders a tiny chart in memory,
 * so it costs about as much as one chart. */
gi_result gi_chart_available(gi_error *err);

/* The x and y ranges (data units) a chart with these arguments is drawn
 * with (see "Axis ranges" above); for tests and for callers that place
 * annotations. */
void gi_chart_axis_ranges(const gi_chart_desc *desc, const gi_chart_series *series, uint32_t n,
                          double x_range[2], double y_range[2]);

/* How many points of `s` a chart with `desc` draws (see "Points" above). */
uint32_t gi_chart_points_kept(const gi_chart_desc *desc, const gi_chart_series *s);

#ifdef __cplusplus
}
#endif
#endif
