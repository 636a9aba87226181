/* Speed against accuracy for one reference set of a study: every run's
 * convergence curve (render --curve-ref: error after frames 1, 2, 4, ...
 * with the time to that image), repeats pooled into a spread, each
 * method's Pareto front, and the path tracer's own curves for full GI and
 * for each bounce limit in use. From them: the error-against-time charts,
 * the equal-error table (speed-up over the full and the bounce-matched
 * path tracer), and the equal-time table (each method's error at the time
 * the path tracer needs for fixed error levels). docs/studies.md, "Speed against accuracy", defines
 * every column. */
#ifndef GIBENCH_TRADEOFF_H
#define GIBENCH_TRADEOFF_H

#include "charts.h"
#include "text.h"

#include <json-c/json.h>
#include <stddef.h>
#include <stdint.h>

#define TRADEOFF_PT_POINTS 32

/* The path tracer's convergence: time (s) to an image of each spp count
 * and its relMSE against the reference of the same bounce limit. Each
 * point is timed `samples` times in one study invocation (issue 34, "one
 * clock per comparison"): t is the median, t_lo and t_hi the spread. */
typedef struct tradeoff_pt_curve {
    uint32_t bounces;
    uint32_t n;
    double t[TRADEOFF_PT_POINTS], e[TRADEOFF_PT_POINTS];
    double t_lo[TRADEOFF_PT_POINTS], t_hi[TRADEOFF_PT_POINTS];
    uint32_t samples[TRADEOFF_PT_POINTS], spp[TRADEOFF_PT_POINTS];
    char invocation[64]; /* the study invocation that timed it ("" unknown) */
} tradeoff_pt_curve;

/* The path tracer's time at relMSE e: log-log interpolation along the
 * curve, beyond its ends slope -1 (relMSE ~ 1/time for an unbiased
 * estimator), *extrapolated set then. NaN without a curve or for e <= 0. */
double tradeoff_pt_time_at(const tradeoff_pt_curve *c, double e, int *extrapolated);

/* One run of the reference set: its record, its bounce count (the
 * method's max_bounces + 1) and the key of its setting (every input but
 * the seed: the runs of one key are repeats). */
typedef struct tradeoff_run {
    json_object *record;
    uint32_t bounces;
    uint64_t setting;
} tradeoff_run;

/* How charts are written: gi_chart_write_png, or a stand-in (tests). */
typedef gi_result (*tradeoff_chart_fn)(const char *path, const gi_chart_desc *desc,
                                       const gi_chart_series *series, uint32_t n, gi_error *err);

/* The tables' note on clocks: "" when every time in the study comes from
 * one invocation; else (gibench study --mix-clocks) each table says which
 * invocations its times come from. */
typedef struct tradeoff_clock_note {
    int mixed; /* the study's timed runs and curves span several invocations */
} tradeoff_clock_note;

/* Writes, through write_chart (NULL: no charts), chart_<name>_error_vs_time.png (and _matched.png
 * when a method has fewer bounces than the full reference) into out_dir, appending the file names
 * to chart_list; appends the tables to md; adds to each ok record: time_to_final_error_s,
 * pt_time_at_equal_error_s, speedup_vs_pt, speedup_vs_pt_matched, speedup_extrapolated (1: the path
 * tracer's time is extrapolated beyond its measured curve) and the speed-ups' spread from the
 * curve's (speedup_vs_pt_min/_max, speedup_vs_pt_matched_min/_max). `matched` holds the
 * bounce-limited curves (matched_n of them). With clocks->mixed each table names the invocations
 * its times come from. */
void tradeoff_report(const char *out_dir, const char *name, const tradeoff_pt_curve *full,
                     const tradeoff_pt_curve *matched, uint32_t matched_n, const tradeoff_run *runs,
                     uint32_t run_n, tradeoff_chart_fn write_chart, json_object *chart_list,
                     gi_text *md, const tradeoff_clock_note *clocks);

#endif
