/* Method runs in child processes and their comparison (runner.h). */
#define _POSIX_C_SOURCE 200809L
#include "runner.h"

#include "cli.h"
#include "gi/cache.h"
#include "gi/image.h"
#include "gi/log.h"
#include "metrics.h"
#include "proc.h"
#include "report.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/statvfs.h>
#include <unistd.h>

/* runner_set_collect_only: nothing is run, cached results are taken */
static int collect_only;

void runner_set_collect_only(int on)
{
    collect_only = on;
}

#define MAX_ARGS 256 /* 40 of the run's own, 2 per parameter (up to 64), with room to spare */

typedef struct argv_builder {
    char *argv[MAX_ARGS + 1];
    int n;
} argv_builder;

static void arg(argv_builder *b, const char *fmt, const char *s)
{
    if (b->n >= MAX_ARGS)
        return;
    int len = snprintf(NULL, 0, fmt, s);
    char *copy = malloc((size_t)len + 1);
    if (!copy)
        return;
    snprintf(copy, (size_t)len + 1, fmt, s);
    b->argv[b->n] = copy;
    b->argv[++b->n] = NULL;
}

static void args_free(argv_builder *b)
{
    for (int i = 0; i < b->n; i++)
        free(b->argv[i]);
    b->n = 0;
}

static void argu(argv_builder *b, unsigned long v)
{
    char tmp[32];
    snprintf(tmp, sizeof tmp, "%lu", v);
    arg(b, "%s", tmp);
}

static void argf(argv_builder *b, double v)
{
    char tmp[32];
    snprintf(tmp, sizeof tmp, "%.9g", v);
    arg(b, "%s", tmp);
}

/* The argument vector as one line (the configuration a result depends on). */
static void join(const argv_builder *b, char *out, size_t size)
{
    out[0] = '\0';
    for (int i = 1; i < b->n; i++) {
        size_t used = strlen(out);
        snprintf(out + used, size - used, "%s%s", i > 1 ? " " : "", b->argv[i]);
    }
}

static void path_in(char *out, size_t size, const char *dir, const char *name)
{
    snprintf(out, size, "%s/%s", dir, name);
}

static json_object *base_record(const run_spec *s)
{
    json_object *o = json_object_new_object();
    char params[64 * 130] = ""; /* up to 64 "k=v" of up to 128 characters */
    for (uint32_t i = 0; i < s->param_count; i++) {
        size_t used = strlen(params);
        snprintf(params + used, sizeof params - used, "%s%s", i ? "," : "", s->params[i]);
    }
    json_object_object_add(o, "run", json_object_new_string(s->run_id));
    json_object_object_add(o, "scene", json_object_new_string(s->scene));
    json_object_object_add(o, "method", json_object_new_string(s->method));
    json_object_object_add(o, "params", json_object_new_string(params));
    json_object_object_add(o, "frames", json_object_new_int((int32_t)s->frames));
    json_object_object_add(o, "seed", json_object_new_int64(s->seed));
    json_object_object_add(o, "width", json_object_new_int((int32_t)s->width));
    json_object_object_add(o, "height", json_object_new_int((int32_t)s->height));
    if (s->label)
        json_object_object_add(o, "label", json_object_new_string(s->label));
    return o;
}

json_object *runner_not_applicable(const run_spec *s, const char *reason)
{
    json_object *o = base_record(s);
    json_object_object_add(o, "status", json_object_new_string("n/a"));
    json_object_object_add(o, "reason", json_object_new_string(reason));
    return o;
}

static void fail_record(json_object *o, const char *reason)
{
    json_object_object_add(o, "status", json_object_new_string("failed"));
    json_object_object_add(o, "reason", json_object_new_string(reason));
}

/* A run whose image holds NaN or infinite pixels has failed, however
 * small its error over the others (the metrics leave such pixels out):
 * 1 and why when `exr` has any; 0 when it has none or cannot be read (the
 * comparison reports an unreadable image itself). */
static int nonfinite_output(const char *exr, char *why, size_t why_size)
{
    gi_error err;
    gi_image *img = gi_image_read(exr, &err);
    if (!img)
        return 0;
    size_t n = (size_t)img->width * img->height, bad = 0;
    for (size_t i = 0; i < n; i++)
        bad += !(isfinite(img->rgba[4 * i]) && isfinite(img->rgba[4 * i + 1]) &&
                 isfinite(img->rgba[4 * i + 2]));
    gi_image_free(img);
    if (bad)
        snprintf(why, why_size, "non-finite output: %zu of %zu pixels are NaN or infinite", bad, n);
    return bad != 0;
}

/* The number of non-finite pixels that `gibench diff --json` counted in
 * image `which` ("test" or "reference"). */
static int64_t diff_nonfinite(json_object *m, const char *which)
{
    json_object *img, *v;
    if (json_object_object_get_ex(m, which, &img) &&
        json_object_object_get_ex(img, "nonfinite_pixels", &v))
        return json_object_get_int64(v);
    return 0;
}

