/* Speed against accuracy for one reference set (tradeoff.h). */
#include "tradeoff.h"

#include "charts.h"
#include "gi/log.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_POINTS 64       /* render records at most this many curve points */
#define FRONT_MIN_GAIN 0.01 /* a front point must lower the error by this share */

double tradeoff_pt_time_at(const tradeoff_pt_curve *c, double e, int *extrapolated)
{
    *extrapolated = 0;
    if (!c || c->n == 0 || !(e > 0))
        return NAN;
    for (uint32_t i = 0; i + 1 < c->n; i++) {
        double e0 = c->e[i], e1 = c->e[i + 1];
        if ((e <= e0 && e >= e1) || (e >= e0 && e <= e1)) {
            double s = (log(e) - log(e0)) / (log(e1) - log(e0));
            if (!isfinite(s))
                s = 0;
            return exp(log(c->t[i]) + s * (log(c->t[i + 1]) - log(c->t[i])));
        }
    }
    *extrapolated = 1;
    /* the end nearest in error, extended with slope -1 */
    uint32_t lo = 0, hi = 0;
    for (uint32_t i = 1; i < c->n; i++) {
        if (c->e[i] < c->e[lo])
            lo = i;
        if (c->e[i] > c->e[hi])
            hi = i;
    }
    uint32_t k = e > c->e[hi] ? hi : lo;
    return c->t[k] * c->e[k] / e;
}

/* The curve at one end of its spread: every point's fastest (hi = 0) or
 * slowest (hi = 1) of its repeats. A point timed once (or a curve made
 * before repeats) is its own spread. */
static tradeoff_pt_curve curve_bound(const tradeoff_pt_curve *c, int hi)
{
    tradeoff_pt_curve b = *c;
    for (uint32_t i = 0; i < c->n; i++) {
        double v = hi ? c->t_hi[i] : c->t_lo[i];
        if (v > 0 && isfinite(v))
            b.t[i] = v;
    }
    return b;
}

/* The spread of a speed-up t_pt(e) / t (issue 34): at its low end the
 * path tracer's fastest repeats reaching the run's highest error, over the
 * run's slowest time; at its high end the path tracer's slowest repeats
 * reaching the run's lowest error, over the run's fastest time. The
 * median speed-up `mid` is kept inside the range. */
static void speedup_range(const tradeoff_pt_curve *c, double e_lo, double e_hi, double t_lo,
                          double t_hi, double mid, double *lo, double *hi)
{
    int ex;
    tradeoff_pt_curve fast = curve_bound(c, 0), slow = curve_bound(c, 1);
    *lo = tradeoff_pt_time_at(&fast, e_hi, &ex) / t_hi;
    *hi = tradeoff_pt_time_at(&slow, e_lo, &ex) / t_lo;
    if (!(*lo <= mid))
        *lo = mid;
    if (!(*hi >= mid))
        *hi = mid;
}

static double num(json_object *o, const char *k1, const char *k2, const char *k3)
{
    const char *keys[3] = {k1, k2, k3};
    for (int i = 0; i < 3 && keys[i]; i++) {
        json_object *v;
        if (!o || !json_object_object_get_ex(o, keys[i], &v) || !v)
            return NAN;
        o = v;
    }
    return json_object_get_double(o);
}

