/* runs.csv, report.md and index.html from run records (report.h). */
#define _POSIX_C_SOURCE 200809L
#include "report.h"

#include "cli.h"
#include "gi/cache.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/utsname.h>
#include <time.h>
#include <unistd.h>

const char *const report_metric_keys[] = {"relmse", "rmse", "mae", "psnr", "ssim", "flip", "mean_lum_diff_pct", NULL};

int cli_mkdirs(const char *path)
{
    char buf[4096];
    snprintf(buf, sizeof buf, "%s", path);
    for (char *p = buf + 1; *p; p++)
        if (*p == '/') {
            *p = '\0';
            if (mkdir(buf, 0755) != 0 && errno != EEXIST)
                return 0;
            *p = '/';
        }
    return mkdir(buf, 0755) == 0 || errno == EEXIST;
}

/* The machine, for the report: kernel, architecture, cores. */
static void machine_string(char *buf, size_t size)
{
    struct utsname u;
    if (uname(&u) != 0)
        snprintf(buf, size, "unknown");
    else
        snprintf(buf, size, "%s %s %s, %ld cores", u.sysname, u.release, u.machine, sysconf(_SC_NPROCESSORS_ONLN));
}

static void date_string(char *buf, size_t size)
{
    time_t t = time(NULL);
    struct tm tm;
    gmtime_r(&t, &tm);
    strftime(buf, size, "%Y-%m-%d %H:%M UTC", &tm);
}

static void command_string(const char *cmd, int argc, char **argv, char *buf, size_t size)
{
    snprintf(buf, size, "gibench %s", cmd);
    for (int i = 0; i < argc; i++) {
        size_t used = strlen(buf);
        snprintf(buf + used, size - used, " %s", argv[i]);
    }
}

json_object *report_meta_new(const char *title, const char *command, int argc, char **argv, const char *renderer,
                             const char *reference)
{
    char cmd[4096], machine[256], date[64];
    command_string(command, argc, argv, cmd, sizeof cmd);
    machine_string(machine, sizeof machine);
    date_string(date, sizeof date);
    json_object *meta = json_object_new_object();
    json_object_object_add(meta, "title", json_object_new_string(title));
    json_object_object_add(meta, "command", json_object_new_string(cmd));
    json_object_object_add(meta, "renderer", json_object_new_string(renderer && *renderer ? renderer : "(no run finished)"));
    json_object_object_add(meta, "reference", json_object_new_string(reference));
    json_object_object_add(meta, "machine", json_object_new_string(machine));
    json_object_object_add(meta, "date", json_object_new_string(date));
    return meta;
}

json_object *cli_read_json(const char *path)
{
    size_t n;
    char *text = gi_file_read_all(path, &n);
    if (!text)
        return NULL;
    json_tokener *tok = json_tokener_new();
    json_object *o = json_tokener_parse_ex(tok, text, (int)n);
    if (json_tokener_get_error(tok) != json_tokener_success) {
        json_object_put(o);
        o = NULL;
    }
    json_tokener_free(tok);
    free(text);
    return o;
}

/* A growing text buffer. */
typedef struct text {
    char *s;
    size_t len, cap;
} text;