json_object *runner_diff(const char *image, const char *reference, const char *heatmap,
                         const char *flip_map, float exposure, char *why, size_t why_size)
{
    argv_builder b = {0};
    arg(&b, "%s", cli_self_exe());
    arg(&b, "%s", "diff");
    arg(&b, "%s", image);
    arg(&b, "%s", reference);
    arg(&b, "%s", "--json");
    arg(&b, "%s", "--exposure");
    argf(&b, exposure);
    if (heatmap) {
        arg(&b, "%s", "--heatmap");
        arg(&b, "%s", heatmap);
    }
    if (flip_map) {
        arg(&b, "%s", "--flip-map");
        arg(&b, "%s", flip_map);
    }
    char out[4096], err[4096];
    snprintf(out, sizeof out, "%s.diff.json", image);
    snprintf(err, sizeof err, "%s.diff.log", image);
    cli_proc_result r;
    int started = cli_run(b.argv, 300, out, err, &r) == 0;
    args_free(&b);
    if (!started || !cli_proc_ok(&r)) {
        char d[600];
        cli_proc_describe(&r, d, sizeof d);
        snprintf(why, why_size, "diff against %s: %s", reference, d);
        return NULL;
    }
    json_object *m = cli_read_json(out);
    if (!m)
        snprintf(why, why_size, "diff against %s: unreadable output", reference);
    unlink(out);
    unlink(err);
    return m;
}

static void take_timings(json_object *rec, json_object *t)
{
    json_object *v, *render, *prepare;
    if (json_object_object_get_ex(t, "gl_renderer", &v))
        json_object_object_add(rec, "renderer", json_object_get(v));
    if (json_object_object_get_ex(t, "timer", &v))
        json_object_object_add(rec, "timer", json_object_get(v));
    /* which GPU and driver gave the timings (GL_VERSION carries the driver
     * version, e.g. "4.6.0 NVIDIA 580.159.03"), and which EGL device */
    static const char *const device_keys[] = {"gl_version", "gl_vendor", "egl_device"};
    for (size_t k = 0; k < sizeof device_keys / sizeof *device_keys; k++)
        if (json_object_object_get_ex(t, device_keys[k], &v))
            json_object_object_add(rec, device_keys[k], json_object_get(v));
    if (json_object_object_get_ex(t, "params", &v))
        json_object_object_add(rec, "params_full", json_object_get(v));
    if (json_object_object_get_ex(t, "stats", &v))
        json_object_object_add(rec, "stats", json_object_get(v));
    if (json_object_object_get_ex(t, "curve", &v))
        json_object_object_add(rec, "curve", json_object_get(v));
    /* memory: the render process's peak resident set, after prepare and in all */
    if (json_object_object_get_ex(t, "peak_rss_mib", &v))
        json_object_object_add(rec, "peak_rss_mib", json_object_get(v));
    if (json_object_object_get_ex(t, "peak_rss_prepare_mib", &v))
        json_object_object_add(rec, "peak_rss_prepare_mib", json_object_get(v));
    if (json_object_object_get_ex(t, "prepare", &prepare)) {
        /* the whole of prepare, and its stages (precomputation timings) */
        json_object *pst = json_object_new_object();
        json_object_object_foreach(prepare, name, st)
        {
            json_object *med;
            if (!json_object_object_get_ex(st, "median_ms", &med))
                continue;
            if (!strcmp(name, "frame"))
                json_object_object_add(rec, "prepare_ms", json_object_get(med));
            else
                json_object_object_add(pst, name, json_object_get(med));
        }
        json_object_object_add(rec, "prepare_stages", pst);
    }
    json_object *stages = json_object_new_object();
    if (json_object_object_get_ex(t, "render", &render)) {
        json_object_object_foreach(render, name, st)
        {
            json_object *med, *mn, *mx;
            if (!json_object_object_get_ex(st, "median_ms", &med))
                continue;
            if (strcmp(name, "frame") == 0) {
                json_object *f = json_object_new_object(), *samples;
                if (json_object_object_get_ex(st, "samples_ms", &samples))
                    json_object_object_add(rec, "frame_samples_ms", json_object_get(samples));
                json_object_object_add(f, "median", json_object_get(med));
                if (json_object_object_get_ex(st, "min_ms", &mn))
                    json_object_object_add(f, "min", json_object_get(mn));
                if (json_object_object_get_ex(st, "max_ms", &mx))
                    json_object_object_add(f, "max", json_object_get(mx));
                json_object_object_add(rec, "frame_ms", f);
            } else {
                json_object *sj = json_object_new_object();
                json_object_object_add(sj, "median", json_object_get(med));
                if (json_object_object_get_ex(st, "min_ms", &mn))
                    json_object_object_add(sj, "min", json_object_get(mn));
                if (json_object_object_get_ex(st, "max_ms", &mx))
                    json_object_object_add(sj, "max", json_object_get(mx));
                json_object_object_add(stages, name, sj);
            }
        }
    }
    json_object_object_add(rec, "stages", stages);
}

