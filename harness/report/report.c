/* runs.csv, report.md and index.html from run records (report.h). */
#define _POSIX_C_SOURCE 200809L
#include "report.h"
#include "text.h"

#include "cli.h"
#include "gi/cache.h"
#include "gi/image.h"
#include "gi/shader.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/utsname.h>
#include <time.h>
#include <unistd.h>

const char *const report_metric_keys[] = {
    "relmse", "rmse", "mae", "psnr", "ssim", "flip", "mean_lum_diff_pct", NULL};

/* The machine, for the report: kernel, architecture, cores. */
static void machine_string(char *buf, size_t size)
{
    struct utsname u;
    if (uname(&u) != 0)
        snprintf(buf, size, "unknown");
    else
        snprintf(buf, size, "%s %s %s, %ld cores", u.sysname, u.release, u.machine,
                 sysconf(_SC_NPROCESSORS_ONLN));
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

json_object *report_meta_new(const char *title, const char *command, int argc, char **argv,
                             const char *renderer, const char *reference)
{
    char cmd[4096], machine[256], date[64];
    command_string(command, argc, argv, cmd, sizeof cmd);
    machine_string(machine, sizeof machine);
    date_string(date, sizeof date);
    json_object *meta = json_object_new_object();
    json_object_object_add(meta, "title", json_object_new_string(title));
    json_object_object_add(meta, "command", json_object_new_string(cmd));
    json_object_object_add(
        meta, "renderer",
        json_object_new_string(renderer && *renderer ? renderer : "(no run finished)"));
    json_object_object_add(meta, "reference", json_object_new_string(reference));
    json_object_object_add(meta, "machine", json_object_new_string(machine));
    json_object_object_add(meta, "date", json_object_new_string(date));
    return meta;
}

/* The text every output file is built in (text.h). */
typedef gi_text text;
#define put gi_text_put

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
static const char *const tradeoff_keys[] = {"seed",
                                            "time_to_final_error_s",
                                            "frames_to_final_error",
                                            "speedup_vs_pt",
                                            "speedup_vs_pt_matched",
                                            "speedup_extrapolated",
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

static void write_csv(text *t, json_object *runs)
{
    const char *stages[32], *pstages[32], *stats[64];
    int ns = stage_names(runs, stages, 32);
    int np = key_names(runs, "prepare_stages", pstages, 32);
    int nst = key_names(runs, "stats", stats, 64);
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
    for (size_t k = 0; k < EXTRA_COLUMNS; k++)
        put(t, ",%s", extra_columns[k].column);
    put(t, "\n");
    size_t count = json_object_array_length(runs);
    for (size_t i = 0; i < count; i++) {
        json_object *o = json_object_array_get_idx(runs, i);
        const char *fields[] = {"run",    "scene",  "method",   "params",
                                "status", "reason", "renderer", "timer"};
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
            csv_num(t, num(o, tradeoff_keys[k], NULL, NULL), 0);
        for (size_t k = 0; k < EXTRA_COLUMNS; k++)
            csv_num(t, num(o, extra_columns[k].k1, extra_columns[k].k2, extra_columns[k].k3),
                    k + 1 == EXTRA_COLUMNS);
    }
}

/* frames.csv: every timed frame of every run (per-frame time of animations). */
static void write_frames_csv(text *t, json_object *runs)
{
    put(t, "run,label,frame,frame_ms\n");
    size_t count = json_object_array_length(runs);
    for (size_t i = 0; i < count; i++) {
        json_object *o = json_object_array_get_idx(runs, i), *f;
        if (!json_object_object_get_ex(o, "frame_samples_ms", &f) ||
            !json_object_is_type(f, json_type_array))
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

/* Whether dir/rel is a file (links in the report point only at files that exist). */
static int exists_in(const char *dir, const char *rel)
{
    if (!rel || !*rel)
        return 0;
    char path[4096];
    if (snprintf(path, sizeof path, "%s/%s", dir, rel) >= (int)sizeof path)
        return 0;
    struct stat sb;
    return stat(path, &sb) == 0 && S_ISREG(sb.st_mode);
}

static void write_md(text *t, const char *dir, json_object *runs, json_object *meta)
{
    put(t, "# %s\n\n", str(meta, "title"));
    put(t, "- command: `%s`\n", str(meta, "command"));
    put(t, "- GL renderer: %s\n", str(meta, "renderer"));
    put(t, "- reference: %s\n", str(meta, "reference"));
    put(t, "- machine: %s\n", str(meta, "machine"));
    put(t, "- date: %s\n\n", str(meta, "date"));
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
        const char *status = str(o, "status");
        put(t, "| %s | %s | `%s` | %s%s%s |", str(o, "run"), str(o, "method"), str(o, "params"),
            status, strcmp(status, "ok") ? ": " : "", strcmp(status, "ok") ? str(o, "reason") : "");
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
    put(t, "\nImages (tonemapped at the report's exposure) and relative error against the full "
           "reference "
           "(log scale, colour bar in each map):\n\n");
    const char *ref_png = str(meta, "reference_png");
    if (exists_in(dir, ref_png))
        put(t, "reference: ![reference](%s)\n\n", ref_png);
    for (size_t i = 0; i < count; i++) {
        json_object *o = json_object_array_get_idx(runs, i);
        int png = exists_in(dir, str(o, "png")), heat = exists_in(dir, str(o, "heatmap"));
        if (!png && !heat)
            continue;
        put(t, "%s:", str(o, "run"));
        if (png)
            put(t, " ![%s](%s)", str(o, "run"), str(o, "png"));
        if (heat)
            put(t, " ![error](%s)", str(o, "heatmap"));
        put(t, "\n\n");
    }
    json_object *charts;
    if (json_object_object_get_ex(meta, "charts", &charts)) {
        put(t, "\n");
        for (size_t i = 0; i < json_object_array_length(charts); i++) {
            const char *c = json_object_get_string(json_object_array_get_idx(charts, i));
            if (exists_in(dir, c))
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

static void html_escape(text *t, const char *s)
{
    for (; *s; s++) {
        switch (*s) {
        case '<':
            put(t, "&lt;");
            break;
        case '>':
            put(t, "&gt;");
            break;
        case '&':
            put(t, "&amp;");
            break;
        case '"':
            put(t, "&quot;");
            break;
        default:
            put(t, "%c", *s);
        }
    }
}

/* The page's script and style, embedded at build time (harness/CMakeLists.txt). */
extern const gi_shader_source gi_report_assets[];

static const char *asset(const char *name)
{
    for (const gi_shader_source *a = gi_report_assets; a->name; a++)
        if (!strcmp(a->name, name))
            return a->text;
    return "";
}

/* A string field as stored (str() swaps "params" for "params_full"). */
static const char *raw(json_object *o, const char *key)
{
    json_object *v;
    if (o && json_object_object_get_ex(o, key, &v) && json_object_is_type(v, json_type_string))
        return json_object_get_string(v);
    return "";
}

static const char b64_chars[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

/* Writes the linear RGB of dir/exr_rel as a script beside it (same stem,
 * .js) for the viewer's exposure control and pixel values: GIB_HDR(key,
 * width, height, base64 of RGBE bytes), the key being the script's path
 * relative to the page. js_rel gets that path; 0 when there is no image. */
static int write_hdr_js(const char *dir, const char *exr_rel, char *js_rel, size_t js_size)
{
    size_t n = strlen(exr_rel);
    if (n < 5 || strcmp(exr_rel + n - 4, ".exr") || !exists_in(dir, exr_rel))
        return 0;
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, exr_rel);
    gi_error err;
    gi_image *img = gi_image_read(path, &err);
    if (!img)
        return 0;
    snprintf(js_rel, js_size, "%.*s.js", (int)(n - 4), exr_rel);
    size_t px = (size_t)img->width * img->height, nb = px * 4;
    unsigned char *rgbe = malloc(nb);
    text t = {0};
    int ok = rgbe != NULL;
    for (size_t i = 0; ok && i < px; i++) {
        float *c = img->rgba + i * 4;
        float r = isfinite(c[0]) && c[0] > 0 ? c[0] : 0, g = isfinite(c[1]) && c[1] > 0 ? c[1] : 0,
              b = isfinite(c[2]) && c[2] > 0 ? c[2] : 0;
        float v = r > g ? (r > b ? r : b) : (g > b ? g : b);
        unsigned char *o = rgbe + i * 4;
        if (v < 1e-32f) {
            o[0] = o[1] = o[2] = o[3] = 0;
        } else {
            int e;
            float scale = frexpf(v, &e) * 256.0f / v;
            o[0] = (unsigned char)(r * scale);
            o[1] = (unsigned char)(g * scale);
            o[2] = (unsigned char)(b * scale);
            o[3] = (unsigned char)(e + 128);
        }
    }
    if (ok) {
        put(&t, "GIB_HDR(\"%s\", %u, %u, \"", js_rel, img->width, img->height);
        for (size_t i = 0; i < nb; i += 3) {
            unsigned v = (unsigned)rgbe[i] << 16 | (i + 1 < nb ? (unsigned)rgbe[i + 1] << 8 : 0) |
                         (i + 2 < nb ? rgbe[i + 2] : 0);
            put(&t, "%c%c%c%c", b64_chars[v >> 18 & 63], b64_chars[v >> 12 & 63],
                i + 1 < nb ? b64_chars[v >> 6 & 63] : '=', i + 2 < nb ? b64_chars[v & 63] : '=');
        }
        put(&t, "\");\n");
        ok = snprintf(path, sizeof path, "%s/%s", dir, js_rel) < (int)sizeof path && t.s &&
             gi_file_write_atomic(path, t.s, t.len, &err) == GI_OK;
    }
    free(t.s);
    free(rgbe);
    gi_image_free(img);
    return ok;
}

/* exr_rel with .png for .exr, when that file exists. */
static const char *png_of(const char *dir, const char *exr_rel, char *buf, size_t size)
{
    size_t n = strlen(exr_rel);
    if (n < 5 || strcmp(exr_rel + n - 4, ".exr"))
        return NULL;
    snprintf(buf, size, "%.*s.png", (int)(n - 4), exr_rel);
    return exists_in(dir, buf) ? buf : NULL;
}

/* A viewer image: label, title (hover), the PNG, the HDR script, error maps, info line. */
static json_object *viewer_image(const char *dir, const char *label, const char *title,
                                 const char *png, const char *exr)
{
    json_object *im = json_object_new_object();
    json_object_object_add(im, "label", json_object_new_string(label));
    json_object_object_add(im, "title", json_object_new_string(title));
    char buf[4096], js[4096];
    if (!png && exr)
        png = png_of(dir, exr, buf, sizeof buf);
    if (png && exists_in(dir, png))
        json_object_object_add(im, "png", json_object_new_string(png));
    if (exr && write_hdr_js(dir, exr, js, sizeof js))
        json_object_object_add(im, "hdr", json_object_new_string(js));
    json_object_object_add(im, "maps", json_object_new_array());
    return im;
}

/* A run's short name: method and the parameters the study set. */
static void run_label(json_object *o, char *buf, size_t size)
{
    const char *p = raw(o, "params"), *l = raw(o, "label");
    snprintf(buf, size, "%s %s%s%s", str(o, "method"), *p ? p : "(defaults)", *l ? " " : "", l);
}

static void run_info(json_object *o, char *buf, size_t size)
{
    snprintf(buf, size, "run %s, %s", str(o, "run"), str(o, "status"));
    const char *names[] = {"frame ms (median)", "prepare ms", "relMSE full",
                           "relMSE matched",    "FLIP full",  "SSIM full"};
    double vals[] = {num(o, "frame_ms", "median", NULL),  num(o, "prepare_ms", NULL, NULL),
                     num(o, "metrics", "full", "relmse"), num(o, "metrics", "matched", "relmse"),
                     num(o, "metrics", "full", "flip"),   num(o, "metrics", "full", "ssim")};
    for (size_t k = 0; k < sizeof vals / sizeof vals[0]; k++)
        if (vals[k] == vals[k]) {
            size_t used = strlen(buf);
            snprintf(buf + used, size - used, "; %s %.4g", names[k], vals[k]);
        }
    size_t used = strlen(buf);
    snprintf(buf + used, size - used, "; params %s", str(o, "params"));
}

static json_object *find_run(json_object *runs, const char *id)
{
    for (size_t i = 0; i < json_object_array_length(runs); i++) {
        json_object *o = json_object_array_get_idx(runs, i);
        if (!strcmp(raw(o, "run"), id))
            return o;
    }
    return NULL;
}

static void add_run_image(const char *dir, json_object *images, json_object *o)
{
    if (strcmp(raw(o, "status"), "ok"))
        return;
    char label[600], title[8192], info[8192];
    run_label(o, label, sizeof label);
    /* repeats of one setting: numbered */
    int same = 0;
    for (size_t k = 0; k < json_object_array_length(images); k++)
        same += !strncmp(raw(json_object_array_get_idx(images, k), "label"), label, strlen(label));
    if (same) {
        size_t used = strlen(label);
        snprintf(label + used, sizeof label - used, " #%d", same + 1);
    }
    snprintf(title, sizeof title, "run %s: %s", raw(o, "run"), str(o, "params"));
    const char *png = raw(o, "png");
    json_object *im = viewer_image(dir, label, title, *png ? png : NULL,
                                   *raw(o, "image") ? raw(o, "image") : NULL);
    if (!json_object_object_get_ex(im, "png", NULL) &&
        !json_object_object_get_ex(im, "hdr", NULL)) {
        json_object_put(im);
        return;
    }
    json_object *maps;
    json_object_object_get_ex(im, "maps", &maps);
    const char *heat = raw(o, "heatmap");
    if (exists_in(dir, heat)) {
        json_object *m = json_object_new_object();
        json_object_object_add(m, "name", json_object_new_string("relative error"));
        json_object_object_add(m, "png", json_object_new_string(heat));
        json_object_array_add(maps, m);
    }
    char flip[4200];
    /* FLIP's map: named in the record, or beside the heat map (older records) */
    snprintf(flip, sizeof flip, "%s", *raw(o, "flip_map") ? raw(o, "flip_map") : heat);
    char *slash = strrchr(flip, '/');
    if (slash) {
        snprintf(slash + 1, sizeof flip - (size_t)(slash + 1 - flip), "flip.png");
        if (exists_in(dir, flip)) {
            json_object *m = json_object_new_object();
            json_object_object_add(m, "name", json_object_new_string("FLIP"));
            json_object_object_add(m, "png", json_object_new_string(flip));
            json_object_array_add(maps, m);
        }
    }
    run_info(o, info, sizeof info);
    json_object_object_add(im, "info", json_object_new_string(info));
    json_object_array_add(images, im);
}

/* The viewer's data: per reference set, its references and runs
 * (meta "references", from study), or one set with the report's reference
 * and every run (compare). */
static json_object *viewer_sets(const char *dir, json_object *runs, json_object *meta)
{
    json_object *sets = json_object_new_array(), *refs;
    double ev = num(meta, "exposure", NULL, NULL);
    if (json_object_object_get_ex(meta, "references", &refs) &&
        json_object_is_type(refs, json_type_array)) {
        for (size_t r = 0; r < json_object_array_length(refs); r++) {
            json_object *rs = json_object_array_get_idx(refs, r), *set = json_object_new_object();
            json_object *images = json_object_new_array(), *matched, *ids;
            json_object_object_add(set, "name", json_object_new_string(raw(rs, "name")));
            char label[128];
            snprintf(label, sizeof label, "reference, full GI (%g bounces)",
                     num(rs, "bounces", NULL, NULL));
            json_object_array_add(images,
                                  viewer_image(dir, label, raw(rs, "full"), NULL, raw(rs, "full")));
            if (json_object_object_get_ex(rs, "matched", &matched))
                for (size_t k = 0; k < json_object_array_length(matched); k++) {
                    json_object *m = json_object_array_get_idx(matched, k);
                    snprintf(label, sizeof label, "reference, %g bounce%s",
                             num(m, "bounces", NULL, NULL),
                             num(m, "bounces", NULL, NULL) == 1 ? "" : "s");
                    json_object_array_add(
                        images, viewer_image(dir, label, raw(m, "image"), NULL, raw(m, "image")));
                }
            if (json_object_object_get_ex(rs, "runs", &ids))
                for (size_t k = 0; k < json_object_array_length(ids); k++) {
                    json_object *o =
                        find_run(runs, json_object_get_string(json_object_array_get_idx(ids, k)));
                    if (o)
                        add_run_image(dir, images, o);
                }
            json_object_object_add(set, "images", images);
            json_object_object_add(set, "exposure", json_object_new_double(ev == ev ? ev : 0));
            json_object_array_add(sets, set);
        }
        return sets;
    }
    json_object *set = json_object_new_object(), *images = json_object_new_array();
    const char *ref_png = raw(meta, "reference_png");
    if (exists_in(dir, ref_png)) {
        char exr[4096];
        size_t n = strlen(ref_png);
        snprintf(exr, sizeof exr, "%.*s.exr", n > 4 ? (int)(n - 4) : 0, ref_png);
        json_object_array_add(images, viewer_image(dir, "reference", ref_png, ref_png, exr));
    }
    for (size_t i = 0; i < json_object_array_length(runs); i++)
        add_run_image(dir, images, json_object_array_get_idx(runs, i));
    json_object_object_add(set, "name", json_object_new_string(raw(meta, "title")));
    json_object_object_add(set, "images", images);
    json_object_object_add(set, "exposure", json_object_new_double(ev == ev ? ev : 0));
    json_object_array_add(sets, set);
    return sets;
}

static void html_num(text *t, double v)
{
    if (v == v)
        put(t, "<td data-v=\"%.9g\">%.4g</td>", v, v);
    else
        put(t, "<td data-v=\"\">–</td>");
}

/* Inline markdown: `code` spans, the rest escaped. */
static void md_inline(text *t, const char *s, size_t n)
{
    int code = 0;
    char buf[2];
    buf[1] = '\0';
    for (size_t i = 0; i < n; i++) {
        if (s[i] == '`') {
            put(t, code ? "</code>" : "<code>");
            code = !code;
            continue;
        }
        buf[0] = s[i];
        html_escape(t, buf);
    }
    if (code)
        put(t, "</code>");
}

/* The speed-against-accuracy text of tradeoff.c (markdown: headings,
 * paragraphs and pipe tables) as HTML, tables sortable and scrolling in
 * their box. */
static void md_to_html(text *t, const char *md)
{
    int in_table = 0, in_par = 0, row = 0;
    while (*md) {
        const char *end = strchr(md, '\n');
        size_t n = end ? (size_t)(end - md) : strlen(md);
        const char *next = end ? end + 1 : md + n;
        while (n && (md[n - 1] == ' ' || md[n - 1] == '\r'))
            n--;
        int is_row = n && md[0] == '|';
        if (!is_row && in_table) {
            put(t, "</tbody></table></div>\n");
            in_table = 0;
        }
        if ((is_row || !n || md[0] == '#') && in_par) {
            put(t, "</p>\n");
            in_par = 0;
        }
        if (is_row) {
            if (!in_table) {
                put(t, "<div class=\"scroll\"><table class=\"sortable\"><thead>");
                in_table = 1;
                row = 0;
            }
            if (row == 1 && strspn(md, "|-: ") == n) { /* the alignment row */
                row++;
                md = next;
                continue;
            }
            put(t, "<tr>");
            const char *c = md + 1, *stop = md + n;
            while (c < stop) {
                const char *bar = memchr(c, '|', (size_t)(stop - c));
                if (!bar)
                    bar = stop;
                const char *a = c, *b = bar;
                while (a < b && *a == ' ')
                    a++;
                while (b > a && b[-1] == ' ')
                    b--;
                put(t, row == 0 ? "<th class=l>" : "<td%s>",
                    row && b > a && (*a < '0' || *a > '9') ? " class=l" : "");
                md_inline(t, a, (size_t)(b - a));
                put(t, row == 0 ? "</th>" : "</td>");
                c = bar + 1;
            }
            put(t, "</tr>");
            if (row == 0)
                put(t, "</thead><tbody>");
            put(t, "\n");
            row++;
        } else if (n && md[0] == '#') {
            size_t h = strspn(md, "#");
            const char *a = md + h;
            while (*a == ' ')
                a++;
            int level = h < 3 ? 3 : h > 5 ? 5 : (int)h; /* below the page's h2 sections */
            put(t, "<h%d>", level);
            md_inline(t, a, (size_t)(md + n - a));
            put(t, "</h%d>\n", level);
        } else if (n) {
            put(t, in_par ? "\n" : "<p>");
            in_par = 1;
            md_inline(t, md, n);
        }
        md = next;
    }
    if (in_table)
        put(t, "</tbody></table></div>\n");
    if (in_par)
        put(t, "</p>\n");
}

static void params_cell(text *t, json_object *o)
{
    const char *given = raw(o, "params"), *full = str(o, "params");
    put(t, "<td class=\"params\" data-v=\"");
    html_escape(t, given);
    put(t, "\"><details><summary title=\"");
    html_escape(t, full);
    put(t, "\"><code>");
    html_escape(t, *given ? given : "(defaults)");
    put(t, "</code></summary><code>");
    html_escape(t, full);
    put(t, "</code></details></td>");
}

static void write_html(text *t, const char *dir, json_object *runs, json_object *meta)
{
    put(t, "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
           "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\"><title>");
    html_escape(t, str(meta, "title"));
    put(t, "</title>\n<style>\n%s</style>\n</head><body>\n<h1>", asset("viewer.css"));
    html_escape(t, str(meta, "title"));
    put(t, "</h1>\n<dl class=\"meta\">");
    const char *keys[] = {"command", "renderer", "reference", "machine", "date"};
    const char *names[] = {"command", "GL renderer", "reference", "machine", "date"};
    for (int k = 0; k < 5; k++) {
        put(t, "<dt>%s</dt><dd>%s", names[k], k == 0 ? "<code>" : "");
        html_escape(t, str(meta, keys[k]));
        put(t, "%s</dd>", k == 0 ? "</code>" : "");
    }
    put(t,
        "</dl>\n<nav><a href=\"#images\">images</a><a href=\"#runs\">runs</a><a "
        "href=\"#stages\">stage "
        "timings</a><a href=\"#tradeoff\">speed against accuracy</a>%s<a "
        "href=\"#charts\">charts</a></nav>\n",
        json_object_object_get_ex(meta, "animation_markdown", NULL) &&
                *str(meta, "animation_markdown")
            ? "<a href=\"#animation\">animation</a>"
            : "");
    put(t, "<p>Errors are against the full-GI reference (\"full\") and against the reference "
           "limited to the "
           "method's own bounce count (\"matched\"). Times are medians over the timed frames; on a "
           "software "
           "renderer only ratios within one study mean anything.</p>\n");

    /* the image viewers, one per reference set */
    json_object *sets = viewer_sets(dir, runs, meta);
    put(t, "<h2 id=\"images\">Images</h2>\n");
    for (size_t i = 0; i < json_object_array_length(sets); i++) {
        json_object *set = json_object_array_get_idx(sets, i);
        put(t, "<h3>");
        html_escape(t, raw(set, "name"));
        put(t, "</h3>\n<div class=\"gib-viewer\" data-set=\"%zu\"></div>\n", i);
    }
    put(t, "<noscript><p>The image viewer needs JavaScript; the images are in runs/ and "
           "references/.</p></noscript>\n");

    /* every run */
    put(t,
        "<h2 id=\"runs\">Runs</h2>\n<p>Click a column header to sort. Parameters: those the study "
        "set; click "
        "for the full string (defaults included).</p>\n<div class=\"scroll\"><table "
        "class=\"sortable\"><thead><tr>"
        "<th class=l>run</th><th class=l>method</th><th class=l>params</th><th "
        "class=l>status</th><th>frames</th>"
        "<th>frame ms</th><th>prepare ms</th><th>relMSE full</th><th>relMSE matched</th><th>FLIP "
        "full</th>"
        "<th>SSIM full</th><th>mean lum. diff %%</th><th>speed-up vs PT</th><th>speed-up vs PT, "
        "matched</th>"
        "<th>leaked energy full</th><th>peak RSS MiB</th><th>data MiB</th></tr></thead><tbody>\n");
    size_t count = json_object_array_length(runs);
    for (size_t i = 0; i < count; i++) {
        json_object *o = json_object_array_get_idx(runs, i);
        put(t, "<tr><td class=l><code>");
        html_escape(t, raw(o, "run"));
        put(t, "</code></td><td class=l>");
        html_escape(t, raw(o, "method"));
        put(t, "</td>");
        params_cell(t, o);
        put(t, "<td class=\"l reason\">");
        html_escape(t, raw(o, "status"));
        if (strcmp(raw(o, "status"), "ok")) {
            put(t, ": ");
            html_escape(t, raw(o, "reason"));
        }
        put(t, "</td>");
        html_num(t, num(o, "frames", NULL, NULL));
        html_num(t, num(o, "frame_ms", "median", NULL));
        html_num(t, num(o, "prepare_ms", NULL, NULL));
        html_num(t, num(o, "metrics", "full", "relmse"));
        html_num(t, num(o, "metrics", "matched", "relmse"));
        html_num(t, num(o, "metrics", "full", "flip"));
        html_num(t, num(o, "metrics", "full", "ssim"));
        html_num(t, num(o, "metrics", "full", "mean_lum_diff_pct"));
        html_num(t, num(o, "speedup_vs_pt", NULL, NULL));
        html_num(t, num(o, "speedup_vs_pt_matched", NULL, NULL));
        html_num(t, num(o, "metrics", "full", "leaked_energy"));
        html_num(t, num(o, "peak_rss_mib", NULL, NULL));
        html_num(t, num(o, "stats", "data_bytes", NULL) / (1024.0 * 1024.0));
        put(t, "</tr>\n");
    }
    put(t, "</tbody></table></div>\n");

    /* stage timings */
    const char *stages[32];
    int ns = stage_names(runs, stages, 32);
    put(t, "<h2 id=\"stages\">Stage timings</h2>\n");
    if (ns == 0) {
        put(t, "<p>No run reported stage timings.</p>\n");
    } else {
        put(t, "<p>Milliseconds, median (min – max) over the timed frames.</p>\n<div "
               "class=\"scroll\"><table "
               "class=\"sortable\"><thead><tr><th class=l>run</th><th class=l>method</th><th "
               "class=l>params</th>");
        for (int k = 0; k < ns; k++) {
            put(t, "<th>");
            html_escape(t, stages[k]);
            put(t, "</th>");
        }
        put(t, "<th>frame</th></tr></thead><tbody>\n");
        for (size_t i = 0; i < count; i++) {
            json_object *o = json_object_array_get_idx(runs, i);
            if (strcmp(raw(o, "status"), "ok"))
                continue;
            put(t, "<tr><td class=l><code>");
            html_escape(t, raw(o, "run"));
            put(t, "</code></td><td class=l>");
            html_escape(t, raw(o, "method"));
            put(t, "</td>");
            params_cell(t, o);
            for (int k = 0; k <= ns; k++) {
                const char *k1 = k < ns ? "stages" : "frame_ms", *k2 = k < ns ? stages[k] : NULL;
                double med = k < ns ? num(o, k1, k2, "median") : num(o, k1, "median", NULL);
                double mn = k < ns ? num(o, k1, k2, "min") : num(o, k1, "min", NULL);
                double mx = k < ns ? num(o, k1, k2, "max") : num(o, k1, "max", NULL);
                if (med == med)
                    put(t, "<td data-v=\"%.9g\">%.4g <small>(%.4g – %.4g)</small></td>", med, med,
                        mn, mx);
                else
                    put(t, "<td data-v=\"\">–</td>");
            }
            put(t, "</tr>\n");
        }
        put(t, "</tbody></table></div>\n");
    }

    /* speed against accuracy (tradeoff.c's tables) */
    put(t, "<h2 id=\"tradeoff\">Speed against accuracy</h2>\n");
    json_object *extra;
    if (json_object_object_get_ex(meta, "markdown", &extra) && *json_object_get_string(extra))
        md_to_html(t, json_object_get_string(extra));
    else
        put(t, "<p>Not computed for this report.</p>\n");

    if (json_object_object_get_ex(meta, "animation_markdown", &extra) &&
        *json_object_get_string(extra)) {
        put(t, "<h2 id=\"animation\">Animated runs, frame by frame</h2>\n");
        md_to_html(t, json_object_get_string(extra));
    }

    put(t, "<h2 id=\"charts\">Charts</h2>\n");
    json_object *charts;
    int nc = 0;
    if (json_object_object_get_ex(meta, "charts", &charts))
        for (size_t i = 0; i < json_object_array_length(charts); i++) {
            const char *c = json_object_get_string(json_object_array_get_idx(charts, i));
            if (!exists_in(dir, c))
                continue;
            put(t, "<figure><img class=\"chart\" alt=\"");
            html_escape(t, c);
            put(t, "\" src=\"");
            html_escape(t, c);
            put(t, "\"><figcaption>");
            html_escape(t, c);
            put(t, "</figcaption></figure>\n");
            nc++;
        }
    if (!nc)
        put(t, "<p>No charts.</p>\n");

    /* the viewer's data; json-c escapes '/', so no "</script>" can occur */
    put(t, "<script type=\"application/json\" id=\"gib-data\">");
    json_object *data = json_object_new_object();
    json_object_object_add(data, "sets", sets);
    put(t, "%s", json_object_to_json_string_ext(data, JSON_C_TO_STRING_PLAIN));
    json_object_put(data);
    put(t, "</script>\n<script>\n%s</script>\n</body></html>\n", asset("viewer.js"));
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
    /* every run record as it is (scripts read this: scripts/scale_fit.py) */
    put(&t, "%s\n",
        json_object_to_json_string_ext(runs, JSON_C_TO_STRING_PRETTY | JSON_C_TO_STRING_SPACED |
                                                 JSON_C_TO_STRING_NOSLASHESCAPE));
    if (!write_text(dir, "runs.json", &t, why, why_size))
        return 0;
    write_csv(&t, runs);
    if (!write_text(dir, "runs.csv", &t, why, why_size))
        return 0;
    write_frames_csv(&t, runs);
    if (!write_text(dir, "frames.csv", &t, why, why_size))
        return 0;
    write_curves_csv(&t, runs);
    if (!write_text(dir, "curves.csv", &t, why, why_size))
        return 0;
    write_md(&t, dir, runs, meta);
    if (!write_text(dir, "report.md", &t, why, why_size))
        return 0;
    write_html(&t, dir, runs, meta);
    return write_text(dir, "index.html", &t, why, why_size);
}
