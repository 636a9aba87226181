/* Method runs in child processes and their comparison (runner.h). */
#define _POSIX_C_SOURCE 200809L
#include "runner.h"

#include "cli.h"
#include "gi/cache.h"
#include "gi/log.h"
#include "proc.h"
#include "report.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
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

json_object *runner_diff(const char *image, const char *reference, const char *heatmap, const char *flip_map,
                         float exposure, char *why, size_t why_size)
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
    if (!started || r.timed_out || r.signaled || r.exit_code) {
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

json_object *runner_execute(const run_spec *s, int resume)
{
    json_object *rec = base_record(s);
    if (!cli_mkdirs(s->dir)) {
        fail_record(rec, "cannot create the run directory");
        return rec;
    }
    char exr[4096], png[4096], timings[4096], log[4096], result[4096], heat[4096], flip[4096];
    path_in(exr, sizeof exr, s->dir, "image.exr");
    path_in(png, sizeof png, s->dir, "image.png");
    path_in(timings, sizeof timings, s->dir, "timings.json");
    path_in(log, sizeof log, s->dir, "render.log");
    path_in(result, sizeof result, s->dir, "result.json");
    path_in(heat, sizeof heat, s->dir, "heatmap.png");
    path_in(flip, sizeof flip, s->dir, "flip.png");

    argv_builder b = {0};
    arg(&b, "%s", cli_self_exe());
    arg(&b, "%s", "render");
    arg(&b, "%s", "--scene");
    arg(&b, "%s", s->scene);
    arg(&b, "%s", "--method");
    arg(&b, "%s", s->method);
    if (s->camera) {
        arg(&b, "%s", "--camera");
        arg(&b, "%s", s->camera);
    }
    char size[64];
    snprintf(size, sizeof size, "%ux%u", s->width, s->height);
    arg(&b, "%s", "--size");
    arg(&b, "%s", size);
    arg(&b, "%s", "--frames");
    argu(&b, s->frames);
    arg(&b, "%s", "--warmup");
    argu(&b, s->warmup);
    arg(&b, "%s", "--seed");
    argu(&b, s->seed);
    arg(&b, "%s", "--time");
    argf(&b, s->time);
    if (s->animate_fps > 0) {
        arg(&b, "%s", "--animate");
        argf(&b, s->animate_fps);
    }
    if (s->no_cache)
        arg(&b, "%s", "--no-cache");
    arg(&b, "%s", "--exposure");
    argf(&b, s->exposure);
    for (uint32_t i = 0; i < s->param_count; i++) {
        arg(&b, "%s", "--param");
        arg(&b, "%s", s->params[i]);
    }
    char config[16384]; /* the whole command line: a cut one could match another run's */
    join(&b, config, sizeof config);
    /* The references are part of what the result depends on. */
    size_t used = strlen(config);
    const char *timer = getenv("GIBENCH_TIMER"); /* the timer mode changes every timing */
    /* "curve": results made before render recorded convergence curves are not reused */
    snprintf(config + used, sizeof config - used, " | full=%s | matched=%s | curve%s%s", s->ref_full ? s->ref_full : "-",
             s->ref_matched ? s->ref_matched : "-", timer ? " | timer=" : "", timer ? timer : "");
    /* the convergence curve against the same references (they are in the
     * config already) */
    const char *crefs[2] = {s->ref_full, s->ref_matched};
    const char *cnames[2] = {"full", "matched"};
    for (int k = 0; k < 2; k++)
        if (crefs[k]) {
            arg(&b, "%s", "--curve-ref");
            char kv[4200];
            snprintf(kv, sizeof kv, "%s=%s", cnames[k], crefs[k]);
            arg(&b, "%s", kv);
        }
    arg(&b, "%s", "--out");
    arg(&b, "%s", exr);
    arg(&b, "%s", "--out");
    arg(&b, "%s", png);
    arg(&b, "%s", "--timings");
    arg(&b, "%s", timings);

    if (resume || collect_only) {
        json_object *old = cli_read_json(result);
        json_object *c;
        json_object *st;
        if (old && json_object_object_get_ex(old, "config", &c) && strcmp(json_object_get_string(c), config) == 0 &&
            !(json_object_object_get_ex(old, "status", &st) && !strcmp(json_object_get_string(st), "interrupted"))) {
            json_object_put(rec);
            args_free(&b);
            /* for the caller's progress line only; it removes the key */
            json_object_object_add(old, "cached", json_object_new_boolean(1));
            return old;
        }
        json_object_put(old);
    }
    json_object_object_add(rec, "config", json_object_new_string(config));
    if (collect_only) {
        args_free(&b);
        fail_record(rec, "no result");
        return rec;
    }
    unlink(result);
    cli_proc_result r;
    int started = cli_run(b.argv, s->timeout_s, log, log, &r) == 0;
    args_free(&b);
    if (!started) {
        fail_record(rec, r.last_line);
        return rec;
    }
    json_object_object_add(rec, "wall_s", json_object_new_double(r.seconds));
    if (r.timed_out || r.signaled || r.exit_code != 0) {
        char d[700];
        cli_proc_describe(&r, d, sizeof d);
        fail_record(rec, d);
    } else {
        json_object *t = cli_read_json(timings);
        if (!t) {
            fail_record(rec, "the method wrote no timings");
        } else {
            take_timings(rec, t);
            json_object_put(t);
            json_object_object_add(rec, "status", json_object_new_string("ok"));
            json_object_object_add(rec, "reason", json_object_new_string(""));
            char p[4200];
            snprintf(p, sizeof p, "%s/image.png", s->rel);
            json_object_object_add(rec, "png", json_object_new_string(p));
            snprintf(p, sizeof p, "%s/image.exr", s->rel);
            json_object_object_add(rec, "image", json_object_new_string(p));
            json_object *metrics = json_object_new_object();
            const char *refs[2] = {s->ref_full, s->ref_matched};
            const char *names[2] = {"full", "matched"};
            for (int k = 0; k < 2; k++) {
                if (!refs[k])
                    continue;
                char why[1024];
                json_object *m = runner_diff(exr, refs[k], k == 0 ? heat : NULL, k == 0 ? flip : NULL, s->exposure, why,
                                            sizeof why);
                if (m) {
                    json_object_object_add(metrics, names[k], m);
                } else {
                    fail_record(rec, why);
                    break;
                }
            }
            json_object_object_add(rec, "metrics", metrics);
            if (s->ref_full) {
                snprintf(p, sizeof p, "%s/heatmap.png", s->rel);
                json_object_object_add(rec, "heatmap", json_object_new_string(p));
                snprintf(p, sizeof p, "%s/flip.png", s->rel);
                json_object_object_add(rec, "flip_map", json_object_new_string(p));
            }
        }
    }
    /* A run that did not finish while gibench was being interrupted is
     * "interrupted": reported, but not recorded, so that resuming redoes it
     * (a failure recorded here would be kept for good). */
    json_object *status;
    if (cli_interrupted && !(json_object_object_get_ex(rec, "status", &status) &&
                             !strcmp(json_object_get_string(status), "ok"))) {
        json_object_object_add(rec, "status", json_object_new_string("interrupted"));
        json_object_object_add(rec, "reason", json_object_new_string("interrupted: resuming the study redoes it"));
        return rec;
    }
    char why[GI_ERROR_MAX];
    if (!cli_write_json(result, rec, why, sizeof why))
        gi_log(GI_LOG_WARN, "%s", why);
    return rec;
}

int runner_reference(const char *scene, uint64_t scene_hash, const char *camera, uint32_t width, uint32_t height,
                     uint32_t spp, double target_se, uint32_t max_bounces, uint32_t seed, float time,
                     int pixel_center, double timeout_s, const char *out_exr, char *why, size_t why_size)
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
    snprintf(config + used, sizeof config - used, "\nscene-content %016llx", (unsigned long long)scene_hash);
    snprintf(cfg_path, sizeof cfg_path, "%s.config", out_exr);
    snprintf(log, sizeof log, "%s.log", out_exr);
    snprintf(stats, sizeof stats, "%s.json", out_exr);
    size_t n = 0;
    char *old = gi_file_read_all(cfg_path, &n);
    int same = old && n == strlen(config) && memcmp(old, config, n) == 0 && access(out_exr, R_OK) == 0;
    free(old);
    if (same || collect_only) {
        args_free(&b);
        if (!same)
            snprintf(why, why_size, "reference %s was not made", out_exr);
        return same;
    }
    char png[4200];
    snprintf(png, sizeof png, "%.*s.png", (int)(strlen(out_exr) > 4 ? strlen(out_exr) - 4 : strlen(out_exr)), out_exr);
    arg(&b, "%s", "--out");
    arg(&b, "%s", out_exr);
    arg(&b, "%s", "--out");
    arg(&b, "%s", png);
    arg(&b, "%s", "--stats");
    arg(&b, "%s", stats);
    cli_proc_result r;
    int started = cli_run(b.argv, timeout_s, log, log, &r) == 0;
    args_free(&b);
    if (!started || r.timed_out || r.signaled || r.exit_code != 0) {
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
