/* The report's section on animated runs compared frame by frame
 * (docs/studies.md, "Animated runs, frame by frame"): a table of every such run and, per scene,
 * charts of relMSE, frame time and frame-to-frame change per frame. */
#define _POSIX_C_SOURCE 200809L
#include "study_internal.h"

#include "charts.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A number of a record at a dotted path ("animation.flicker_full"); NaN if absent. */
static double anim_num(json_object *rec, const char *key)
{
    json_object *a, *v;
    if (!json_object_object_get_ex(rec, "animation", &a) ||
        !json_object_object_get_ex(a, key, &v) || !v)
        return NAN;
    return json_object_get_double(v);
}

static void md_cell(gi_text *md, double v)
{
    if (isfinite(v))
        gi_text_put(md, " %.4g |", v);
    else
        gi_text_put(md, " – |");
}

/* Series of the animation charts: y per frame of one list of the record's
 * "animation" against the frame index (from 0). */
typedef struct anim_series {
    char label[200];
    double *x, *y;
    uint32_t n;
} anim_series;

static int anim_series_from(json_object *rec, const char *key, const char *label, anim_series *out)
{
    json_object *a, *list;
    memset(out, 0, sizeof *out);
    if (!json_object_object_get_ex(rec, "animation", &a) ||
        !json_object_object_get_ex(a, key, &list) || !json_object_is_type(list, json_type_array))
        return 0;
    uint32_t n = (uint32_t)json_object_array_length(list);
    out->x = calloc(n + 1, sizeof *out->x);
    out->y = calloc(n + 1, sizeof *out->y);
    if (!out->x || !out->y) {
        free(out->x), free(out->y);
        return 0;
    }
    /* frames without a value (a warm-up frame's time, the first frame's change) are left out */
    uint32_t k = 0;
    for (uint32_t i = 0; i < n; i++) {
        json_object *e = json_object_array_get_idx(list, i);
        double y = e ? json_object_get_double(e) : NAN;
        if (!isfinite(y))
            continue;
        out->x[k] = i;
        out->y[k++] = y;
    }
    out->n = k;
    snprintf(out->label, sizeof out->label, "%s", label);
    return 1;
}

