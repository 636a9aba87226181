/* report.md of a report (report.h), for results/: the header, the runs,
 * their stage timings, the images and charts, and the speed-against-accuracy
 * text. */
#include "report_internal.h"

#include <string.h>

/* Names from users as report.md text and code spans (text.h). */
#define md_text gi_text_md
#define md_code gi_text_md_code

/* A file name as a link target: anything but [A-Za-z0-9._~/-] as %XX, so
 * that a name cannot close the link or open markup. */
static void md_url(text *t, const char *s)
{
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        if ((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
            strchr("._~/-", c))
            put(t, "%c", c);
        else
            put(t, "%%%02X", c);
    }
}

/* ![alt](file) with both escaped. */
static void md_image(text *t, const char *alt, const char *file)
{
    put(t, "![");
    md_text(t, alt);
    put(t, "](");
    md_url(t, file);
    put(t, ")");
}

static void md_num(text *t, double v)
{
    if (v == v)
        put(t, " %.4g |", v);
    else
        put(t, " – |");
}

/* The title and the list of what the report was made with. */
static void md_header(text *t, json_object *meta)
{
    static const char *const head[][2] = {{"- GL renderer: ", "renderer"},
                                          {"- reference: ", "reference"},
                                          {"- machine: ", "machine"},
                                          {"- date: ", "date"}};
    put(t, "# ");
    md_text(t, report_str(meta, "title"));
    put(t, "\n\n- command: ");
    md_code(t, report_str(meta, "command"));
    put(t, "\n");
    for (size_t k = 0; k < sizeof head / sizeof head[0]; k++) {
        put(t, "%s", head[k][0]);
        md_text(t, report_str(meta, head[k][1]));
        put(t, "\n");
    }
    put(t, "\n");
}

/* The reference and each run's image and error map, as links. */
static void md_images(text *t, const char *dir, json_object *runs, json_object *meta)
{
    size_t count = json_object_array_length(runs);
    put(t, "\nImages (tonemapped at the report's exposure) and relative error against the full "
           "reference "
           "(log scale, colour bar in each map):\n\n");
    const char *ref_png = report_str(meta, "reference_png");
    if (report_exists_in(dir, ref_png)) {
        put(t, "reference: ");
        md_image(t, "reference", ref_png);
        put(t, "\n\n");
    }
    for (size_t i = 0; i < count; i++) {
        json_object *o = json_object_array_get_idx(runs, i);
        int png = report_exists_in(dir, report_str(o, "png")),
            heat = report_exists_in(dir, report_str(o, "heatmap"));
        if (!png && !heat)
            continue;
        md_text(t, report_str(o, "run"));
        put(t, ":");
        if (png) {
            put(t, " ");
            md_image(t, report_str(o, "run"), report_str(o, "png"));
        }
        if (heat) {
            put(t, " ");
            md_image(t, "error", report_str(o, "heatmap"));
        }
        put(t, "\n\n");
    }
}

void report_write_md(text *t, const char *dir, json_object *runs, json_object *meta)
{
    md_header(t, meta);
    put(t, "Errors are against the full-GI reference (\"full\") and against the reference limited "
           "to the "
           "method's own bounce count (\"matched\"), so that method error and missing light are "
           "reported "
           "apart. Times are medians over the timed frames; on a software renderer only ratios "
           "within one "
           "run mean anything.\n\n");
    put(t, "| run | method | params | status | frame ms | prepare ms | relMSE full | relMSE "
           "matched | HDR-FLIP full | FLIP full "
           "| SSIM full | mean lum. diff %% |\n");
    put(t, "|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    size_t count = json_object_array_length(runs);
    for (size_t i = 0; i < count; i++) {
        json_object *o = json_object_array_get_idx(runs, i);
        const char *status = report_str(o, "status");
        put(t, "| ");
        md_text(t, report_str(o, "run"));
        put(t, " | ");
        md_text(t, report_str(o, "method"));
        put(t, " | ");
        md_code(t, report_str(o, "params"));
        put(t, " | ");
        md_text(t, status);
        if (strcmp(status, "ok")) {
            put(t, ": ");
            md_text(t, report_str(o, "reason"));
        }
        put(t, " |");
        md_num(t, report_num(o, "frame_ms", "median", NULL));
        md_num(t, report_num(o, "prepare_ms", NULL, NULL));
        md_num(t, report_num(o, "metrics", "full", "relmse"));
        md_num(t, report_num(o, "metrics", "matched", "relmse"));
        md_num(t, report_num(o, "metrics", "full", "hdr_flip"));
        md_num(t, report_num(o, "metrics", "full", "flip"));
        md_num(t, report_num(o, "metrics", "full", "ssim"));
        md_num(t, report_num(o, "metrics", "full", "mean_lum_diff_pct"));
        put(t, "\n");
    }
    const char *stages[32];
    int ns = report_stage_names(runs, stages, 32);
    if (ns > 0) {
        put(t, "\nStage timings in ms, median (min – max) over the timed frames:\n\n| run |");
        for (int k = 0; k < ns; k++) {
            put(t, " ");
            md_text(t, stages[k]);
            put(t, " |");
        }
        put(t, " frame |\n|---|");
        for (int k = 0; k <= ns; k++)
            put(t, "---:|");
        put(t, "\n");
        for (size_t i = 0; i < count; i++) {
            json_object *o = json_object_array_get_idx(runs, i);
            if (strcmp(report_str(o, "status"), "ok"))
                continue;
            put(t, "| ");
            md_text(t, report_str(o, "run"));
            put(t, " |");
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
    md_images(t, dir, runs, meta);
    json_object *charts;
    if (json_object_object_get_ex(meta, "charts", &charts)) {
        put(t, "\n");
        for (size_t i = 0; i < json_object_array_length(charts); i++) {
            const char *c = json_object_get_string(json_object_array_get_idx(charts, i));
            if (report_exists_in(dir, c)) {
                md_image(t, c, c);
                put(t, "\n\n");
            }
        }
    }
    json_object *extra;
    if (json_object_object_get_ex(meta, "markdown", &extra))
        put(t, "\n%s\n", json_object_get_string(extra));
    if (json_object_object_get_ex(meta, "animation_markdown", &extra) &&
        *json_object_get_string(extra))
        put(t, "\n## Animated runs, frame by frame\n\n%s\n", json_object_get_string(extra));
}
