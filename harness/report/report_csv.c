/* runs.csv, frames.csv and curves.csv of a report (report.h): every run
 * a row, every timed frame a row, every point of a convergence curve a row. */
#include "report.h"
#include "report_internal.h"

#include <string.h>

static void csv_field(text *t, const char *s, int last)
{
    int quote = strpbrk(s, ",\"\n") != NULL;
    if (quote) {
        put(t, "\"");
        for (const char *p = s; *p; p++)
            put(t, *p == '"' ? "\"\"" : "%c", *p);
        put(t, "\"");
    } else {
        put(t, "%s", s);
    }
    put(t, last ? "\n" : ",");
}

static void csv_num(text *t, double v, int last)
{
    if (v == v)
        put(t, "%.6g", v);
    put(t, last ? "\n" : ",");
}

/* The last columns of runs.csv: the seed, and what the study's speed
 * against accuracy found for the run (tradeoff.h). */
static const char *const tradeoff_keys[] = {"seed",
                                            "time_to_final_error_s",
                                            "frames_to_final_error",
                                            "speedup_vs_pt",
                                            "speedup_vs_pt_matched",
                                            "speedup_extrapolated",
                                            "speedup_vs_pt_min",
                                            "speedup_vs_pt_max",
                                            "speedup_vs_pt_matched_min",
                                            "speedup_vs_pt_matched_max",
                                            NULL};

/* The columns after those: leaked energy (metrics), memory, the scene's
 * size and an animated run's per-frame summary ("animation"), each a path
 * of up to three keys in the record. */
static const struct {
    const char *column, *k1, *k2, *k3;
} extra_columns[] = {
    {"leaked_energy_full", "metrics", "full", "leaked_energy"},
    {"dark_fraction_full", "metrics", "full", "dark_fraction"},
    {"dark_energy_ref_full", "metrics", "full", "dark_energy_ref"},
    {"leaked_energy_matched", "metrics", "matched", "leaked_energy"},
    {"peak_rss_mib", "peak_rss_mib", NULL, NULL},
    {"peak_rss_prepare_mib", "peak_rss_prepare_mib", NULL, NULL},
    {"data_bytes", "stats", "data_bytes", NULL},
    {"scene_triangles", "scene_triangles", NULL, NULL},
    {"anim_frame_ms_median", "animation", "frame_ms_median", NULL},
    {"anim_relmse_full_mean", "animation", "relmse_full_mean", NULL},
    {"anim_relmse_full_max", "animation", "relmse_full_max", NULL},
    {"anim_relmse_matched_mean", "animation", "relmse_matched_mean", NULL},
    {"anim_leaked_energy_full_mean", "animation", "leaked_energy_full_mean", NULL},
    {"anim_change_method", "animation", "change_method_mean", NULL},
    {"anim_change_ref_full", "animation", "change_ref_full_mean", NULL},
    {"anim_change_ref_matched", "animation", "change_ref_matched_mean", NULL},
    {"anim_flicker_full", "animation", "flicker_full", NULL},
    {"anim_flicker_matched", "animation", "flicker_matched", NULL},
    {"anim_temporal_error_full", "animation", "temporal_error_full_mean", NULL},
    {"anim_noise_floor_full", "animation", "noise_floor_full_mean", NULL},
};
#define EXTRA_COLUMNS (sizeof extra_columns / sizeof extra_columns[0])

