/* A study's charts: per reference set the error-against-time charts, the
 * speed-ups against the path tracer and the equal-error and equal-time
 * tables (tradeoff.h), and the study's own "charts" (y against x over the
 * finished runs' records, docs/studies.md "gibench study"). */
#define _POSIX_C_SOURCE 200809L
#include "study_internal.h"

#include "charts.h"
#include "gi/cache.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Per reference set: the error-against-time charts with every run's
 * convergence curve, the Pareto fronts and the path tracer's curves, and
 * the equal-error and equal-time tables (tradeoff.h). */
/* pt_curves.csv: every point of the path tracer's curves with its timed
 * spread and the invocation that timed it (issue 34). */
static void write_pt_curves(const study *st, const char *out_dir)
{
    char path[4200];
    snprintf(path, sizeof path, "%s/pt_curves.csv", out_dir);
    gi_text t = {0};
    gi_text_put(&t, "reference_set,bounces,spp,relmse,time_s_median,time_s_min,time_s_max,"
                    "samples,invocation\n");
    for (uint32_t ri = 0; ri < st->ref_count; ri++) {
        const study_ref *sc = &st->refs[ri];
        for (uint32_t c = 0; c <= sc->matched_count && !sc->frame_only; c++) {
            const tradeoff_pt_curve *cv = c ? &sc->pt_matched[c - 1] : &sc->pt_full;
            for (uint32_t k = 0; k < cv->n; k++)
                gi_text_put(&t, "\"%s\",%u,%u,%.6g,%.6g,%.6g,%.6g,%u,%s\n", sc->name, cv->bounces,
                            cv->spp[k], cv->e[k], cv->t[k], cv->t_lo[k], cv->t_hi[k],
                            cv->samples[k], cv->invocation);
        }
    }
    gi_error err;
    if (gi_file_write_atomic(path, t.s ? t.s : "", t.s ? strlen(t.s) : 0, &err) != GI_OK)
        fprintf(stderr, "study: %s\n", err.text);
    free(t.s);
}

void study_charts_and_speedups(study *st, const char *out_dir, json_object *meta,
                               json_object *chart_list, int mixed)
{
    tradeoff_clock_note clocks = {mixed};
    if (st->conv_n > 0)
        write_pt_curves(st, out_dir);
    gi_text md = {0};
    tradeoff_run *tr = calloc(st->run_count + 1, sizeof *tr);
    for (uint32_t ri = 0; ri < st->ref_count && tr; ri++) {
        study_ref *sc = &st->refs[ri];
        if (sc->frame_only)
            continue; /* animation frames: the animation section reports them */
        uint32_t n = 0;
        /* animated runs have no convergence curve (each frame is a new image) */
        for (uint32_t i = 0; i < st->run_count; i++)
            if (st->runs[i].ref_index == (int)ri && st->runs[i].record &&
                st->runs[i].spec.animate_fps <= 0)
                tr[n++] =
                    (tradeoff_run){st->runs[i].record, st->runs[i].bounces, st->runs[i].setting};
        tradeoff_report(out_dir, sc->name, &sc->pt_full, sc->pt_matched, sc->matched_count, tr, n,
                        gi_chart_write_png, chart_list, &md, &clocks);
    }
    free(tr);
    json_object_object_add(meta, "markdown", json_object_new_string(md.s ? md.s : ""));
    free(md.s);
}

/* A field of a run record by name: a top-level key ("label", "run",
 * "prepare_ms", "frame_samples_ms"), a dotted path ("stats.ratio",
 * "metrics.matched.relmse", "stages.render.median", "prepare_stages.compress")
 * or "params.K", the value of parameter K in the full parameter string.
 * Returns a new reference (json_object_put it) or NULL. */