static void put(text *t, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
static void put(text *t, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(NULL, 0, fmt, ap);
    va_end(ap);
    if (n < 0)
        return;
    if (t->len + (size_t)n + 1 > t->cap) {
        size_t cap = t->cap ? t->cap : 4096;
        while (cap < t->len + (size_t)n + 1)
            cap *= 2;
        char *s = realloc(t->s, cap);
        if (!s)
            return;
        t->s = s;
        t->cap = cap;
    }
    va_start(ap, fmt);
    vsnprintf(t->s + t->len, (size_t)n + 1, fmt, ap);
    va_end(ap);
    t->len += (size_t)n;
}

static const char *str(json_object *o, const char *key)
{
    /* the method's full parameter string (defaults included) when known */
    if (!strcmp(key, "params") && o && json_object_object_get_ex(o, "params_full", NULL))
        key = "params_full";
    json_object *v;
    if (o && json_object_object_get_ex(o, key, &v) && json_object_is_type(v, json_type_string))
        return json_object_get_string(v);
    return "";
}

/* Number at a path of up to three keys; NaN when absent. */
static double num(json_object *o, const char *k1, const char *k2, const char *k3)
{
    const char *keys[3] = {k1, k2, k3};
    for (int i = 0; i < 3 && keys[i]; i++) {
        json_object *v;
        if (!o || !json_object_object_get_ex(o, keys[i], &v))
            return NAN;
        o = v;
    }
    if (json_object_is_type(o, json_type_double) || json_object_is_type(o, json_type_int))
        return json_object_get_double(o);
    return NAN;
}

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

/* The union over all runs of the keys of object `field` ("stages",
 * "prepare_stages", "stats"), first-seen order. */
static int key_names(json_object *runs, const char *field, const char **names, int max)
{
    int n = 0;
    size_t count = json_object_array_length(runs);
    for (size_t i = 0; i < count; i++) {
        json_object *stages;
        if (!json_object_object_get_ex(json_object_array_get_idx(runs, i), field, &stages) ||
            !json_object_is_type(stages, json_type_object))
            continue;
        json_object_object_foreach(stages, key, val)
        {
            (void)val;
            int seen = 0;
            for (int k = 0; k < n; k++)
                seen |= strcmp(names[k], key) == 0;
            if (!seen && n < max)
                names[n++] = key;
        }
    }
    return n;
}

static int stage_names(json_object *runs, const char **names, int max)
{
    return key_names(runs, "stages", names, max);
}

/* The last columns of runs.csv: the seed, and what the study's speed
 * against accuracy found for the run (tradeoff.h). */
static const char *const tradeoff_keys[] = {"seed", "time_to_final_error_s", "frames_to_final_error",
                                             "speedup_vs_pt", "speedup_vs_pt_matched", NULL};

static void write_csv(text *t, json_object *runs)
{
    const char *stages[32], *pstages[32], *stats[64];
    int ns = stage_names(runs, stages, 32);
    int np = key_names(runs, "prepare_stages", pstages, 32);
    int nst = key_names(runs, "stats", stats, 64);
    put(t, "run,scene,method,params,status,reason,renderer,timer,frames,prepare_ms,frame_ms_median,frame_ms_min,"
           "frame_ms_max");
    for (int k = 0; k < ns; k++)
        put(t, ",stage_%s_ms_median,stage_%s_ms_min,stage_%s_ms_max", stages[k], stages[k], stages[k]);
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
    put(t, "\n");
    size_t count = json_object_array_length(runs);
    for (size_t i = 0; i < count; i++) {
        json_object *o = json_object_array_get_idx(runs, i);
        const char *fields[] = {"run", "scene", "method", "params", "status", "reason", "renderer", "timer"};
        for (size_t f = 0; f < sizeof fields / sizeof fields[0]; f++)
            csv_field(t, str(o, fields[f]), 0);
        csv_num(t, num(o, "frames", NULL, NULL), 0);
        csv_num(t, num(o, "prepare_ms", NULL, NULL), 0);
        csv_num(t, num(o, "frame_ms", "median", NULL), 0);
        csv_num(t, num(o, "frame_ms", "min", NULL), 0);
        csv_num(t, num(o, "frame_ms", "max", NULL), 0);
        for (int k = 0; k < ns; k++) {
            csv_num(t, num(o, "stages", stages[k], "median"), 0);
            csv_num(t, num(o, "stages", stages[k], "min"), 0);
            csv_num(t, num(o, "stages", stages[k], "max"), 0);
        }
        for (int r = 0; r < 2; r++)
            for (int m = 0; report_metric_keys[m]; m++)
                csv_num(t, num(o, "metrics", r ? "matched" : "full", report_metric_keys[m]), 0);
        csv_field(t, str(o, "label"), 0);
        csv_num(t, num(o, "width", NULL, NULL), 0);
        csv_num(t, num(o, "height", NULL, NULL), 0);
        for (int k = 0; k < np; k++)
            csv_num(t, num(o, "prepare_stages", pstages[k], NULL), 0);
        for (int k = 0; k < nst; k++)
            csv_num(t, num(o, "stats", stats[k], NULL), 0);
        for (int k = 0; tradeoff_keys[k]; k++)
            csv_num(t, num(o, tradeoff_keys[k], NULL, NULL), !tradeoff_keys[k + 1]);
    }
}

/* frames.csv: every timed frame of every run (per-frame time of animations). */
static void write_frames_csv(text *t, json_object *runs)
{
    put(t, "run,label,frame,frame_ms\n");
    size_t count = json_object_array_length(runs);
    for (size_t i = 0; i < count; i++) {
        json_object *o = json_object_array_get_idx(runs, i), *f;
        if (!json_object_object_get_ex(o, "frame_samples_ms", &f) || !json_object_is_type(f, json_type_array))
            continue;
        for (size_t k = 0; k < json_object_array_length(f); k++) {
            csv_field(t, str(o, "run"), 0);
            csv_field(t, str(o, "label"), 0);
            put(t, "%zu,", k + 1);
            csv_num(t, json_object_get_double(json_object_array_get_idx(f, k)), 1);
        }
    }
}

/* curves.csv: every run's convergence curve (render --curve-ref): the
 * time to the image after each recorded frame and its error. */
static void write_curves_csv(text *t, json_object *runs)
{
    put(t, "run,method,params,label,seed,frame,time_s,relmse_full,relmse_matched\n");
    size_t count = json_object_array_length(runs);
    for (size_t i = 0; i < count; i++) {
        json_object *o = json_object_array_get_idx(runs, i), *c;
        if (!json_object_object_get_ex(o, "curve", &c) || !json_object_is_type(c, json_type_array))
            continue;
        for (size_t k = 0; k < json_object_array_length(c); k++) {
            json_object *p = json_object_array_get_idx(c, k);
            csv_field(t, str(o, "run"), 0);
            csv_field(t, str(o, "method"), 0);
            csv_field(t, str(o, "params"), 0);
            csv_field(t, str(o, "label"), 0);
            csv_num(t, num(o, "seed", NULL, NULL), 0);
            csv_num(t, num(p, "frame", NULL, NULL), 0);
            csv_num(t, num(p, "time_ms", NULL, NULL) / 1000.0, 0);
            csv_num(t, num(p, "full", "relmse", NULL), 0);
            csv_num(t, num(p, "matched", "relmse", NULL), 1);
        }
    }
}

static void md_num(text *t, double v)
{
    if (v == v)
        put(t, " %.4g |", v);
    else
        put(t, " – |");
}

static void write_md(text *t, json_object *runs, json_object *meta)
{
    put(t, "# %s\n\n", str(meta, "title"));
    put(t, "- command: `%s`\n", str(meta, "command"));
    put(t, "- GL renderer: %s\n", str(meta, "renderer"));
    put(t, "- reference: %s\n", str(meta, "reference"));
    put(t, "- machine: %s\n", str(meta, "machine"));
    put(t, "- date: %s\n\n", str(meta, "date"));
    put(t, "Errors are against the full-GI reference (\"full\") and against the reference limited to the "
           "method's own bounce count (\"matched\"), so that method error and missing light are reported "
           "apart. Times are medians over the timed frames; on a software renderer only ratios within one "
           "run mean anything.\n\n");
    put(t, "| run | method | params | status | frame ms | prepare ms | relMSE full | relMSE matched | FLIP full "
           "| SSIM full | mean lum. diff %% |\n");
    put(t, "|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|\n");
    size_t count = json_object_array_length(runs);
    for (size_t i = 0; i < count; i++) {
        json_object *o = json_object_array_get_idx(runs, i);
        const char *status = str(o, "status");
        put(t, "| %s | %s | `%s` | %s%s%s |", str(o, "run"), str(o, "method"), str(o, "params"), status,
            strcmp(status, "ok") ? ": " : "", strcmp(status, "ok") ? str(o, "reason") : "");
        md_num(t, num(o, "frame_ms", "median", NULL));
        md_num(t, num(o, "prepare_ms", NULL, NULL));
        md_num(t, num(o, "metrics", "full", "relmse"));
        md_num(t, num(o, "metrics", "matched", "relmse"));
        md_num(t, num(o, "metrics", "full", "flip"));
        md_num(t, num(o, "metrics", "full", "ssim"));
        md_num(t, num(o, "metrics", "full", "mean_lum_diff_pct"));
        put(t, "\n");
    }
    const char *stages[32];
    int ns = stage_names(runs, stages, 32);
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
            if (strcmp(str(o, "status"), "ok"))
                continue;
            put(t, "| %s |", str(o, "run"));
            for (int k = 0; k <= ns; k++) {
                const char *k1 = k < ns ? "stages" : "frame_ms", *k2 = k < ns ? stages[k] : NULL;
                double med = k < ns ? num(o, k1, k2, "median") : num(o, k1, "median", NULL);
                double mn = k < ns ? num(o, k1, k2, "min") : num(o, k1, "min", NULL);
                double mx = k < ns ? num(o, k1, k2, "max") : num(o, k1, "max", NULL);
                if (med == med)
                    put(t, " %.4g (%.4g – %.4g) |", med, mn, mx);
                else
                    put(t, " – |");
            }
            put(t, "\n");
        }
    }
    put(t, "\nImages (tonemapped at the report's exposure) and relative error against the full reference "
           "(log scale, colour bar in each map):\n\n");
    const char *ref_png = str(meta, "reference_png");
    if (*ref_png)
        put(t, "reference: ![reference](%s)\n\n", ref_png);
    for (size_t i = 0; i < count; i++) {
        json_object *o = json_object_array_get_idx(runs, i);
        if (*str(o, "png"))
            put(t, "%s: ![%s](%s) ![error](%s)\n\n", str(o, "run"), str(o, "run"), str(o, "png"), str(o, "heatmap"));
    }
    json_object *charts;
    if (json_object_object_get_ex(meta, "charts", &charts)) {
        put(t, "\n");
        for (size_t i = 0; i < json_object_array_length(charts); i++) {
            const char *c = json_object_get_string(json_object_array_get_idx(charts, i));
            put(t, "![%s](%s)\n\n", c, c);
        }
    }
    json_object *extra;
    if (json_object_object_get_ex(meta, "markdown", &extra))
        put(t, "\n%s\n", json_object_get_string(extra));
}