static int cmp_dbl(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The median of the finite values of v[0..n) (v is left as it was); NaN if none. */
static double rec_median(const double *v, uint32_t n)
{
    double *c = malloc((n + 1) * sizeof *c);
    uint32_t k = 0;
    for (uint32_t i = 0; c && i < n; i++)
        if (isfinite(v[i]))
            c[k++] = v[i];
    double m = NAN;
    if (c && k) {
        qsort(c, k, sizeof *c, cmp_dbl);
        m = k % 2 ? c[k / 2] : 0.5 * (c[k / 2 - 1] + c[k / 2]);
    }
    free(c);
    return m;
}

static json_object *num_or_null(double v)
{
    return isfinite(v) ? json_object_new_double(v) : NULL;
}

/* Mean absolute difference, per pixel and channel, of a and b over the
 * pixels where `ok` is set; NaN when none. */
static double mean_abs_diff(const gi_image *a, const gi_image *b, const uint8_t *ok)
{
    double sum = 0;
    uint64_t n = 0;
    for (size_t i = 0; i < (size_t)a->width * a->height; i++) {
        if (!ok[i])
            continue;
        for (int c = 0; c < 3; c++)
            sum += fabs((double)a->rgba[4 * i + c] - b->rgba[4 * i + c]);
        n += 3;
    }
    return n ? sum / (double)n : NAN;
}

static int finite_px(const gi_image *img, size_t i)
{
    return img && isfinite(img->rgba[4 * i]) && isfinite(img->rgba[4 * i + 1]) &&
           isfinite(img->rgba[4 * i + 2]);
}

/* Mean of the finite values of v[0..n), NaN if none. */
static double mean_finite(const double *v, uint32_t n)
{
    double s = 0;
    uint32_t k = 0;
    for (uint32_t i = 0; i < n; i++)
        if (isfinite(v[i])) {
            s += v[i];
            k++;
        }
    return k ? s / k : NAN;
}

static json_object *series_json(const double *v, uint32_t n)
{
    json_object *a = json_object_new_array();
    for (uint32_t i = 0; i < n; i++)
        json_object_array_add(a, num_or_null(v[i]));
    return a;
}

/* The per-frame series of an animated run, in the record's order. */
enum {
    RELMSE_FULL,
    RELMSE_MATCHED,
    LEAK_FULL,
    LUM_DIFF_FULL,
    FRAME_MS,
    CHANGE_METHOD,
    CHANGE_REF_FULL,
    CHANGE_REF_MATCHED,
    TEMPORAL_FULL,
    TEMPORAL_MATCHED,
    NOISE_FULL,
    SCENE_TIME,
    SERIES
};
static const char *const series_names[SERIES] = {"relmse_full",
                                                 "relmse_matched",
                                                 "leaked_energy_full",
                                                 "mean_lum_diff_pct_full",
                                                 "frame_ms",
                                                 "change_method",
                                                 "change_ref_full",
                                                 "change_ref_matched",
                                                 "temporal_error_full",
                                                 "temporal_error_matched",
                                                 "noise_floor_full",
                                                 "scene_time"};

/* Frame f of the method, its full and matched references and the second
 * full reference (img[3], when there is one), each of the run's size.
 * 0 with why when one is missing or of another size. */
static int read_frame_images(const run_spec *s, const char *frames_pattern, uint32_t f,
                             gi_image **img, char *why, size_t why_size)
{
    int ok = 1;
    char path[4200];
    gi_error err;
    cli_frame_path(frames_pattern, f, path, sizeof path);
    const char *paths[4] = {path, s->frame_ref_full[f], s->frame_ref_matched[f],
                            s->frame_ref_alt ? s->frame_ref_alt[f] : NULL};
    for (int k = 0; k < 4 && ok; k++) {
        if (!paths[k])
            continue;
        img[k] = gi_image_read(paths[k], &err);
        if (!img[k]) {
            snprintf(why, why_size, "frame %u: %s", f, err.text);
            ok = 0;
        } else if (img[k]->width != s->width || img[k]->height != s->height) {
            snprintf(why, why_size, "frame %u: %s is %ux%u, not %ux%u", f, paths[k], img[k]->width,
                     img[k]->height, s->width, s->height);
            ok = 0;
        }
    }
    return ok;
}

/* Frame f's error against its full and matched references. */
static int frame_errors(const run_spec *s, uint32_t f, gi_image *const *img, double **v, char *why,
                        size_t why_size)
{
    int ok = 1;
    gi_error err;
    gi_metrics m[2];
    gi_metrics_opts mo = {s->exposure, 0, 1, 0};
    for (int k = 0; k < 2 && ok; k++)
        if (gi_metrics_compute(img[0], img[1 + k], &mo, &m[k], &err) != GI_OK) {
            snprintf(why, why_size, "frame %u: %s", f, err.text);
            ok = 0;
        } else if (m[k].nonfinite_test || m[k].nonfinite_ref) {
            /* the metrics leave such pixels out: the frame is not judged on the rest */
            snprintf(why, why_size,
                     "frame %u: non-finite %s: %llu of %u pixels are NaN or infinite", f,
                     m[k].nonfinite_test ? "output" : "reference",
                     (unsigned long long)(m[k].nonfinite_test ? m[k].nonfinite_test
                                                              : m[k].nonfinite_ref),
                     s->width * s->height);
            ok = 0;
        }
    if (ok) {
        v[RELMSE_FULL][f] = m[0].relmse;
        v[RELMSE_MATCHED][f] = m[1].relmse;
        v[LEAK_FULL][f] = m[0].leaked_energy;
        v[LUM_DIFF_FULL][f] = m[0].mean_lum_diff_pct;
    }
    return ok;
}

/* How far the method's change from the frame before is from reference
 * img[1 + k]'s, pixel by pixel, over the pixels of `mask`; NaN when none. */
static double temporal_error(gi_image *const *img, gi_image *const *prev, int k,
                             const uint8_t *mask, size_t np)
{
    double sum = 0;
    uint64_t cnt = 0;
    for (size_t i = 0; i < np; i++) {
        if (!mask[i])
            continue;
        for (int c = 0; c < 3; c++) {
            double dm = (double)img[0]->rgba[4 * i + c] - prev[0]->rgba[4 * i + c];
            double dr = (double)img[1 + k]->rgba[4 * i + c] - prev[1 + k]->rgba[4 * i + c];
            sum += fabs(dm - dr);
        }
        cnt += 3;
    }
    return cnt ? sum / (double)cnt : NAN;
}

/* Frame f's noise floor and its change from the frame before (`prev`):
 * the method's, the references' and the temporal error. */
static int frame_changes(const run_spec *s, uint32_t f, gi_image *const *img, gi_image *const *prev,
                         double **v, char *why, size_t why_size)
{
    size_t np = (size_t)s->width * s->height;
    uint8_t *mask = malloc(np ? np : 1);
    if (!mask) {
        snprintf(why, why_size, "out of memory");
        return 0;
    }
    /* the noise floor: two renders of the reference with different seeds */
    for (size_t i = 0; i < np; i++)
        mask[i] = (uint8_t)(finite_px(img[1], i) && finite_px(img[3], i));
    v[NOISE_FULL][f] = img[3] ? mean_abs_diff(img[1], img[3], mask) : NAN;
    /* frame-to-frame change, over the pixels finite in both frames of all three */
    v[CHANGE_METHOD][f] = v[CHANGE_REF_FULL][f] = v[CHANGE_REF_MATCHED][f] = NAN;
    v[TEMPORAL_FULL][f] = v[TEMPORAL_MATCHED][f] = NAN;
    if (f > 0) {
        for (size_t i = 0; i < np; i++)
            mask[i] =
                (uint8_t)(finite_px(img[0], i) && finite_px(prev[0], i) && finite_px(img[1], i) &&
                          finite_px(prev[1], i) && finite_px(img[2], i) && finite_px(prev[2], i));
        v[CHANGE_METHOD][f] = mean_abs_diff(img[0], prev[0], mask);
        v[CHANGE_REF_FULL][f] = mean_abs_diff(img[1], prev[1], mask);
        v[CHANGE_REF_MATCHED][f] = mean_abs_diff(img[2], prev[2], mask);
        /* how far the method's change is from the reference's, pixel by pixel */
        for (int k = 0; k < 2; k++)
            v[k ? TEMPORAL_MATCHED : TEMPORAL_FULL][f] = temporal_error(img, prev, k, mask, np);
    }
    free(mask);
    return 1;
}

/* The record's "animation": every series and their summaries. */
static json_object *animation_json(const run_spec *s, double *const *v, uint32_t n)
{
    json_object *a = json_object_new_object();
    json_object_object_add(a, "fps", json_object_new_double(s->animate_fps));
    json_object_object_add(a, "frames", json_object_new_int((int32_t)n));
    json_object_object_add(a, "time0", json_object_new_double(s->time));
    for (int k = 0; k < SERIES; k++)
        json_object_object_add(a, series_names[k], series_json(v[k], n));
    double cm = mean_finite(v[CHANGE_METHOD], n), cf = mean_finite(v[CHANGE_REF_FULL], n),
           cmt = mean_finite(v[CHANGE_REF_MATCHED], n);
    double emax = NAN;
    for (uint32_t f = 0; f < n; f++)
        if (isfinite(v[RELMSE_FULL][f]) && !(v[RELMSE_FULL][f] <= emax))
            emax = v[RELMSE_FULL][f];
    json_object_object_add(a, "relmse_full_mean", num_or_null(mean_finite(v[RELMSE_FULL], n)));
    json_object_object_add(a, "relmse_full_max", num_or_null(emax));
    json_object_object_add(a, "relmse_matched_mean",
                           num_or_null(mean_finite(v[RELMSE_MATCHED], n)));
    json_object_object_add(a, "leaked_energy_full_mean", num_or_null(mean_finite(v[LEAK_FULL], n)));
    json_object_object_add(a, "frame_ms_median", num_or_null(rec_median(v[FRAME_MS], n)));
    json_object_object_add(a, "change_method_mean", num_or_null(cm));
    json_object_object_add(a, "change_ref_full_mean", num_or_null(cf));
    json_object_object_add(a, "change_ref_matched_mean", num_or_null(cmt));
    json_object_object_add(a, "flicker_full", num_or_null(cm - cf));
    json_object_object_add(a, "flicker_matched", num_or_null(cm - cmt));
    json_object_object_add(a, "temporal_error_full_mean",
                           num_or_null(mean_finite(v[TEMPORAL_FULL], n)));
    json_object_object_add(a, "temporal_error_matched_mean",
                           num_or_null(mean_finite(v[TEMPORAL_MATCHED], n)));
    json_object_object_add(a, "noise_floor_full_mean", num_or_null(mean_finite(v[NOISE_FULL], n)));
    return a;
}

json_object *runner_animation_metrics(const run_spec *s, const char *frames_pattern,
                                      json_object *timings, char *why, size_t why_size)
{
    uint32_t n = s->frame_ref_count;
    double *v[SERIES] = {0};
    for (int k = 0; k < SERIES; k++)
        v[k] = malloc((n + 1) * sizeof(double));
    gi_image *prev[3] = {0}; /* the method, full and matched references of the frame before */
    int ok = 1;
    for (uint32_t f = 0; f < n; f++)
        if (!s->frame_ref_full[f] || !s->frame_ref_matched[f]) {
            snprintf(why, why_size, "frame %u has no reference", f);
            return NULL;
        }
    for (int k = 0; k < SERIES; k++)
        ok &= v[k] != NULL;
    if (!ok)
        snprintf(why, why_size, "out of memory");
    /* the frame times the render kept: the timed frames, after the warm-up ones */
    json_object *samples = NULL, *render, *frame;
    if (json_object_object_get_ex(timings, "render", &render) &&
        json_object_object_get_ex(render, "frame", &frame))
        json_object_object_get_ex(frame, "samples_ms", &samples);
    uint32_t warm = s->warmup < n ? s->warmup : 0;
    for (uint32_t f = 0; f < n && ok; f++) {
        gi_image *img[4] = {0};
        ok = read_frame_images(s, frames_pattern, f, img, why, why_size);
        if (ok)
            ok = frame_errors(s, f, img, v, why, why_size);
        if (ok)
            ok = frame_changes(s, f, img, prev, v, why, why_size);
        v[SCENE_TIME][f] = s->time + (float)f / s->animate_fps; /* as render computes it */
        v[FRAME_MS][f] = NAN;
        if (f >= warm && samples && f - warm < json_object_array_length(samples))
            v[FRAME_MS][f] = json_object_get_double(json_object_array_get_idx(samples, f - warm));
        for (int k = 0; k < 3; k++) {
            gi_image_free(prev[k]);
            prev[k] = img[k];
        }
        gi_image_free(img[3]);
    }
    for (int k = 0; k < 3; k++)
        gi_image_free(prev[k]);
    json_object *a = ok ? animation_json(s, v, n) : NULL;
    for (int k = 0; k < SERIES; k++)
        free(v[k]);
    return a;
}

/* A result made before the metrics had the leaked energy or HDR-FLIP: its
 * image is compared again with the same references and only the missing
 * keys are added (every value it had stays as it was), so that resuming a
 * study fills the columns without rendering anything. Nothing happens when the
 * image is gone (committed results keep PNGs only). */
static void add_leak_to_cached(json_object *old, const run_spec *s, const char *exr,
                               const char *result)
{
    json_object *st, *metrics, *m;
    if (!json_object_object_get_ex(old, "status", &st) ||
        strcmp(json_object_get_string(st), "ok") ||
        !json_object_object_get_ex(old, "metrics", &metrics) || access(exr, R_OK) != 0)
        return;
    const char *refs[2] = {s->ref_full, s->ref_matched}, *names[2] = {"full", "matched"};
    static const char *const keys[] = {"leaked_energy",  "dark_fraction",     "dark_energy_ref",
                                       "dark_threshold", "hdr_flip",          "hdr_flip_start",
                                       "hdr_flip_stop",  "hdr_flip_exposures"};
    int changed = 0;
    for (int k = 0; k < 2; k++) {
        if (!refs[k] || !json_object_object_get_ex(metrics, names[k], &m) ||
            (json_object_object_get_ex(m, "leaked_energy", NULL) &&
             json_object_object_get_ex(m, "hdr_flip", NULL)))
            continue;
        char why[1024];
        json_object *fresh = runner_diff(exr, refs[k], NULL, NULL, s->exposure, why, sizeof why),
                    *v;
        for (size_t q = 0; fresh && q < sizeof keys / sizeof keys[0]; q++)
            if (!json_object_object_get_ex(m, keys[q], NULL) &&
                json_object_object_get_ex(fresh, keys[q], &v)) {
                json_object_object_add(m, keys[q], json_object_get(v));
                changed = 1;
            }
        json_object_put(fresh);
    }
    char why[GI_ERROR_MAX];
    if (changed && !cli_write_json(result, old, why, sizeof why))
        gi_log(GI_LOG_WARN, "%s", why);
}

/* The files of a run's directory. */
typedef struct run_files {
    char exr[4096], png[4096], timings[4096], log[4096], result[4096], heat[4096], flip[4096];
    char frames_dir[4200], frames_pattern[4300];
} run_files;

static void run_files_init(run_files *p, const run_spec *s)
{
    path_in(p->exr, sizeof p->exr, s->dir, "image.exr");
    path_in(p->png, sizeof p->png, s->dir, "image.png");
    path_in(p->timings, sizeof p->timings, s->dir, "timings.json");
    path_in(p->log, sizeof p->log, s->dir, "render.log");
    path_in(p->result, sizeof p->result, s->dir, "result.json");
    path_in(p->heat, sizeof p->heat, s->dir, "heatmap.png");
    path_in(p->flip, sizeof p->flip, s->dir, "flip.png");
    snprintf(p->frames_dir, sizeof p->frames_dir, "%s/frames", s->dir);
    snprintf(p->frames_pattern, sizeof p->frames_pattern, "%s/frame_%%04d.exr", p->frames_dir);
}

/* `gibench render` with the run's scene, method, size, frames, time and parameters. */
static void render_args(argv_builder *b, const run_spec *s)
{
    arg(b, "%s", cli_self_exe());
    arg(b, "%s", "render");
    arg(b, "%s", "--scene");
    arg(b, "%s", s->scene);
    arg(b, "%s", "--method");
    arg(b, "%s", s->method);
    if (s->camera) {
        arg(b, "%s", "--camera");
        arg(b, "%s", s->camera);
    }
    char size[64];
    snprintf(size, sizeof size, "%ux%u", s->width, s->height);
    arg(b, "%s", "--size");
    arg(b, "%s", size);
    arg(b, "%s", "--frames");
    argu(b, s->frames);
    arg(b, "%s", "--warmup");
    argu(b, s->warmup);
    arg(b, "%s", "--seed");
    argu(b, s->seed);
    arg(b, "%s", "--time");
    argf(b, s->time);
    if (s->animate_fps > 0) {
        arg(b, "%s", "--animate");
        argf(b, s->animate_fps);
    }
    if (s->no_cache)
        arg(b, "%s", "--no-cache");
    arg(b, "%s", "--exposure");
    argf(b, s->exposure);
    for (uint32_t i = 0; i < s->param_count; i++) {
        arg(b, "%s", "--param");
        arg(b, "%s", s->params[i]);
    }
}

/* The configuration a result is kept under (the command line so far, the
 * references and the timer); an animated run also gets --frames-out. */
static void run_config(argv_builder *b, const run_spec *s, const run_files *p, char *config,
                       size_t size)
{
    join(b, config, size);
    /* The references are part of what the result depends on. */
    size_t used = strlen(config);
    const char *timer = getenv("GIBENCH_TIMER"); /* the timer mode changes every timing */
    /* "curve": results made before render recorded convergence curves are not reused */
    snprintf(config + used, size - used, " | full=%s | matched=%s | curve%s%s",
             s->ref_full ? s->ref_full : "-", s->ref_matched ? s->ref_matched : "-",
             timer ? " | timer=" : "", timer ? timer : "");
    /* an animated run compared frame by frame: every frame written, and the
     * references of every frame in the key (by a hash of their names) */
    if (s->frame_ref_count) {
        uint64_t h = 0;
        for (uint32_t f = 0; f < s->frame_ref_count; f++) {
            const char *names[3] = {s->frame_ref_full[f], s->frame_ref_matched[f],
                                    s->frame_ref_alt ? s->frame_ref_alt[f] : NULL};
            for (int k = 0; k < 3; k++)
                h = gi_hash64(names[k] ? names[k] : "-", strlen(names[k] ? names[k] : "-"), h);
        }
        used = strlen(config);
        snprintf(config + used, size - used, " | frame-refs=%u:%016llx", s->frame_ref_count,
                 (unsigned long long)h);
        arg(b, "%s", "--frames-out");
        arg(b, "%s", p->frames_pattern);
    }
}

/* The convergence curve's references and the output files. */
static void output_args(argv_builder *b, const run_spec *s, const run_files *p)
{
    /* the convergence curve against the same references (they are in the
     * config already); an animated run's frames are compared one by one
     * instead (each frame is a new image, not a step of a convergence) */
    const char *crefs[2] = {s->ref_full, s->ref_matched};
    const char *cnames[2] = {"full", "matched"};
    for (int k = 0; k < 2 && !s->frame_ref_count; k++)
        if (crefs[k]) {
            arg(b, "%s", "--curve-ref");
            char kv[4200];
            snprintf(kv, sizeof kv, "%s=%s", cnames[k], crefs[k]);
            arg(b, "%s", kv);
        }
    arg(b, "%s", "--out");
    arg(b, "%s", p->exr);
    arg(b, "%s", "--out");
    arg(b, "%s", p->png);
    arg(b, "%s", "--timings");
    arg(b, "%s", p->timings);
}

/* Whether a cached record's metrics counted non-finite pixels in its image
 * (the image itself may be gone: committed results keep PNGs only). */
static int cached_nonfinite(json_object *rec, char *why, size_t why_size)
{
    json_object *metrics, *m;
    if (!json_object_object_get_ex(rec, "metrics", &metrics) ||
        !json_object_object_get_ex(metrics, "full", &m) || diff_nonfinite(m, "test") <= 0)
        return 0;
    snprintf(why, why_size, "non-finite output: %lld pixels are NaN or infinite",
             (long long)diff_nonfinite(m, "test"));
    return 1;
}

/* The result kept for the same configuration (not an interrupted one),
 * marked "cached"; NULL when there is none. */
static json_object *cached_result(const run_spec *s, const run_files *p, const char *config,
                                  int resume)
{
    json_object *old = cli_read_json(p->result);
    json_object *c;
    json_object *st = NULL;
    if (old && json_object_object_get_ex(old, "config", &c) &&
        strcmp(json_object_get_string(c), config) == 0 &&
        !(json_object_object_get_ex(old, "status", &st) &&
          !strcmp(json_object_get_string(st), "interrupted"))) {
        if (!collect_only)
            add_leak_to_cached(old, s, p->exr, p->result);
        /* a result recorded "ok" before non-finite output failed a run */
        char why[256];
        const char *status = st ? json_object_get_string(st) : "";
        if (!strcmp(status, "ok") &&
            (nonfinite_output(p->exr, why, sizeof why) || cached_nonfinite(old, why, sizeof why)))
            fail_record(old, why);
        if (resume == RUNNER_RETRY_FAILED && strcmp(status, "ok")) {
            json_object_put(old); /* --retry-failed: run it again */
            return NULL;
        }
        /* for the caller's progress line only; it removes the key */
        json_object_object_add(old, "cached", json_object_new_boolean(1));
        return old;
    }
    json_object_put(old);
    return NULL;
}

/* A finished render's record: its timings, the per-frame comparison of an
 * animated run, the image files and the metrics against each reference. */
static void take_render(json_object *rec, const run_spec *s, const run_files *p, json_object *t)
{
    take_timings(rec, t);
    char anim_why[1100] = "";
    if (s->frame_ref_count) {
        char why[1024];
        json_object *anim = runner_animation_metrics(s, p->frames_pattern, t, why, sizeof why);
        if (!anim)
            snprintf(anim_why, sizeof anim_why, "per-frame comparison: %s", why);
        if (anim)
            json_object_object_add(rec, "animation", anim);
    }
    json_object_put(t);
    json_object_object_add(rec, "status", json_object_new_string("ok"));
    json_object_object_add(rec, "reason", json_object_new_string(""));
    char nf_why[256];
    if (anim_why[0])
        fail_record(rec, anim_why);
    else if (nonfinite_output(p->exr, nf_why, sizeof nf_why))
        fail_record(rec, nf_why);
    char q[4200];
    snprintf(q, sizeof q, "%s/image.png", s->rel);
    json_object_object_add(rec, "png", json_object_new_string(q));
    snprintf(q, sizeof q, "%s/image.exr", s->rel);
    json_object_object_add(rec, "image", json_object_new_string(q));
    json_object *metrics = json_object_new_object();
    const char *refs[2] = {s->ref_full, s->ref_matched};
    const char *names[2] = {"full", "matched"};
    for (int k = 0; k < 2; k++) {
        if (!refs[k])
            continue;
        char why[1024];
        json_object *m = runner_diff(p->exr, refs[k], k == 0 ? p->heat : NULL,
                                     k == 0 ? p->flip : NULL, s->exposure, why, sizeof why);
        if (m && diff_nonfinite(m, "reference") > 0) {
            snprintf(why, sizeof why, "reference %s has %lld NaN or infinite pixels", refs[k],
                     (long long)diff_nonfinite(m, "reference"));
            fail_record(rec, why);
        }
        if (m) {
            json_object_object_add(metrics, names[k], m);
        } else {
            fail_record(rec, why);
            break;
        }
    }
    json_object_object_add(rec, "metrics", metrics);
    if (s->ref_full) {
        snprintf(q, sizeof q, "%s/heatmap.png", s->rel);
        json_object_object_add(rec, "heatmap", json_object_new_string(q));
        snprintf(q, sizeof q, "%s/flip.png", s->rel);
        json_object_object_add(rec, "flip_map", json_object_new_string(q));
    }
}

/* Runs the render in its own process and fills the record from what it wrote. */
static void run_render(json_object *rec, const run_spec *s, const run_files *p, argv_builder *b)
{
    cli_proc_result r;
    int started = cli_run(b->argv, s->timeout_s, p->log, p->log, &r) == 0;
    args_free(b);
    if (!started) {
        fail_record(rec, r.last_line);
        return;
    }
    json_object_object_add(rec, "wall_s", json_object_new_double(r.seconds));
    if (!cli_proc_ok(&r)) {
        char d[700], full[900];
        cli_proc_describe(&r, d, sizeof d);
        /* a full disk may have swallowed the child's own words (its log
         * lies on the same disk): say so, for the summary's "external" */
        struct statvfs fs;
        if (statvfs(s->dir, &fs) == 0 && fs.f_bavail == 0 && !strstr(d, "No space left"))
            snprintf(full, sizeof full, "%s (No space left on device in %s)", d, s->dir);
        else
            snprintf(full, sizeof full, "%s", d);
        fail_record(rec, full);
    } else {
        json_object *t = cli_read_json(p->timings);
        if (!t)
            fail_record(rec, "the method wrote no timings");
        else
            take_render(rec, s, p, t);
    }
}

json_object *runner_execute(const run_spec *s, int resume)
{
    json_object *rec = base_record(s);
    if (!cli_mkdirs(s->dir)) {
        fail_record(rec, "cannot create the run directory");
        return rec;
    }
    run_files p;
    run_files_init(&p, s);
    argv_builder b = {0};
    render_args(&b, s);
    char config[16384]; /* the whole command line: a cut one could match another run's */
    run_config(&b, s, &p, config, sizeof config);
    output_args(&b, s, &p);

    if (resume || collect_only) {
        json_object *old = cached_result(s, &p, config, collect_only ? RUNNER_RESUME : resume);
        if (old) {
            json_object_put(rec);
            args_free(&b);
            return old;
        }
    }
    json_object_object_add(rec, "config", json_object_new_string(config));
    if (collect_only) {
        args_free(&b);
        fail_record(rec, "no result");
        return rec;
    }
    /* nothing of an earlier run may be read as this run's output (an
     * interrupted or failed render leaves the old files otherwise) */
    const char *outputs[] = {p.result, p.exr, p.png, p.timings, p.heat, p.flip};
    for (size_t k = 0; k < sizeof outputs / sizeof outputs[0]; k++)
        unlink(outputs[k]);
    if (s->frame_ref_count && !cli_mkdirs(p.frames_dir)) {
        args_free(&b);
        fail_record(rec, "cannot create the frames directory");
        return rec;
    }
    run_render(rec, s, &p, &b);
    /* A run that did not finish while gibench was being interrupted is
     * "interrupted": reported, but not recorded, so that resuming redoes it
     * (a failure recorded here would be kept for good). */
    json_object *status;
    if (cli_interrupted && !(json_object_object_get_ex(rec, "status", &status) &&
                             !strcmp(json_object_get_string(status), "ok"))) {
        json_object_object_add(rec, "status", json_object_new_string("interrupted"));
        json_object_object_add(rec, "reason",
                               json_object_new_string("interrupted: resuming the study redoes it"));
        return rec;
    }
    char why[GI_ERROR_MAX];
    if (!cli_write_json(p.result, rec, why, sizeof why))
        gi_log(GI_LOG_WARN, "%s", why);
    return rec;
}

int runner_reference(const char *scene, uint64_t scene_hash, const char *camera, uint32_t width,
                     uint32_t height, uint32_t spp, double target_se, uint32_t max_bounces,
                     uint32_t seed, float time, int pixel_center, double timeout_s,
                     const char *out_exr, char *why, size_t why_size)
{
    argv_builder b = {0};
    arg(&b, "%s", cli_self_exe());
    arg(&b, "%s", "reference");
    arg(&b, "%s", "--scene");
    arg(&b, "%s", scene);
    if (camera) {
        arg(&b, "%s", "--camera");
        arg(&b, "%s", camera);
    }
    char size[64];
    snprintf(size, sizeof size, "%ux%u", width, height);
    arg(&b, "%s", "--size");
    arg(&b, "%s", size);
    arg(&b, "%s", "--spp");
    argu(&b, spp);
    if (target_se > 0) {
        arg(&b, "%s", "--target-se");
        argf(&b, target_se);
    }
    arg(&b, "%s", "--max-bounces");
    argu(&b, max_bounces);
    arg(&b, "%s", "--seed");
    argu(&b, seed);
    arg(&b, "%s", "--time-of-scene");
    argf(&b, time);
    if (pixel_center) {
        arg(&b, "%s", "--pixel");
        arg(&b, "%s", "center");
    }
    char config[8192], cfg_path[4200], log[4200], stats[4200];
    join(&b, config, sizeof config);
    /* The scene's content joins the command line in the key: an edited
     * scene under the same name is rendered again, never reused. */
    size_t used = strlen(config);
    snprintf(config + used, sizeof config - used, "\nscene-content %016llx",
             (unsigned long long)scene_hash);
    snprintf(cfg_path, sizeof cfg_path, "%s.config", out_exr);
    snprintf(log, sizeof log, "%s.log", out_exr);
    snprintf(stats, sizeof stats, "%s.json", out_exr);
    size_t n = 0;
    char *old = gi_file_read_all(cfg_path, &n);
    int same =
        old && n == strlen(config) && memcmp(old, config, n) == 0 && access(out_exr, R_OK) == 0;
    free(old);
    if (same || collect_only) {
        args_free(&b);
        if (!same)
            snprintf(why, why_size, "reference %s was not made", out_exr);
        return same;
    }
    char png[4200];
    snprintf(png, sizeof png, "%.*s.png",
             (int)(strlen(out_exr) > 4 ? strlen(out_exr) - 4 : strlen(out_exr)), out_exr);
    arg(&b, "%s", "--out");
    arg(&b, "%s", out_exr);
    arg(&b, "%s", "--out");
    arg(&b, "%s", png);
    arg(&b, "%s", "--stats");
    arg(&b, "%s", stats);
    cli_proc_result r;
    /* The old key goes first: until the new image is complete and its key
     * written, neither the old nor a half-made image passes as this one. */
    unlink(cfg_path);
    int started = cli_run(b.argv, timeout_s, log, log, &r) == 0;
    args_free(&b);
    if (!started || !cli_proc_ok(&r)) {
        char d[700];
        cli_proc_describe(&r, d, sizeof d);
        snprintf(why, why_size, "reference for %s: %s", scene, d);
        return 0;
    }
    gi_error err;
    if (gi_file_write_atomic(cfg_path, config, strlen(config), &err) != GI_OK) {
        snprintf(why, why_size, "%s", err.text);
        return 0;
    }
    return 1;
}
