/* report.md of a report (report.h), for results/: the header, the runs,
 * their stage timings, the images and charts, and the speed-against-accuracy
 * text. */
#include "report_internal.h"

#include <string.h>

static void md_num(text *t, double v)
{
    if (v == v)
        put(t, " %.4g |", v);
    else
        put(t, " – |");
}

void report_write_md(text *t, const char *dir, json_object *runs, json_object *meta)
{
    put(t, "# %s\n\n", report_str(meta, "title"));
    put(t, "- command: `%s`\n", report_str(meta, "command"));
    put(t, "- GL renderer: %s\n", report_str(meta, "renderer"));
    put(t, "- reference: %s\n", report_str(meta, "reference"));
    put(t, "- machine: %s\n", report_str(meta, "machine"));
    put(t, "- date: %s\n\n", report_str(meta, "date"));
    put(t, "Errors are against the full-GI reference (\"full\") and against the reference limited "
           "to the "
           "method's own bounce count (\"matched\"), so that method error and missing light are "
           "reported "
           "apart. Times are medians over the timed frames; on a software renderer only ratios "
           "within one "
           "run mean anything.\n\n");
    put(t, "| run | method | params | status | frame ms | prepare ms | relMSE full | relMSE "
           "matched | FLIP full "
           "| SSIM full | mean lum. diff %% |\n");
    put(t, "|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|\n");
    size_t count = json_object_array_length(runs);
    for (size_t i = 0; i < count; i++) {
        json_object *o = json_object_array_get_idx(runs, i);
        const char *status = report_str(o, "status");
        put(t, "| %s | %s | `%s` | %s%s%s |", report_str(o, "run"), report_str(o, "method"),
            report_str(o, "params"), status, strcmp(status, "ok") ? ": " : "",
            strcmp(status, "ok") ? report_str(o, "reason") : "");
        md_num(t, report_num(o, "frame_ms", "median", NULL));
        md_num(t, report_num(o, "prepare_ms", NULL, NULL));
        md_num(t, report_num(o, "metrics", "full", "relmse"));
        md_num(t, report_num(o, "metrics", "matched", "relmse"));
        md_num(t, report_num(o, "metrics", "full", "flip"));
        md_num(t, report_num(o, "metrics", "full", "ssim"));
        md_num(t, report_num(o, "metrics", "full", "mean_lum_diff_pct"));
        put(t, "\n");
    }
    const char *stages[32];
    int ns = report_stage_names(runs, stages, 32);
    if (ns > 0) {
        put(t, "\nStage timings in ms, median (min – max) over the timed frames:\n\n| run |");
        for (int k = 0; k < ns; k++)
            put(t, " %s |", stages[k]);
        put(t, " frame |\n|---|");
        for (int k = 0; k <= ns; k++)
            put(t, "---:|");
        put(t, "\n");
        for (size_t i = 0; i < count; i++) {
            json_object *o = json_object_array_get_idx(runs, i);
            if (strcmp(report_str(o, "status"), "ok"))
                continue;
            put(t, "| %s |", report_str(o, "run"));
            for (int k = 0; k <= ns; k++) {
                const char *k1 = k < ns ? "stages" : "frame_ms", *k2 = k < ns ? stages[k] : NULL;
                double med =
                    k < ns ? report_num(o, k1, k2, "median") : report_num(o, k1, "median", NULL);
                double mn = k < ns ? report_num(o, k1, k2, "min") : report_num(o, k1, "min", NULL);
                double mx = k < ns ? report_num(o, k1, k2, "max") : report_num(o, k1, "max", NULL);
                if (med == med)
                    put(t, " %.4g (%.4g – %.4g) |", med, mn, mx);
                else
                    put(t, " – |");
            }
            put(t, "\n");
        }
    }
    put(t, "\nImages (tonemapped at the report's exposure) and relative error against the full "
           "reference "
           "(log scale, colour bar in each map):\n\n");
    const char *ref_png = report_str(meta, "reference_png");
    if (report_exists_in(dir, ref_png))
        put(t, "reference: ![reference](%s)\n\n", ref_png);
    for (size_t i = 0; i < count; i++) {
        json_object *o = json_object_array_get_idx(runs, i);
        int png = report_exists_in(dir, report_str(o, "png")),
            heat = report_exists_in(dir, report_str(o, "heatmap"));
        if (!png && !heat)
            continue;
        put(t, "%s:", report_str(o, "run"));
        if (png)
            put(t, " ![%s](%s)", report_str(o, "run"), report_str(o, "png"));
        if (heat)
            put(t, " ![error](%s)", report_str(o, "heatmap"));
        put(t, "\n\n");
    }
    json_object *charts;
    if (json_object_object_get_ex(meta, "charts", &charts)) {
        put(t, "\n");
        for (size_t i = 0; i < json_object_array_length(charts); i++) {
            const char *c = json_object_get_string(json_object_array_get_idx(charts, i));
            if (report_exists_in(dir, c))
                put(t, "![%s](%s)\n\n", c, c);
        }
    }
    json_object *extra;
    if (json_object_object_get_ex(meta, "markdown", &extra))
        put(t, "\n%s\n", json_object_get_string(extra));
    if (json_object_object_get_ex(meta, "animation_markdown", &extra) &&
        *json_object_get_string(extra))
        put(t, "\n## Animated runs, frame by frame\n\n%s\n", json_object_get_string(extra));
}