static void html_escape(text *t, const char *s)
{
    for (; *s; s++) {
        switch (*s) {
        case '<': put(t, "&lt;"); break;
        case '>': put(t, "&gt;"); break;
        case '&': put(t, "&amp;"); break;
        case '"': put(t, "&quot;"); break;
        default: put(t, "%c", *s);
        }
    }
}

static void write_html(text *t, json_object *runs, json_object *meta)
{
    put(t, "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>");
    html_escape(t, str(meta, "title"));
    put(t, "</title>\n<style>body{font-family:sans-serif;margin:2em}table{border-collapse:collapse}"
           "td,th{border:1px solid #ccc;padding:4px 8px;text-align:right}td.l,th.l{text-align:left}"
           "img{image-rendering:pixelated;width:192px}figure{display:inline-block;margin:4px}"
           "figcaption{font-size:small}</style></head><body>\n<h1>");
    html_escape(t, str(meta, "title"));
    put(t, "</h1>\n<p>GL renderer: ");
    html_escape(t, str(meta, "renderer"));
    put(t, "<br>reference: ");
    html_escape(t, str(meta, "reference"));
    put(t, "<br>machine: ");
    html_escape(t, str(meta, "machine"));
    put(t, "<br>command: <code>");
    html_escape(t, str(meta, "command"));
    put(t, "</code></p>\n");
    const char *ref_png = str(meta, "reference_png");
    if (*ref_png)
        put(t, "<figure><img src=\"%s\"><figcaption>reference</figcaption></figure>\n", ref_png);
    json_object *charts;
    if (json_object_object_get_ex(meta, "charts", &charts))
        for (size_t i = 0; i < json_object_array_length(charts); i++)
            put(t, "<p><img style=\"width:900px\" src=\"%s\"></p>\n",
                json_object_get_string(json_object_array_get_idx(charts, i)));
    put(t, "<table><tr><th class=l>run</th><th class=l>method</th><th class=l>params</th><th class=l>status</th>"
           "<th>image</th><th>error (relative, vs full)</th><th>frame ms</th><th>prepare ms</th><th>relMSE full</th>"
           "<th>relMSE matched</th><th>FLIP</th><th>SSIM</th></tr>\n");
    size_t count = json_object_array_length(runs);
    for (size_t i = 0; i < count; i++) {
        json_object *o = json_object_array_get_idx(runs, i);
        put(t, "<tr><td class=l>");
        html_escape(t, str(o, "run"));
        put(t, "</td><td class=l>");
        html_escape(t, str(o, "method"));
        put(t, "</td><td class=l><code>");
        html_escape(t, str(o, "params"));
        put(t, "</code></td><td class=l>");
        html_escape(t, str(o, "status"));
        if (strcmp(str(o, "status"), "ok")) {
            put(t, ": ");
            html_escape(t, str(o, "reason"));
        }
        put(t, "</td><td>");
        if (*str(o, "png"))
            put(t, "<img src=\"%s\">", str(o, "png"));
        put(t, "</td><td>");
        if (*str(o, "heatmap"))
            put(t, "<img src=\"%s\">", str(o, "heatmap"));
        put(t, "</td>");
        double vals[] = {num(o, "frame_ms", "median", NULL), num(o, "prepare_ms", NULL, NULL),
                         num(o, "metrics", "full", "relmse"), num(o, "metrics", "matched", "relmse"),
                         num(o, "metrics", "full", "flip"), num(o, "metrics", "full", "ssim")};
        for (size_t k = 0; k < sizeof vals / sizeof vals[0]; k++)
            put(t, vals[k] == vals[k] ? "<td>%.4g</td>" : "<td>–</td>", vals[k]);
        put(t, "</tr>\n");
    }
    put(t, "</table>\n</body></html>\n");
}

static int write_text(const char *dir, const char *name, text *t, char *why, size_t why_size)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    gi_error err;
    int ok = t->s && gi_file_write_atomic(path, t->s, t->len, &err) == GI_OK;
    if (!ok)
        snprintf(why, why_size, "%s", t->s ? err.text : "out of memory");
    free(t->s);
    memset(t, 0, sizeof *t);
    return ok;
}

int report_write(const char *dir, json_object *runs, json_object *meta, char *why, size_t why_size)
{
    text t = {0};
    write_csv(&t, runs);
    if (!write_text(dir, "runs.csv", &t, why, why_size))
        return 0;
    write_frames_csv(&t, runs);
    if (!write_text(dir, "frames.csv", &t, why, why_size))
        return 0;
    write_curves_csv(&t, runs);
    if (!write_text(dir, "curves.csv", &t, why, why_size))
        return 0;
    write_md(&t, runs, meta);
    if (!write_text(dir, "report.md", &t, why, why_size))
        return 0;
    write_html(&t, runs, meta);
    return write_text(dir, "index.html", &t, why, why_size);
}