static json_object *record_field(json_object *rec, const char *name)
{
    json_object *v;
    if (!strncmp(name, "params.", 7)) {
        const char *ps = json_object_object_get_ex(rec, "params_full", &v) ||
                                 json_object_object_get_ex(rec, "params", &v)
                             ? json_object_get_string(v)
                             : "";
        size_t kl = strlen(name + 7);
        for (const char *p = ps; p && *p; p = strchr(p, ',') ? strchr(p, ',') + 1 : NULL) {
            if (!strncmp(p, name + 7, kl) && p[kl] == '=') {
                const char *val = p + kl + 1, *end = strchr(val, ',');
                size_t n = end ? (size_t)(end - val) : strlen(val);
                return json_object_new_string_len(val, (int)n);
            }
        }
        return NULL;
    }
    char buf[256];
    snprintf(buf, sizeof buf, "%s", name);
    json_object *o = rec;
    for (char *save = NULL, *tok = strtok_r(buf, ".", &save); tok;
         tok = strtok_r(NULL, ".", &save)) {
        if (!o || !json_object_object_get_ex(o, tok, &o))
            return NULL;
    }
    return json_object_get(o);
}

/* The number a field holds (a number, or text that is one); NaN otherwise. */
static double field_num(json_object *f)
{
    if (!f)
        return NAN;
    if (json_object_is_type(f, json_type_double) || json_object_is_type(f, json_type_int))
        return json_object_get_double(f);
    if (json_object_is_type(f, json_type_string)) {
        char *end;
        const char *s = json_object_get_string(f);
        double d = strtod(s, &end);
        return end != s && *end == '\0' ? d : NAN;
    }
    return NAN;
}

/* Whether a record's field equals a "where" value (numerically when both are numbers). */
static int field_equals(json_object *rec, const char *name, json_object *want)
{
    json_object *f = record_field(rec, name);
    int eq = 0;
    if (f) {
        double a = field_num(f), b = field_num(want);
        eq = isfinite(a) && isfinite(b)
                 ? a == b
                 : !strcmp(json_object_get_string(f), json_object_get_string(want));
    }
    json_object_put(f);
    return eq;
}

static int cmp_double_asc(const void *a, const void *b)
{
    double p = *(const double *)a, q = *(const double *)b;
    return (p > q) - (p < q);
}

static int cmp_point(const void *a, const void *b)
{
    const double *p = a, *q = b;
    return (p[0] > q[0]) - (p[0] < q[0]);
}

/* Whether the runs name more than one GL renderer. */
static int renderers_mixed(json_object *runs)
{
    size_t nr = json_object_array_length(runs);
    const char *renderer0 = NULL;
    int mixed = 0;
    for (size_t i = 0; i < nr; i++) {
        json_object *rec = json_object_array_get_idx(runs, i), *r;
        const char *rn =
            json_object_object_get_ex(rec, "renderer", &r) ? json_object_get_string(r) : "";
        if (!renderer0)
            renderer0 = rn;
        mixed |= strcmp(renderer0, rn) != 0;
    }
    return mixed;
}

/* The fields one user chart draws, as the study file names them. */
typedef struct user_chart {
    const char *file, *xf, *yf, *sf; /* sf: the "series" field, or NULL */
    json_object *where;              /* or NULL */
} user_chart;

/* One chart's series as the runs fill them: (x, y) pairs per label. */
typedef struct chart_points {
    char *labels[32];
    double *pts[32]; /* (x, y) pairs */
    uint32_t counts[32], ns;
    int listed[32]; /* series drawn from a list field */
} chart_points;

/* The series a record's points join: the run (a list y without "series"),
 * the "series" field's value, or else the y field's name; with the
 * renderer where the runs were timed under several. */
static void series_label(const user_chart *uc, json_object *rec, int is_list, int mixed,
                         char *label, size_t size)
{
    if (is_list && !uc->sf)
        snprintf(label, size, "%s", json_object_get_string(json_object_object_get(rec, "run")));
    else if (uc->sf) {
        json_object *s = record_field(rec, uc->sf);
        const char *leaf = strrchr(uc->sf, '.') ? strrchr(uc->sf, '.') + 1 : uc->sf;
        snprintf(label, size, "%s=%s", leaf, s ? json_object_get_string(s) : "?");
        json_object_put(s);
    } else
        snprintf(label, size, "%s", uc->yf);
    json_object *rn;
    if (mixed && json_object_object_get_ex(rec, "renderer", &rn)) {
        size_t used = strlen(label);
        snprintf(label + used, size - used, " [%s]", json_object_get_string(rn));
    }
}

/* Adds one finished run's points to its series (a new series while there
 * are fewer than 32): (x, y), or (position, value) for each element of a
 * list y. */