static const char *str(json_object *o, const char *key)
{
    json_object *v;
    return o && json_object_object_get_ex(o, key, &v) && v ? json_object_get_string(v) : "";
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The median of the finite values of v[0..n) (sorted to the front); NaN if none. */
static double median_of(double *v, uint32_t n)
{
    uint32_t k = 0;
    for (uint32_t i = 0; i < n; i++)
        if (isfinite(v[i]))
            v[k++] = v[i];
    n = k;
    if (n == 0)
        return NAN;
    qsort(v, n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* One run's curve: time (s), relMSE full and matched after each recorded
 * frame. A record without a curve (made before render recorded them)
 * gives its final image only, at frames x median frame time. */
static uint32_t run_curve(json_object *rec, double *t, double *ef, double *em, uint32_t *frame)
{
    json_object *c;
    if (json_object_object_get_ex(rec, "curve", &c) && json_object_is_type(c, json_type_array) &&
        json_object_array_length(c) > 0) {
        uint32_t n = 0;
        for (size_t k = 0; k < json_object_array_length(c) && n < MAX_POINTS; k++) {
            json_object *p = json_object_array_get_idx(c, k);
            t[n] = num(p, "time_ms", NULL, NULL) / 1000.0;
            ef[n] = num(p, "full", "relmse", NULL);
            em[n] = num(p, "matched", "relmse", NULL);
            frame[n] = (uint32_t)num(p, "frame", NULL, NULL);
            if (!isfinite(em[n]))
                em[n] = ef[n];
            n++;
        }
        return n;
    }
    t[0] = num(rec, "frame_ms", "median", NULL) * num(rec, "frames", NULL, NULL) / 1000.0;
    ef[0] = num(rec, "metrics", "full", "relmse");
    em[0] = num(rec, "metrics", "matched", "relmse");
    frame[0] = (uint32_t)num(rec, "frames", NULL, NULL);
    if (!isfinite(em[0]))
        em[0] = ef[0];
    return 1;
}

/* The repeats of one setting pooled: medians, and the spread (min, max) of
 * time and relMSE. */
typedef struct setting {
    uint64_t key;
    json_object *first;
    const char *method;
    uint32_t bounces, repeats, method_index;
    uint32_t n;
    double t[MAX_POINTS], ef[MAX_POINTS], ef_lo[MAX_POINTS], ef_hi[MAX_POINTS], em[MAX_POINTS];
    double t_lo[MAX_POINTS], t_hi[MAX_POINTS], em_lo[MAX_POINTS], em_hi[MAX_POINTS];
    uint32_t frame[MAX_POINTS];
    double prep_s;
    double rss_mib,
        data_mib; /* medians over repeats: peak resident memory, the method's data_bytes stat */
    const char *renderer; /* the GL renderer its runs reported ("" when none) */
    char label[192];      /* the method, with its renderer when runs of a set differ in it */
} setting;

typedef struct front_point {
    uint32_t s, k; /* setting and point */
} front_point;

static const tradeoff_pt_curve *curve_for(const tradeoff_pt_curve *full,
                                          const tradeoff_pt_curve *matched, uint32_t matched_n,
                                          uint32_t bounces)
{
    for (uint32_t i = 0; i < matched_n; i++)
        if (matched[i].bounces == bounces && bounces < full->bounces)
            return &matched[i];
    return full;
}

/* Pools the runs of each setting. Returns the number of settings. Timings
 * from different GL renderers (runs on different machines, e.g. cluster
 * nodes) are never pooled: the runs of one setting are repeats only when
 * their renderer is the same, and when the runs disagree on the renderer
 * each method is listed once per renderer ("csm [NVIDIA ...]"), with its
 * own front and rows. */
static uint32_t pool_settings(const tradeoff_run *runs, uint32_t run_n, setting *set,
                              const char **methods, uint32_t *nm)
{
    uint32_t ns = 0;
    *nm = 0;
    const char *first_renderer = NULL;
    int mixed = 0;
    for (uint32_t i = 0; i < run_n; i++) {
        if (strcmp(str(runs[i].record, "status"), "ok"))
            continue;
        const char *r = str(runs[i].record, "renderer");
        if (!first_renderer)
            first_renderer = r;
        mixed |= strcmp(first_renderer, r) != 0;
    }
    for (uint32_t i = 0; i < run_n; i++) {
        if (strcmp(str(runs[i].record, "status"), "ok"))
            continue;
        const char *renderer = str(runs[i].record, "renderer");
        uint32_t s = 0;
        while (s < ns && (set[s].key != runs[i].setting || strcmp(set[s].renderer, renderer)))
            s++;
        if (s < ns)
            continue;
        setting *g = &set[ns++];
        memset(g, 0, sizeof *g);
        g->key = runs[i].setting;
        g->first = runs[i].record;
        g->renderer = renderer;
        if (mixed)
            snprintf(g->label, sizeof g->label, "%s [%s]", str(runs[i].record, "method"),
                     *renderer ? renderer : "no renderer");
        else
            snprintf(g->label, sizeof g->label, "%s", str(runs[i].record, "method"));
        g->method = g->label;
        g->bounces = runs[i].bounces;
        uint32_t m = 0;
        while (m < *nm && strcmp(methods[m], g->method))
            m++;
        if (m == *nm)
            methods[(*nm)++] = g->method;
        g->method_index = m;
        /* every repeat of this setting */
        static double t[MAX_POINTS][64], ef[MAX_POINTS][64], em[MAX_POINTS][64];
        double prep[64], rss[64], data[64];
        uint32_t n = MAX_POINTS, rep = 0;
        for (uint32_t j = i; j < run_n && rep < 64; j++) {
            if (runs[j].setting != g->key || strcmp(str(runs[j].record, "status"), "ok") ||
                strcmp(str(runs[j].record, "renderer"), renderer))
                continue;
            double rt[MAX_POINTS], ref[MAX_POINTS], rem[MAX_POINTS];
            uint32_t frame[MAX_POINTS];
            uint32_t rn = run_curve(runs[j].record, rt, ref, rem, frame);
            if (rn < n)
                n = rn;
            for (uint32_t k = 0; k < rn; k++) {
                t[k][rep] = rt[k];
                ef[k][rep] = ref[k];
                em[k][rep] = rem[k];
                if (rep == 0)
                    g->frame[k] = frame[k];
            }
            prep[rep] = num(runs[j].record, "prepare_ms", NULL, NULL) / 1000.0;
            rss[rep] = num(runs[j].record, "peak_rss_mib", NULL, NULL);
            data[rep] = num(runs[j].record, "stats", "data_bytes", NULL) / (1024.0 * 1024.0);
            rep++;
        }
        g->repeats = rep;
        g->n = rep ? n : 0;
        for (uint32_t k = 0; k < g->n; k++) {
            /* median_of sorts: the ends are the spread */
            g->t[k] = median_of(t[k], rep);
            g->em[k] = median_of(em[k], rep);
            g->ef[k] = median_of(ef[k], rep);
            g->t_lo[k] = t[k][0], g->t_hi[k] = t[k][rep - 1];
            g->ef_lo[k] = ef[k][0], g->ef_hi[k] = ef[k][rep - 1];
            g->em_lo[k] = em[k][0], g->em_hi[k] = em[k][rep - 1];
        }
        g->prep_s = median_of(prep, rep);
        g->rss_mib = median_of(rss, rep);
        g->data_mib = median_of(data, rep);
    }
    return ns;
}

/* Each method's Pareto front over all its settings' points (time, error):
 * no other point of the method is both faster and more accurate, and each
 * point is at least 1 % more accurate than the faster one before it. */
static uint32_t pareto(const setting *set, uint32_t ns, uint32_t method, int matched,
                       front_point *out)
{
    uint32_t n = 0;
    for (uint32_t s = 0; s < ns; s++) {
        if (set[s].method_index != method)
            continue;
        for (uint32_t k = 0; k < set[s].n; k++) {
            double t = set[s].t[k], e = matched ? set[s].em[k] : set[s].ef[k];
            if (!(t > 0) || !(e > 0))
                continue;
            int dominated = 0;
            for (uint32_t s2 = 0; s2 < ns && !dominated; s2++) {
                if (set[s2].method_index != method)
                    continue;
                for (uint32_t k2 = 0; k2 < set[s2].n && !dominated; k2++) {
                    double t2 = set[s2].t[k2], e2 = matched ? set[s2].em[k2] : set[s2].ef[k2];
                    dominated = t2 <= t && e2 <= e && (t2 < t || e2 < e);
                }
            }
            /* of equal points, the first one stands */
            for (uint32_t i = 0; i < n && !dominated; i++) {
                const setting *o = &set[out[i].s];
                dominated =
                    o->t[out[i].k] == t && (matched ? o->em[out[i].k] : o->ef[out[i].k]) == e;
            }
            if (!dominated)
                out[n++] = (front_point){s, k};
        }
    }
    /* by time */
    for (uint32_t i = 1; i < n; i++)
        for (uint32_t j = i; j > 0 && set[out[j].s].t[out[j].k] < set[out[j - 1].s].t[out[j - 1].k];
             j--) {
            front_point tmp = out[j];
            out[j] = out[j - 1];
            out[j - 1] = tmp;
        }
    /* a point that lowers the error by less than 1 % against the last one
     * kept is not worth its extra time: such points (an error floor
     * approached frame by frame) are dropped */
    uint32_t kept = 0;
    for (uint32_t i = 0; i < n; i++) {
        double e = matched ? set[out[i].s].em[out[i].k] : set[out[i].s].ef[out[i].k];
        if (kept > 0) {
            const setting *l = &set[out[kept - 1].s];
            double el = matched ? l->em[out[kept - 1].k] : l->ef[out[kept - 1].k];
            if (!(e < el * (1.0 - FRONT_MIN_GAIN)))
                continue;
        }
        out[kept++] = out[i];
    }
    return kept;
}

/* Method m's series: each of its settings' curves (thin), then its Pareto
 * front as a staircase into x (and the five arrays after it, `per` values
 * apart) labelled in `label`. Returns the number of series added. */
static uint32_t method_series(gi_chart_series *series, const setting *set, uint32_t ns, uint32_t m,
                              int matched, front_point *fp, double *x, size_t per, char *label,
                              size_t label_size, const char *method)
{
    uint32_t n = 0;
    for (uint32_t s = 0; s < ns; s++)
        if (set[s].method_index == m && set[s].n > 1)
            series[n++] =
                (gi_chart_series){NULL,     set[s].t,      matched ? set[s].em : set[s].ef,
                                  set[s].n, GI_CHART_THIN, (int)m + 1,
                                  NULL,     NULL,          NULL,
                                  NULL};
    uint32_t k = pareto(set, ns, m, matched, fp);
    double *y = x + per, *xl = y + per, *xh = xl + per, *yl = xh + per, *yh = yl + per;
    /* a staircase: between two settings on the front nothing better is
     * known than the slower one's error, reached at its own time. Each
     * front point carries the spread of its repeats as error bars
     * (time and relMSE, min to max); the corners carry none. */
    uint32_t c = 0;
    int spread = 0;
    for (uint32_t i = 0; i < k; i++) {
        const setting *g = &set[fp[i].s];
        uint32_t j = fp[i].k;
        double e = matched ? g->em[j] : g->ef[j];
        if (i > 0) {
            x[c] = g->t[j];
            y[c] = y[c - 1];
            xl[c] = xh[c] = yl[c] = yh[c] = NAN;
            c++;
        }
        x[c] = g->t[j];
        y[c] = e;
        xl[c] = g->t_lo[j], xh[c] = g->t_hi[j];
        yl[c] = matched ? g->em_lo[j] : g->ef_lo[j];
        yh[c] = matched ? g->em_hi[j] : g->ef_hi[j];
        spread |= g->repeats > 1;
        c++;
    }
    snprintf(label, label_size, "%s (Pareto front%s)", method,
             spread ? "; bars: min-max of repeats" : "");
    series[n++] = (gi_chart_series){label,
                                    x,
                                    y,
                                    c,
                                    GI_CHART_LINE_MARKERS,
                                    (int)m + 1,
                                    spread ? xl : NULL,
                                    spread ? xh : NULL,
                                    spread ? yl : NULL,
                                    spread ? yh : NULL};
    return n;
}

/* The path tracer's curves, in the reference looks (greys, none a
 * method's colour): full GI, or with matched every bounce limit (labelled
 * in labels) and then full GI. Returns the number of series added. */
static uint32_t path_tracer_series(gi_chart_series *series, int matched,
                                   const tradeoff_pt_curve *full, const tradeoff_pt_curve *mcurves,
                                   uint32_t matched_n, char (*labels)[160])
{
    uint32_t n = 0;
    if (!matched) {
        series[n++] = (gi_chart_series){"path tracer (Embree, CPU), full GI",
                                        full->t,
                                        full->e,
                                        full->n,
                                        GI_CHART_REFERENCE,
                                        1,
                                        NULL,
                                        NULL,
                                        NULL,
                                        NULL};
    } else {
        /* full GI keeps the first look in both charts; the bounce limits follow */
        for (uint32_t i = 0; i < matched_n; i++) {
            snprintf(labels[i], sizeof labels[i], "path tracer, max_bounces %u",
                     mcurves[i].bounces);
            series[n++] = (gi_chart_series){
                labels[i],  mcurves[i].t, mcurves[i].e, mcurves[i].n, GI_CHART_REFERENCE,
                (int)i + 2, NULL,         NULL,         NULL,         NULL};
        }
        series[n++] = (gi_chart_series){"path tracer, full GI",
                                        full->t,
                                        full->e,
                                        full->n,
                                        GI_CHART_REFERENCE,
                                        1,
                                        NULL,
                                        NULL,
                                        NULL,
                                        NULL};
    }
    return n;
}

static void chart(tradeoff_chart_fn write_chart, const char *out_dir, const char *name, int matched,
                  const tradeoff_pt_curve *full, const tradeoff_pt_curve *mcurves,
                  uint32_t matched_n, const setting *set, uint32_t ns, const char **methods,
                  uint32_t nm, json_object *chart_list)
{
    uint32_t cap = ns + 2 * nm + matched_n + 2;
    gi_chart_series *series = calloc(cap, sizeof *series);
    /* per method: the staircase's x, y and its error bars (x lo/hi, y lo/hi) */
    size_t per = (size_t)ns * MAX_POINTS * 2;
    double *fx = calloc((size_t)nm * per * 6 + 1, sizeof *fx);
    front_point *fp = calloc((size_t)ns * MAX_POINTS + 1, sizeof *fp);
    char(*labels)[160] = calloc(nm + matched_n + 1, sizeof *labels);
    if (!series || !fx || !fp || !labels) {
        free(series), free(fx), free(fp), free(labels);
        return;
    }
    uint32_t n = 0;
    for (uint32_t m = 0; m < nm; m++)
        n += method_series(series + n, set, ns, m, matched, fp, fx + (size_t)m * per * 6, per,
                           labels[m], sizeof labels[m], methods[m]);
    n += path_tracer_series(series + n, matched, full, mcurves, matched_n, labels + nm);
    char file[512], path[4700], title[512];
    snprintf(file, sizeof file, "chart_%s_error_vs_time%s.png", name, matched ? "_matched" : "");
    snprintf(path, sizeof path, "%s/%s", out_dir, file);
    snprintf(title, sizeof title, "%s: relMSE against time (%s)", name,
             matched ? "bounce-matched references" : "full-GI reference");
    gi_chart_desc desc = {
        title, "time to image (s): sum of frame times so far", "relMSE", 1, 1, 0, 0, NULL, 0};
    gi_error err;
    if (write_chart(path, &desc, series, n, &err) == GI_OK)
        json_object_array_add(chart_list, json_object_new_string(file));
    else
        gi_log(GI_LOG_WARN, "chart %s not written: %s", file, err.text);
    free(series), free(fx), free(fp), free(labels);
}

/* A memory cell: MiB, or "–" when not measured (the method reports no
 * data_bytes; records made before runs measured their memory). */
static void put_mib(gi_text *md, double mib)
{
    if (isfinite(mib))
        gi_text_put(md, " %.4g |", mib);
    else
        gi_text_put(md, " – |");
}

/* relMSE as "median" or "median [min–max]" over repeats. */
static void put_error(gi_text *md, const setting *g, uint32_t k)
{
    if (g->repeats > 1 && g->ef_hi[k] > g->ef_lo[k])
        gi_text_put(md, " %.4g [%.4g–%.4g] |", g->ef[k], g->ef_lo[k], g->ef_hi[k]);
    else
        gi_text_put(md, " %.4g |", g->ef[k]);
}

/* A speed-up cell: the median, and [min–max] from the spreads of the
 * path tracer's curve and of the setting's repeats (time and error). */
static void put_speedup(gi_text *md, const tradeoff_pt_curve *c, const setting *g, uint32_t k,
                        int matched, double tpt, int ex)
{
    double mid = tpt / g->t[k], lo, hi;
    double e_lo = matched ? g->em_lo[k] : g->ef_lo[k], e_hi = matched ? g->em_hi[k] : g->ef_hi[k];
    if (!(e_lo > 0) || !(e_hi > 0))
        e_lo = e_hi = matched ? g->em[k] : g->ef[k];
    double t_lo = g->t_lo[k] > 0 ? g->t_lo[k] : g->t[k],
           t_hi = g->t_hi[k] > 0 ? g->t_hi[k] : g->t[k];
    speedup_range(c, e_lo, e_hi, t_lo, t_hi, mid, &lo, &hi);
    if (isfinite(lo) && isfinite(hi) && hi > lo)
        gi_text_put(md, " %.3g [%.3g–%.3g]%s |", mid, lo, hi, ex ? "*" : "");
    else
        gi_text_put(md, " %.3g%s |", mid, ex ? "*" : "");
}

static void params_cell(gi_text *md, json_object *rec)
{
    const char *p = str(rec, "params");
    gi_text_put(md, " ");
    gi_text_md_code(md, *p ? p : "(defaults)");
    gi_text_put(md, " |");
}

/* Per record: the earliest recorded frame whose error is within 1 % of the
 * final image's (a method with an error floor is charged only the frames it
 * needs), and its speed-ups there. */
static void annotate_records(const tradeoff_run *runs, uint32_t run_n,
                             const tradeoff_pt_curve *full, const tradeoff_pt_curve *matched,
                             uint32_t matched_n)
{
    for (uint32_t i = 0; i < run_n; i++) {
        json_object *rec = runs[i].record;
        if (strcmp(str(rec, "status"), "ok"))
            continue;
        double t[MAX_POINTS], ef[MAX_POINTS], em[MAX_POINTS];
        uint32_t frame[MAX_POINTS];
        uint32_t n = run_curve(rec, t, ef, em, frame);
        if (n == 0 || !(ef[n - 1] > 0))
            continue;
        uint32_t k = 0;
        while (k + 1 < n && !(ef[k] <= ef[n - 1] * 1.01))
            k++;
        json_object_object_add(rec, "time_to_final_error_s", json_object_new_double(t[k]));
        json_object_object_add(rec, "frames_to_final_error",
                               json_object_new_int((int32_t)frame[k]));
        int ex = 0, exm = 0;
        double tpt = tradeoff_pt_time_at(full, ef[n - 1], &ex);
        const tradeoff_pt_curve *mc = curve_for(full, matched, matched_n, runs[i].bounces);
        double tptm = tradeoff_pt_time_at(mc, em[n - 1], &exm);
        double lo, hi;
        if (isfinite(tpt) && t[k] > 0) {
            json_object_object_add(rec, "pt_time_at_equal_error_s", json_object_new_double(tpt));
            json_object_object_add(rec, "speedup_vs_pt", json_object_new_double(tpt / t[k]));
            /* one run is one sample: the spread is the curve's */
            speedup_range(full, ef[n - 1], ef[n - 1], t[k], t[k], tpt / t[k], &lo, &hi);
            json_object_object_add(rec, "speedup_vs_pt_min", json_object_new_double(lo));
            json_object_object_add(rec, "speedup_vs_pt_max", json_object_new_double(hi));
        }
        if (isfinite(tptm) && t[k] > 0) {
            json_object_object_add(rec, "speedup_vs_pt_matched",
                                   json_object_new_double(tptm / t[k]));
            speedup_range(mc, em[n - 1], em[n - 1], t[k], t[k], tptm / t[k], &lo, &hi);
            json_object_object_add(rec, "speedup_vs_pt_matched_min", json_object_new_double(lo));
            json_object_object_add(rec, "speedup_vs_pt_matched_max", json_object_new_double(hi));
        }
        json_object_object_add(rec, "speedup_extrapolated",
                               json_object_new_int(ex || exm)); /* 1: beyond the measured curve */
    }
}

static void equal_error_table(gi_text *md, const char *name, const tradeoff_pt_curve *full,
                              const tradeoff_pt_curve *matched, uint32_t matched_n,
                              const setting *set, uint32_t ns, const char **methods, uint32_t nm,
                              front_point *fp)
{
    gi_text_put(md, "#### ");
    gi_text_md(md, name);
    gi_text_put(
        md,
        ": equal error (each method's Pareto front against the full-GI reference)\n\n"
        "Speed-up = the path tracer's time to the same relMSE ÷ the method's time to its image; "
        "\"matched\" compares the method's error against the reference of its own bounce count "
        "with "
        "the path tracer limited to that count. Precomputation is not in the time to image: it has "
        "its own column, and the next three add it amortised over 1, 100 and 10,000 images. "
        "Memory: "
        "the render process's peak resident set (MiB; on llvmpipe GPU buffers and textures count, "
        "on a hardware GPU they do not) and the size of the method's own precomputed data (its "
        "`data_bytes` statistic; \"–\" where it reports none), medians over repeats. "
        "\"*\": the path tracer's time is extrapolated beyond its measured curve (slope −1). "
        "relMSE over repeats: median [min–max]. Speed-up: median [min–max], the range from the "
        "spread of the path tracer's repeated curve points and of the method's repeats (time "
        "and relMSE).\n\n");
    gi_text_put(
        md,
        "| method | params | frames | time to image (s) | relMSE full | path tracer, same error "
        "(s) | "
        "speed-up | relMSE matched | matched path tracer (s) | speed-up matched | precompute (s) | "
        "amortised ×1 (s) | ×100 (s) | ×10⁴ (s) | peak RSS (MiB) | data (MiB) |\n"
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for (uint32_t m = 0; m < nm; m++) {
        uint32_t k = pareto(set, ns, m, 0, fp);
        for (uint32_t i = 0; i < k; i++) {
            const setting *g = &set[fp[i].s];
            uint32_t p = fp[i].k;
            int ex = 0, exm = 0;
            double tpt = tradeoff_pt_time_at(full, g->ef[p], &ex);
            const tradeoff_pt_curve *mc = curve_for(full, matched, matched_n, g->bounces);
            double tptm = tradeoff_pt_time_at(mc, g->em[p], &exm);
            double prep = isfinite(g->prep_s) ? g->prep_s : 0.0;
            gi_text_put(md, "| ");
            gi_text_md(md, methods[m]);
            gi_text_put(md, " |");
            params_cell(md, g->first);
            gi_text_put(md, " %u | %.4g |", g->frame[p], g->t[p]);
            put_error(md, g, p);
            gi_text_put(md, " %.4g%s |", tpt, ex ? "*" : "");
            put_speedup(md, full, g, p, 0, tpt, ex);
            gi_text_put(md, " %.4g | %.4g%s |", g->em[p], tptm, exm ? "*" : "");
            put_speedup(md, mc, g, p, 1, tptm, exm);
            gi_text_put(md, " %.4g | %.4g | %.4g | %.4g |", prep, g->t[p] + prep,
                        g->t[p] + prep / 100.0, g->t[p] + prep / 1e4);
            put_mib(md, g->rss_mib);
            put_mib(md, g->data_mib);
            gi_text_put(md, "\n");
        }
    }
    gi_text_put(md, "\n");
}

/* The method's best error among its points reached by time T (NaN if none). */
static double best_error_by(const setting *set, uint32_t ns, uint32_t m, int matched, double T,
                            const setting **at, uint32_t *at_k)
{
    double best = NAN;
    for (uint32_t s = 0; s < ns; s++) {
        if (set[s].method_index != m)
            continue;
        for (uint32_t k = 0; k < set[s].n; k++) {
            double e = matched ? set[s].em[k] : set[s].ef[k];
            if (set[s].t[k] <= T && e > 0 && !(e >= best)) {
                best = e;
                *at = &set[s];
                *at_k = k;
            }
        }
    }
    return best;
}

static void equal_time_table(gi_text *md, const char *name, const tradeoff_pt_curve *full,
                             const tradeoff_pt_curve *matched, uint32_t matched_n,
                             const setting *set, uint32_t ns, const char **methods, uint32_t nm)
{
    if (full->n == 0)
        return;
    gi_text_put(md, "#### ");
    gi_text_md(md, name);
    gi_text_put(
        md,
        ": equal time (each method's best relMSE within the time the path tracer needs for "
        "its "
        "error levels)\n\n"
        "A column per image of the path tracer's convergence run (time, its relMSE). A cell: the "
        "method's lowest relMSE among its settings and frames whose time to image is within that "
        "time "
        "(precomputation not counted), and its ratio to the path tracer's error; \"–\": no setting "
        "is "
        "that fast. \"matched\" rows: against the reference of the method's bounce count, the path "
        "tracer limited to it (its own time and error at that image). The last three columns: the "
        "precomputation time, peak resident memory and data size of the settings behind the row's "
        "cells (min–max when they differ).\n\n");
    gi_text_put(md, "| method |");
    for (uint32_t i = 0; i < full->n; i++)
        gi_text_put(md, " %.3g s (PT %.3g) |", full->t[i], full->e[i]);
    gi_text_put(md, " precompute (s) | peak RSS (MiB) | data (MiB) |\n|---|");
    for (uint32_t i = 0; i < full->n + 3; i++)
        gi_text_put(md, "---:|");
    gi_text_put(md, "\n");
    for (uint32_t m = 0; m < nm; m++) {
        for (int matched_row = 0; matched_row < 2; matched_row++) {
            uint32_t b = 0;
            for (uint32_t s = 0; s < ns; s++)
                if (set[s].method_index == m)
                    b = set[s].bounces;
            const tradeoff_pt_curve *c =
                matched_row ? curve_for(full, matched, matched_n, b) : full;
            if (matched_row && c == full)
                continue; /* the method is full GI: the row above says it */
            gi_text_put(md, "| ");
            gi_text_md(md, methods[m]);
            gi_text_put(md, "%s |", matched_row ? " (matched)" : "");
            /* the range of the costs of the settings behind the cells */
            double lo[3] = {INFINITY, INFINITY, INFINITY},
                   hi[3] = {-INFINITY, -INFINITY, -INFINITY};
            for (uint32_t i = 0; i < full->n; i++) {
                double T = i < c->n ? c->t[i] : NAN, ept = i < c->n ? c->e[i] : NAN;
                const setting *at = NULL;
                uint32_t at_k = 0;
                double e =
                    isfinite(T) ? best_error_by(set, ns, m, matched_row, T, &at, &at_k) : NAN;
                if (isfinite(e))
                    gi_text_put(md, " %.4g (×%.3g) |", e, e / ept);
                else
                    gi_text_put(md, " – |");
                if (isfinite(e) && at) {
                    double v[3] = {at->prep_s, at->rss_mib, at->data_mib};
                    for (int q = 0; q < 3; q++)
                        if (isfinite(v[q])) {
                            lo[q] = v[q] < lo[q] ? v[q] : lo[q];
                            hi[q] = v[q] > hi[q] ? v[q] : hi[q];
                        }
                }
            }
            for (int q = 0; q < 3; q++) {
                if (!isfinite(lo[q]))
                    gi_text_put(md, " – |");
                else if (hi[q] > lo[q])
                    gi_text_put(md, " %.4g–%.4g |", lo[q], hi[q]);
                else
                    gi_text_put(md, " %.4g |", lo[q]);
            }
            gi_text_put(md, "\n");
        }
    }
    gi_text_put(md, "\n");
}

/* gibench study --mix-clocks: which invocations this set's tables take
 * their times from (the curves', then the runs' with their counts). */
static void clock_note(gi_text *md, const tradeoff_pt_curve *full, const tradeoff_pt_curve *matched,
                       uint32_t matched_n, const tradeoff_run *runs, uint32_t run_n)
{
    const char *inv[64];
    uint32_t count[64], ni = 0;
    int curve[64] = {0};
    for (uint32_t i = 0; i < matched_n + 1 + run_n; i++) {
        const char *v;
        if (i == 0)
            v = full->invocation;
        else if (i <= matched_n)
            v = matched[i - 1].invocation;
        else if (!strcmp(str(runs[i - 1 - matched_n].record, "status"), "ok"))
            v = str(runs[i - 1 - matched_n].record, "invocation");
        else
            continue;
        uint32_t k = 0;
        while (k < ni && strcmp(inv[k], v))
            k++;
        if (k == ni && ni < 64) {
            inv[ni] = v;
            count[ni++] = 0;
        }
        if (k < ni && i > matched_n)
            count[k]++;
        else if (k < ni)
            curve[k] = 1;
    }
    gi_text_put(md, "**Clocks are mixed** (gibench study --mix-clocks): the study's times come "
                    "from several invocations; this set's from");
    for (uint32_t k = 0; k < ni; k++) {
        gi_text_put(md, "%s ", k ? ";" : "");
        gi_text_md(md, *inv[k] ? inv[k] : "(not recorded)");
        gi_text_put(md, " (%s%u runs)", curve[k] ? "the path tracer's curve, " : "", count[k]);
    }
    gi_text_put(md, ". Speed-ups across invocations compare different clocks.\n\n");
}

void tradeoff_report(const char *out_dir, const char *name, const tradeoff_pt_curve *full,
                     const tradeoff_pt_curve *matched, uint32_t matched_n, const tradeoff_run *runs,
                     uint32_t run_n, tradeoff_chart_fn write_chart, json_object *chart_list,
                     gi_text *md, const tradeoff_clock_note *clocks)
{
    setting *set = calloc(run_n + 1, sizeof *set);
    const char **methods = calloc(run_n + 1, sizeof *methods);
    front_point *fp = calloc((size_t)(run_n + 1) * MAX_POINTS, sizeof *fp);
    if (!set || !methods || !fp) {
        free(set), free(methods), free(fp);
        return;
    }
    annotate_records(runs, run_n, full, matched, matched_n);
    uint32_t nm = 0, ns = pool_settings(runs, run_n, set, methods, &nm);
    int any_matched = 0;
    for (uint32_t s = 0; s < ns; s++)
        any_matched |= set[s].bounces < full->bounces;
    if (write_chart)
        chart(write_chart, out_dir, name, 0, full, matched, matched_n, set, ns, methods, nm,
              chart_list);
    if (write_chart && any_matched)
        chart(write_chart, out_dir, name, 1, full, matched, matched_n, set, ns, methods, nm,
              chart_list);
    gi_text_put(md, "Path tracer convergence on ");
    gi_text_md(md, name);
    gi_text_put(md,
                " (relMSE against the reference, another seed; time: median [min–max] of "
                "%u repeats in the study's invocation):",
                full->samples[0] ? full->samples[0] : 1);
    const tradeoff_pt_curve *curves[9] = {full};
    uint32_t nc = 1;
    for (uint32_t i = 0; i < matched_n && nc < 9; i++)
        curves[nc++] = &matched[i];
    for (uint32_t c = 0; c < nc; c++) {
        gi_text_put(md, "%s max_bounces %u:", c ? ";" : "", curves[c]->bounces);
        for (uint32_t i = 0; i < curves[c]->n; i++) {
            gi_text_put(md, " %.3g s", curves[c]->t[i]);
            if (curves[c]->t_hi[i] > curves[c]->t_lo[i] && curves[c]->t_lo[i] > 0)
                gi_text_put(md, " [%.3g–%.3g]", curves[c]->t_lo[i], curves[c]->t_hi[i]);
            gi_text_put(md, " → %.3g%s", curves[c]->e[i], i + 1 < curves[c]->n ? "," : "");
        }
    }
    gi_text_put(md, ".\n\n");
    if (clocks && clocks->mixed)
        clock_note(md, full, matched, matched_n, runs, run_n);
    equal_error_table(md, name, full, matched, matched_n, set, ns, methods, nm, fp);
    equal_time_table(md, name, full, matched, matched_n, set, ns, methods, nm);
    free(set), free(methods), free(fp);
}