/* What the table's columns mean, and its header. */
static void anim_table_head(gi_text *md)
{
    gi_text_put(
        md,
        "Every frame of an animated run (`\"animate\"` with comparison on) against references "
        "rendered at that frame's scene time. relMSE: mean over the frames (max); leaked energy: "
        "the "
        "method's light where the full reference is dark (below 1 %% of its mean luminance), as a "
        "share of the reference's light, mean over the frames. Change: the mean absolute "
        "frame-to-frame difference, per pixel and channel (linear radiance), of the method's "
        "frames "
        "and of the references' frames; **flicker** = the method's change − the reference's (> 0: "
        "the method changes more from frame to frame than the light does). Temporal error: the "
        "mean "
        "of |method's change − reference's change| per pixel and channel. Noise floor: the mean "
        "absolute difference between two full-GI references of the same frame with different "
        "seeds; "
        "the references of all frames share one seed, so their noise is correlated from frame to "
        "frame where nothing moves, and the noise floor bounds the noise's share of the "
        "reference's "
        "change from above: a flicker smaller than it is not told apart from reference noise.\n\n");
    gi_text_put(
        md,
        "| run | method | params | label | frames | fps | frame ms (median) | relMSE full mean | "
        "relMSE full max | relMSE matched mean | leaked energy | change method | change reference "
        "| flicker full | flicker matched | temporal error | noise floor |\n"
        "|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
}

/* The table's row of one animated run: its metrics, or its status and why. */
static void anim_table_row(gi_text *md, const study_run *r)
{
    json_object *v;
    const char *status =
        json_object_object_get_ex(r->record, "status", &v) ? json_object_get_string(v) : "?";
    char params[600] = "";
    for (uint32_t k = 0; k < r->spec.param_count; k++) {
        size_t used = strlen(params);
        snprintf(params + used, sizeof params - used, "%s%s", k ? "," : "", r->spec.params[k]);
    }
    /* names, labels and reasons come from users: escaped (text.h) */
    gi_text_put(md, "| ");
    gi_text_md(md, r->id);
    gi_text_put(md, " | ");
    gi_text_md(md, r->spec.method);
    gi_text_put(md, " | ");
    gi_text_md_code(md, params[0] ? params : "(defaults)");
    gi_text_put(md, " | ");
    gi_text_md(md, r->spec.label ? r->spec.label : "");
    gi_text_put(md, " |");
    if (strcmp(status, "ok")) {
        const char *reason =
            json_object_object_get_ex(r->record, "reason", &v) ? json_object_get_string(v) : "";
        gi_text_put(md, " ");
        gi_text_md(md, status);
        gi_text_put(md, ": ");
        gi_text_md(md, reason);
        gi_text_put(md, " | | | | | | | | | | | | |\n");
        return;
    }
    gi_text_put(md, " %u | %g |", r->frame_ref_n, (double)r->spec.animate_fps);
    const char *keys[] = {"frame_ms_median",         "relmse_full_mean",
                          "relmse_full_max",         "relmse_matched_mean",
                          "leaked_energy_full_mean", "change_method_mean",
                          "change_ref_full_mean",    "flicker_full",
                          "flicker_matched",         "temporal_error_full_mean",
                          "noise_floor_full_mean"};
    for (size_t k = 0; k < sizeof keys / sizeof keys[0]; k++)
        md_cell(md, anim_num(r->record, keys[k]));
    gi_text_put(md, "\n");
}

/* A run's series label: the method, its parameters and its label. */
static void anim_run_label(const study_run *r, char *label, size_t size)
{
    size_t used = (size_t)snprintf(label, size, "%s", r->spec.method);
    for (uint32_t k = 0; k < r->spec.param_count && used < size; k++)
        used += (size_t)snprintf(label + used, size - used, " %s", r->spec.params[k]);
    if (r->spec.label && used < size)
        snprintf(label + used, size - used, " [%s]", r->spec.label);
}

/* Appends the series of record list `key` (drawn as `style`) when the
 * record has it. */
static void anim_add_series(json_object *rec, const char *key, const char *label, int style,
                            anim_series *ser, gi_chart_series *cs, uint32_t *n)
{
    if (anim_series_from(rec, key, label, &ser[*n])) {
        cs[*n] = (gi_chart_series){ser[*n].label, ser[*n].x, ser[*n].y, ser[*n].n, style, 0,
                                   NULL,          NULL,      NULL,      NULL};
        (*n)++;
    }
}

/* The series of chart c (0 relMSE, 1 frame time, 2 change) of scene sc:
 * one per finished animated run (at most 30), and on the change chart the
 * references' own change and noise floor once per frame rate. */
static uint32_t anim_chart_series(const study *st, uint32_t sc, int c, anim_series *ser,
                                  gi_chart_series *cs)
{
    uint32_t n = 0;
    double seen_fps[16];
    uint32_t nseen = 0;
    for (uint32_t i = 0; i < st->run_count && n < 30; i++) {
        const study_run *r = &st->runs[i];
        json_object *v;
        if (!r->frame_ref_n || !r->record || r->scene_index != (int)sc ||
            !json_object_object_get_ex(r->record, "status", &v) ||
            strcmp(json_object_get_string(v), "ok"))
            continue;
        char label[200];
        anim_run_label(r, label, sizeof label);
        const char *key = c == 0 ? "relmse_full" : c == 1 ? "frame_ms" : "change_method";
        anim_add_series(r->record, key, label, GI_CHART_LINE_MARKERS, ser, cs, &n);
        /* the references' own change and noise floor, once per frame rate */
        uint32_t q = 0;
        while (q < nseen && seen_fps[q] != r->spec.animate_fps)
            q++;
        if (c == 2 && q == nseen && nseen < 16 && n < 30) {
            seen_fps[nseen++] = r->spec.animate_fps;
            char l2[200];
            snprintf(l2, sizeof l2, "reference change (%g fps)", (double)r->spec.animate_fps);
            anim_add_series(r->record, "change_ref_full", l2, GI_CHART_DASHED, ser, cs, &n);
            snprintf(l2, sizeof l2, "reference noise floor, two seeds (%g fps)",
                     (double)r->spec.animate_fps);
            anim_add_series(r->record, "noise_floor_full", l2, GI_CHART_DASHED, ser, cs, &n);
        }
    }
    return n;
}

/* Chart c (0 relMSE, 1 frame time, 2 change) of scene sc, written into
 * out_dir and listed when any run has the series. */
static void anim_chart(const study *st, const char *out_dir, uint32_t sc, int c,
                       json_object *chart_list)
{
    const char *what[3] = {"relmse", "frame_ms", "change"};
    const char *ylab[3] = {"relMSE against the full-GI reference of the frame",
                           "frame time (ms; update + render)",
                           "mean |frame - previous frame| (linear, per pixel and channel)"};
    anim_series ser[32];
    gi_chart_series cs[32];
    uint32_t n = anim_chart_series(st, sc, c, ser, cs);
    if (n) {
        char file[512], path[4700], title[512];
        snprintf(file, sizeof file, "chart_%s_anim_%s.png", st->scenes[sc].stem, what[c]);
        snprintf(path, sizeof path, "%s/%s", out_dir, file);
        snprintf(title, sizeof title, "%s, animated: %s per frame", st->scenes[sc].stem,
                 c == 0   ? "relMSE"
                 : c == 1 ? "frame time"
                          : "frame-to-frame change");
        gi_chart_desc desc = {title, "frame index (from 0)", ylab[c], 0, c == 0, 0, 0, NULL, 0};
        gi_error err;
        if (gi_chart_write_png(path, &desc, cs, n, &err) == GI_OK)
            json_object_array_add(chart_list, json_object_new_string(file));
        else
            fprintf(stderr, "gibench: warning: chart %s not written: %s\n", file, err.text);
    }
    for (uint32_t k = 0; k < n; k++) {
        free(ser[k].x);
        free(ser[k].y);
    }
}

/* Animated runs compared frame by frame (docs/studies.md, "Animated runs, frame by frame"): a
 * table of every such run (markdown, into meta "animation_markdown") and,
 * per scene, charts of relMSE, frame time and frame-to-frame change
 * against the frame index, one series per run. */
void study_animation_report(study *st, const char *out_dir, json_object *meta,
                            json_object *chart_list)
{
    gi_text md = {0};
    int any = 0;
    for (uint32_t i = 0; i < st->run_count; i++)
        any |= st->runs[i].frame_ref_n > 0 && st->runs[i].record;
    if (!any) {
        json_object_object_add(meta, "animation_markdown", json_object_new_string(""));
        return;
    }
    anim_table_head(&md);
    for (uint32_t i = 0; i < st->run_count; i++)
        if (st->runs[i].frame_ref_n && st->runs[i].record)
            anim_table_row(&md, &st->runs[i]);
    gi_text_put(&md, "\n");
    json_object_object_add(meta, "animation_markdown", json_object_new_string(md.s ? md.s : ""));
    free(md.s);

    /* charts, per scene */
    for (uint32_t sc = 0; sc < st->scene_count; sc++)
        for (int c = 0; c < 3; c++)
            anim_chart(st, out_dir, sc, c, chart_list);
}