static void add_run_points(chart_points *p, const user_chart *uc, json_object *rec, int mixed)
{
    json_object *y = record_field(rec, uc->yf);
    int is_list = y && json_object_is_type(y, json_type_array);
    char label[256];
    series_label(uc, rec, is_list, mixed, label, sizeof label);
    uint32_t k = 0;
    while (k < p->ns && strcmp(p->labels[k], label))
        k++;
    if (k == p->ns) {
        if (p->ns == 32) {
            json_object_put(y);
            return;
        }
        p->labels[p->ns] = strdup(label);
        p->pts[p->ns] = calloc((size_t)2 * MAX_RUNS, sizeof(double));
        p->ns++;
    }
    if (is_list) {
        p->listed[k] = 1;
        for (size_t j = 0; j < json_object_array_length(y) && p->counts[k] < MAX_RUNS && p->pts[k];
             j++) {
            if (!json_object_array_get_idx(y, j))
                continue; /* null: no value at this position (a warm-up frame, frame 0's
                             change) */
            p->pts[k][2 * p->counts[k]] = (double)(j + 1);
            p->pts[k][2 * p->counts[k] + 1] =
                json_object_get_double(json_object_array_get_idx(y, j));
            p->counts[k]++;
        }
    } else if (p->pts[k] && p->counts[k] < MAX_RUNS) {
        json_object *x = record_field(rec, uc->xf);
        p->pts[k][2 * p->counts[k]] = field_num(x);
        p->pts[k][2 * p->counts[k] + 1] = field_num(y);
        p->counts[k]++;
        json_object_put(x);
    }
    json_object_put(y);
}

/* The points of every finished run that matches the chart's "where". */
static void collect_points(chart_points *p, const user_chart *uc, json_object *runs, int mixed)
{
    size_t nr = json_object_array_length(runs);
    for (size_t i = 0; i < nr; i++) {
        json_object *rec = json_object_array_get_idx(runs, i), *v;
        if (!json_object_object_get_ex(rec, "status", &v) ||
            strcmp(json_object_get_string(v), "ok"))
            continue;
        int match = 1;
        if (uc->where) {
            json_object_object_foreach(uc->where, k, want) match &= field_equals(rec, k, want);
        }
        if (!match)
            continue;
        add_run_points(p, uc, rec, mixed);
    }
}

/* Series k's points sorted by x, and those at one x merged into
 * xy[0..3] = x, median y, min y, max y; returns their number and sets
 * *spread when any merged point has a min-max spread. */
static uint32_t merge_points(chart_points *p, uint32_t k, double *xy[4], int *spread)
{
    if (p->pts[k])
        qsort(p->pts[k], p->counts[k], 2 * sizeof(double), cmp_point);
    for (int a = 0; a < 4; a++)
        xy[a] = malloc((p->counts[k] + 1) * sizeof(double));
    uint32_t m = 0;
    *spread = 0;
    for (uint32_t j = 0; j < p->counts[k] && xy[0] && xy[1] && xy[2] && xy[3];) {
        uint32_t e = j + 1;
        while (!p->listed[k] && e < p->counts[k] && p->pts[k][2 * e] == p->pts[k][2 * j])
            e++;
        double ys[MAX_RUNS];
        for (uint32_t q = j; q < e; q++)
            ys[q - j] = p->pts[k][2 * q + 1];
        qsort(ys, e - j, sizeof(double), cmp_double_asc);
        uint32_t cnt = e - j;
        xy[0][m] = p->pts[k][2 * j];
        xy[1][m] = cnt % 2 ? ys[cnt / 2] : 0.5 * (ys[cnt / 2 - 1] + ys[cnt / 2]);
        xy[2][m] = ys[0];
        xy[3][m] = ys[cnt - 1];
        *spread |= cnt > 1 && ys[cnt - 1] > ys[0];
        m++;
        j = e;
    }
    return m;
}