void report_write_csv(text *t, json_object *runs)
{
    const char *stages[32], *pstages[32], *stats[64];
    int ns = report_stage_names(runs, stages, 32);
    int np = report_key_names(runs, "prepare_stages", pstages, 32);
    int nst = report_key_names(runs, "stats", stats, 64);
    put(t, "run,scene,method,params,status,reason,renderer,timer,frames,prepare_ms,frame_ms_median,"
           "frame_ms_min,"
           "frame_ms_max");
    for (int k = 0; k < ns; k++)
        put(t, ",stage_%s_ms_median,stage_%s_ms_min,stage_%s_ms_max", stages[k], stages[k],
            stages[k]);
    for (int r = 0; r < 2; r++)
        for (int m = 0; report_metric_keys[m]; m++)
            put(t, ",%s_%s", report_metric_keys[m], r ? "matched" : "full");
    put(t, ",label,width,height");
    for (int k = 0; k < np; k++)
        put(t, ",prepare_%s_ms", pstages[k]);
    for (int k = 0; k < nst; k++)
        put(t, ",stat_%s", stats[k]);
    for (int k = 0; tradeoff_keys[k]; k++)
        put(t, ",%s", tradeoff_keys[k]);
    put(t, ",invocation"); /* the study invocation that timed the run (issue 34) */
    for (size_t k = 0; k < EXTRA_COLUMNS; k++)
        put(t, ",%s", extra_columns[k].column);
    put(t, "\n");
    size_t count = json_object_array_length(runs);
    for (size_t i = 0; i < count; i++) {
        json_object *o = json_object_array_get_idx(runs, i);
        const char *fields[] = {"run",    "scene",  "method",   "params",
                                "status", "reason", "renderer", "timer"};
        for (size_t f = 0; f < sizeof fields / sizeof fields[0]; f++)
            csv_field(t, report_str(o, fields[f]), 0);
        csv_num(t, report_num(o, "frames", NULL, NULL), 0);
        csv_num(t, report_num(o, "prepare_ms", NULL, NULL), 0);
        csv_num(t, report_num(o, "frame_ms", "median", NULL), 0);
        csv_num(t, report_num(o, "frame_ms", "min", NULL), 0);
        csv_num(t, report_num(o, "frame_ms", "max", NULL), 0);
        for (int k = 0; k < ns; k++) {
            csv_num(t, report_num(o, "stages", stages[k], "median"), 0);
            csv_num(t, report_num(o, "stages", stages[k], "min"), 0);
            csv_num(t, report_num(o, "stages", stages[k], "max"), 0);
        }
        for (int r = 0; r < 2; r++)
            for (int m = 0; report_metric_keys[m]; m++)
                csv_num(t, report_num(o, "metrics", r ? "matched" : "full", report_metric_keys[m]),
                        0);
        csv_field(t, report_str(o, "label"), 0);
        csv_num(t, report_num(o, "width", NULL, NULL), 0);
        csv_num(t, report_num(o, "height", NULL, NULL), 0);
        for (int k = 0; k < np; k++)
            csv_num(t, report_num(o, "prepare_stages", pstages[k], NULL), 0);
        for (int k = 0; k < nst; k++)
            csv_num(t, report_num(o, "stats", stats[k], NULL), 0);
        for (int k = 0; tradeoff_keys[k]; k++)
            csv_num(t, report_num(o, tradeoff_keys[k], NULL, NULL), 0);
        csv_field(t, report_str(o, "invocation"), 0);
        for (size_t k = 0; k < EXTRA_COLUMNS; k++)
            csv_num(t, report_num(o, extra_columns[k].k1, extra_columns[k].k2, extra_columns[k].k3),
                    k + 1 == EXTRA_COLUMNS);
    }
}

/* frames.csv: every timed frame of every run (per-frame time of animations). */
void report_write_frames_csv(text *t, json_object *runs)
{
    put(t, "run,label,frame,frame_ms\n");
    size_t count = json_object_array_length(runs);
    for (size_t i = 0; i < count; i++) {
        json_object *o = json_object_array_get_idx(runs, i), *f;
        if (!json_object_object_get_ex(o, "frame_samples_ms", &f) ||
            !json_object_is_type(f, json_type_array))
            continue;
        for (size_t k = 0; k < json_object_array_length(f); k++) {
            csv_field(t, report_str(o, "run"), 0);
            csv_field(t, report_str(o, "label"), 0);
            put(t, "%zu,", k + 1);
            csv_num(t, json_object_get_double(json_object_array_get_idx(f, k)), 1);
        }
    }
}

/* curves.csv: every run's convergence curve (render --curve-ref): the
 * time to the image after each recorded frame and its error. */
void report_write_curves_csv(text *t, json_object *runs)
{
    put(t, "run,method,params,label,seed,frame,time_s,relmse_full,relmse_matched\n");
    size_t count = json_object_array_length(runs);
    for (size_t i = 0; i < count; i++) {
        json_object *o = json_object_array_get_idx(runs, i), *c;
        if (!json_object_object_get_ex(o, "curve", &c) || !json_object_is_type(c, json_type_array))
            continue;
        for (size_t k = 0; k < json_object_array_length(c); k++) {
            json_object *p = json_object_array_get_idx(c, k);
            csv_field(t, report_str(o, "run"), 0);
            csv_field(t, report_str(o, "method"), 0);
            csv_field(t, report_str(o, "params"), 0);
            csv_field(t, report_str(o, "label"), 0);
            csv_num(t, report_num(o, "seed", NULL, NULL), 0);
            csv_num(t, report_num(p, "frame", NULL, NULL), 0);
            csv_num(t, report_num(p, "time_ms", NULL, NULL) / 1000.0, 0);
            csv_num(t, report_num(p, "full", "relmse", NULL), 0);
            csv_num(t, report_num(p, "matched", "relmse", NULL), 1);
        }
    }
}