/* Draws the chart into out_dir and lists it, or warns why not. */
static void write_user_chart(json_object *c, const user_chart *uc, const char *out_dir,
                             const gi_chart_series *series, uint32_t ns, const double *ticks,
                             uint32_t tick_n, int any_list, json_object *chart_list)
{
    json_object *v;
    const char *title =
        json_object_object_get_ex(c, "title", &v) ? json_object_get_string(v) : uc->file;
    const char *xl =
        json_object_object_get_ex(c, "x_label", &v) ? json_object_get_string(v) : uc->xf;
    const char *yl =
        json_object_object_get_ex(c, "y_label", &v) ? json_object_get_string(v) : uc->yf;
    int lx = json_object_object_get_ex(c, "log_x", &v) && json_object_get_boolean(v);
    int ly = json_object_object_get_ex(c, "log_y", &v) && json_object_get_boolean(v);
    /* ticks at the swept values when there are few (at most 12) */
    gi_chart_desc desc = {title,
                          xl,
                          yl,
                          lx,
                          ly,
                          0,
                          0,
                          any_list || tick_n > 12 ? NULL : ticks,
                          any_list || tick_n > 12 ? 0 : tick_n};
    char path[4700];
    snprintf(path, sizeof path, "%s/%s", out_dir, uc->file);
    gi_error err;
    if (ns == 0)
        fprintf(stderr, "gibench: warning: chart %s: no finished run matches\n", uc->file);
    else if (gi_chart_write_png(path, &desc, series, ns, &err) == GI_OK)
        json_object_array_add(chart_list, json_object_new_string(uc->file));
    else
        fprintf(stderr, "gibench: warning: chart %s not written: %s\n", uc->file, err.text);
}

/* One chart of the study's "charts" list. */
static void user_chart_draw(json_object *c, const char *out_dir, json_object *runs, int mixed,
                            json_object *chart_list)
{
    json_object *v;
    user_chart uc = {0};
    uc.file = json_object_get_string(json_object_object_get(c, "file"));
    uc.xf = json_object_get_string(json_object_object_get(c, "x"));
    uc.yf = json_object_get_string(json_object_object_get(c, "y"));
    uc.sf = json_object_object_get_ex(c, "series", &v) ? json_object_get_string(v) : NULL;
    json_object_object_get_ex(c, "where", &uc.where);
    chart_points p = {0};
    collect_points(&p, &uc, runs, mixed);
    /* Runs of one series at the same x (repeats, or settings the
     * chart does not tell apart) become one point: the median y, with
     * the min-max spread as an error bar. Series drawn from a list
     * (one run each) keep their points. */
    gi_chart_series series[32];
    double *xy[32][4] = {{0}};
    double ticks[13];
    uint32_t tick_n = 0;
    int any_list = 0;
    for (uint32_t k = 0; k < p.ns; k++) {
        int spread;
        uint32_t m = merge_points(&p, k, xy[k], &spread);
        any_list |= p.listed[k];
        /* the distinct x values of every series: ticks at the swept values */
        for (uint32_t j = 0; j < m && tick_n <= 12; j++) {
            uint32_t t = 0;
            while (t < tick_n && ticks[t] != xy[k][0][j])
                t++;
            if (t == tick_n && isfinite(xy[k][0][j]))
                ticks[tick_n++] = xy[k][0][j];
        }
        series[k] = (gi_chart_series){p.labels[k],
                                      xy[k][0],
                                      xy[k][1],
                                      xy[k][0] && xy[k][1] ? m : 0,
                                      0,
                                      0,
                                      NULL,
                                      NULL,
                                      spread ? xy[k][2] : NULL,
                                      spread ? xy[k][3] : NULL};
    }
    write_user_chart(c, &uc, out_dir, series, p.ns, ticks, tick_n, any_list, chart_list);
    for (uint32_t k = 0; k < p.ns; k++) {
        free(p.labels[k]);
        free(p.pts[k]);
        for (int a = 0; a < 4; a++)
            free(xy[k][a]);
    }
}

/* The study's own charts ("charts" in the study file): y against x over the
 * finished runs that match "where", one series per value of "series". A y
 * that is a list (e.g. frame_samples_ms) gives one series per run, against
 * its position in the list. */
void study_user_charts(study *st, const char *out_dir, json_object *runs, json_object *chart_list)
{
    if (!st->charts)
        return;
    /* runs timed under different GL renderers (cluster nodes) never share a
     * series: their label names the renderer */
    int mixed = renderers_mixed(runs);
    for (size_t ci = 0; ci < json_object_array_length(st->charts); ci++)
        user_chart_draw(json_object_array_get_idx(st->charts, ci), out_dir, runs, mixed,
                        chart_list);
}
