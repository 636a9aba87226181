/* gibench study: a declarative experiment (harness/studies/NAME.json)
 * expanded into independent runs, executed in child processes by a worker
 * pool, cached by the hash of each run's configuration, and reported with
 * tables and error-against-time charts that include the path tracer's own
 * convergence curve. The file format is documented in README.md ("Studies"). */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"

#include "charts.h"
#include "gi/cache.h"
#include "report.h"
#include "runner.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#define MAX_RUNS 4096
#define MAX_SWEEP 64
#define MAX_KEYS 16

typedef struct study_run {
    run_spec spec;
    char id[512], dir[4096], rel[1024];
    char *params[MAX_KEYS];
    int scene_index;
    uint32_t bounces; /* the method's max_bounces + 1 */
    json_object *record;
} study_run;

typedef struct study_scene {
    const char *path;
    char stem[256];
    char ref_full[4096];
    char ref_matched[8][4096];
    uint32_t matched_bounces[8];
    uint32_t matched_count;
    /* convergence curve of the path tracer: time (s) and relMSE */
    double curve_t[32], curve_e[32];
    uint32_t curve_n;
} study_scene;

typedef struct study {
    json_object *root;
    const char *name;
    uint32_t width, height, frames, warmup, repeats, seed;
    uint32_t ref_spp, ref_bounces;
    double ref_target_se; /* 0: none */
    uint32_t conv_spp[32], conv_n;
    float time, exposure;
    const char *camera;
    double timeout_s;
    study_scene scenes[16];
    uint32_t scene_count;
    study_run *runs;
    uint32_t run_count;
} study;

static int fail_json(const char *file, const char *path, const char *what)
{
    return cli_fail(EXIT_USAGE, "%s: %s: %s", file, path, what);
}

static int get_uint(json_object *o, const char *key, uint32_t min, uint32_t max, uint32_t def, uint32_t *out,
                    const char *file)
{
    json_object *v;
    *out = def;
    if (!json_object_object_get_ex(o, key, &v) || json_object_is_type(v, json_type_null))
        return EXIT_OK;
    if (!json_object_is_type(v, json_type_int) || json_object_get_int64(v) < min || json_object_get_int64(v) > max) {
        char msg[128];
        snprintf(msg, sizeof msg, "must be an integer in [%u, %u]", min, max);
        char path[64];
        snprintf(path, sizeof path, "/%s", key);
        return fail_json(file, path, msg);
    }
    *out = (uint32_t)json_object_get_int64(v);
    return EXIT_OK;
}

/* Values of one parameter: a scalar, a list, or a range
 * {"from": a, "to": b, "step": s} / {"from": a, "to": b, "count": n, "scale": "log"}.
 * Written as text "name=value". */
static int sweep_values(const char *file, const char *mpath, const char *name, json_object *v, char out[][128],
                        int *n)
{
    char path[512];
    snprintf(path, sizeof path, "%s/params/%s", mpath, name);
    *n = 0;
    if (json_object_is_type(v, json_type_array)) {
        size_t len = json_object_array_length(v);
        if (len == 0 || len > MAX_SWEEP)
            return fail_json(file, path, "a sweep needs 1 to 64 values");
        for (size_t i = 0; i < len; i++) {
            json_object *e = json_object_array_get_idx(v, i);
            if (json_object_is_type(e, json_type_array) || json_object_is_type(e, json_type_object))
                return fail_json(file, path, "sweep values must be numbers, booleans or strings");
            snprintf(out[(*n)++], 128, "%s=%s", name, json_object_get_string(e));
        }
        return EXIT_OK;
    }
    if (json_object_is_type(v, json_type_object)) {
        json_object *from, *to, *step, *count, *scale;
        if (!json_object_object_get_ex(v, "from", &from) || !json_object_object_get_ex(v, "to", &to))
            return fail_json(file, path, "a range needs \"from\" and \"to\"");
        double a = json_object_get_double(from), b = json_object_get_double(to);
        int is_int = json_object_is_type(from, json_type_int) && json_object_is_type(to, json_type_int);
        int log_scale = json_object_object_get_ex(v, "scale", &scale) && !strcmp(json_object_get_string(scale), "log");
        if (json_object_object_get_ex(v, "count", &count)) {
            int c = json_object_get_int(count);
            if (c < 1 || c > MAX_SWEEP || (log_scale && (a <= 0 || b <= 0)))
                return fail_json(file, path, "count must be 1..64 (and a log range positive)");
            for (int i = 0; i < c; i++) {
                double t = c == 1 ? 0.0 : (double)i / (c - 1);
                double x = log_scale ? exp(log(a) + t * (log(b) - log(a))) : a + t * (b - a);
                if (is_int)
                    snprintf(out[(*n)++], 128, "%s=%lld", name, (long long)llround(x));
                else
                    snprintf(out[(*n)++], 128, "%s=%.9g", name, x);
            }
        } else if (json_object_object_get_ex(v, "step", &step)) {
            double s = json_object_get_double(step);
            if (!(s > 0) || (b - a) / s > MAX_SWEEP - 1)
                return fail_json(file, path, "step must be positive and give at most 64 values");
            for (double x = a; x <= b + 1e-9 * fabs(s); x += s) {
                if (is_int && json_object_is_type(step, json_type_int))
                    snprintf(out[(*n)++], 128, "%s=%lld", name, (long long)llround(x));
                else
                    snprintf(out[(*n)++], 128, "%s=%.9g", name, x);
            }
        } else {
            return fail_json(file, path, "a range needs \"step\" or \"count\"");
        }
        if (*n == 0)
            return fail_json(file, path, "the range is empty");
        return EXIT_OK;
    }
    snprintf(out[(*n)++], 128, "%s=%s", name, json_object_get_string(v));
    return EXIT_OK;
}

static void stem_of(const char *path, char *out, size_t size)
{
    const char *b = strrchr(path, '/');
    b = b ? b + 1 : path;
    snprintf(out, size, "%s", b);
    char *dot = strrchr(out, '.');
    if (dot)
        *dot = '\0';
}

static int add_run(study *st, const char *file, const char *out_dir, const gi_method *m, char combo[][128], int nk,
                   uint32_t repeat)
{
    for (uint32_t si = 0; si < st->scene_count; si++) {
        if (st->run_count == MAX_RUNS)
            return cli_fail(EXIT_USAGE, "%s: more than %d runs", file, MAX_RUNS);
        study_run *r = &st->runs[st->run_count];
        memset(r, 0, sizeof *r);
        char key[4096];
        snprintf(key, sizeof key, "%s|%s|%u", st->scenes[si].path, m->id, repeat);
        for (int k = 0; k < nk; k++) {
            r->params[k] = strdup(combo[k]);
            size_t used = strlen(key);
            snprintf(key + used, sizeof key - used, "|%s", combo[k]);
        }
        uint64_t h = gi_hash64(key, strlen(key), 0);
        snprintf(r->id, sizeof r->id, "%s-%s-%08x", st->scenes[si].stem, m->id, (unsigned)(h & 0xFFFFFFFFu));
        snprintf(r->rel, sizeof r->rel, "runs/%s", r->id);
        snprintf(r->dir, sizeof r->dir, "%s/%s", out_dir, r->rel);
        r->scene_index = (int)si;
        r->bounces = m->max_bounces + 1;
        run_spec *s = &r->spec;
        s->run_id = r->id;
        s->scene = st->scenes[si].path;
        s->method = m->id;
        s->camera = st->camera;
        s->width = st->width;
        s->height = st->height;
        s->frames = st->frames;
        s->warmup = st->warmup;
        s->seed = st->seed + repeat;
        s->time = st->time;
        s->params = (const char *const *)r->params;
        s->param_count = (uint32_t)nk;
        s->timeout_s = st->timeout_s;
        s->dir = r->dir;
        s->rel = r->rel;
        s->exposure = st->exposure;
        st->run_count++;
    }
    return EXIT_OK;
}

/* Expands one method entry: the Cartesian product of its sweeps. */
static int expand_method(study *st, const char *file, const char *out_dir, const gi_method *m, json_object *params,
                         const char *mpath)
{
    static char values[MAX_KEYS][MAX_SWEEP][128];
    int counts[MAX_KEYS], nk = 0;
    if (params) {
        json_object_object_foreach(params, name, v)
        {
            if (nk == MAX_KEYS)
                return fail_json(file, mpath, "too many parameters");
            int rc = sweep_values(file, mpath, name, v, values[nk], &counts[nk]);
            if (rc != EXIT_OK)
                return rc;
            /* validate each value against the method's table now, not at run time */
            for (int i = 0; i < counts[nk]; i++) {
                gi_error err;
                const char *kv = values[nk][i];
                gi_params *p = gi_params_parse(m->id, m->params, &kv, 1, &err);
                if (!p)
                    return cli_fail(EXIT_USAGE, "%s: %s: %s", file, mpath, err.text);
                gi_params_free(p);
            }
            nk++;
        }
    }
    int idx[MAX_KEYS] = {0};
    for (;;) {
        char combo[MAX_KEYS][128];
        for (int k = 0; k < nk; k++)
            snprintf(combo[k], 128, "%s", values[k][idx[k]]);
        for (uint32_t rep = 0; rep < st->repeats; rep++) {
            int rc = add_run(st, file, out_dir, m, combo, nk, rep);
            if (rc != EXIT_OK)
                return rc;
        }
        int k = 0;
        while (k < nk && ++idx[k] == counts[k])
            idx[k++] = 0;
        if (k == nk)
            break;
    }
    return EXIT_OK;
}

static int load_study(study *st, const char *file, const char *out_dir, gi_plugins *reg)
{
    st->root = cli_read_json(file);
    if (!st->root)
        return access(file, R_OK) ? cli_fail(EXIT_USAGE, "%s: cannot read the study file", file)
                                  : cli_fail(EXIT_USAGE, "%s: not valid JSON", file);
    json_object *o = st->root, *v;
    if (!json_object_is_type(o, json_type_object))
        return fail_json(file, "/", "a study is a JSON object");
    json_object_object_foreach(o, key, val)
    {
        (void)val;
        static const char *known[] = {"name", "description", "scenes", "size", "frames", "warmup", "repeats",
                                      "seed", "camera", "time", "exposure", "timeout", "methods", "reference",
                                      NULL};
        int ok = 0;
        for (int i = 0; known[i]; i++)
            ok |= !strcmp(known[i], key);
        if (!ok) {
            char path[128];
            snprintf(path, sizeof path, "/%s", key);
            return fail_json(file, path, "unknown key");
        }
    }
    st->name = json_object_object_get_ex(o, "name", &v) ? json_object_get_string(v) : "study";
    if (!json_object_object_get_ex(o, "scenes", &v) || !json_object_is_type(v, json_type_array) ||
        json_object_array_length(v) == 0 || json_object_array_length(v) > 16)
        return fail_json(file, "/scenes", "a list of 1 to 16 scene files is required");
    for (size_t i = 0; i < json_object_array_length(v); i++) {
        study_scene *sc = &st->scenes[st->scene_count++];
        sc->path = json_object_get_string(json_object_array_get_idx(v, i));
        gi_error err;
        gi_scene *s = gi_scene_load(sc->path, &err);
        if (!s)
            return cli_fail(EXIT_USAGE, "%s: /scenes/%zu: %s", file, i, err.text);
        gi_scene_free(s);
        stem_of(sc->path, sc->stem, sizeof sc->stem);
    }
    st->width = st->height = 128;
    if (json_object_object_get_ex(o, "size", &v)) {
        if (!json_object_is_type(v, json_type_array) || json_object_array_length(v) != 2)
            return fail_json(file, "/size", "must be [width, height]");
        int w = json_object_get_int(json_object_array_get_idx(v, 0)), h = json_object_get_int(json_object_array_get_idx(v, 1));
        if (w < 1 || h < 1 || w > 16384 || h > 16384)
            return fail_json(file, "/size", "width and height must be 1..16384");
        st->width = (uint32_t)w;
        st->height = (uint32_t)h;
    }
    int rc;
    if ((rc = get_uint(o, "frames", 1, 100000, 8, &st->frames, file)) || (rc = get_uint(o, "warmup", 0, 1000, 1, &st->warmup, file)) ||
        (rc = get_uint(o, "repeats", 1, 100, 1, &st->repeats, file)) || (rc = get_uint(o, "seed", 0, 0x7FFFFFFF, 1, &st->seed, file)))
        return rc;
    if (st->warmup >= st->frames)
        st->warmup = st->frames > 1 ? st->frames - 1 : 0;
    st->camera = json_object_object_get_ex(o, "camera", &v) && !json_object_is_type(v, json_type_null)
                     ? json_object_get_string(v)
                     : NULL;
    st->time = json_object_object_get_ex(o, "time", &v) ? (float)json_object_get_double(v) : 0.0f;
    st->exposure = json_object_object_get_ex(o, "exposure", &v) ? (float)json_object_get_double(v) : 0.0f;
    st->timeout_s = json_object_object_get_ex(o, "timeout", &v) ? json_object_get_double(v) : 600.0;
    if (!(st->timeout_s > 0))
        return fail_json(file, "/timeout", "must be a positive number of seconds");

    json_object *ref;
    st->ref_spp = 256;
    st->ref_bounces = 64;
    if (json_object_object_get_ex(o, "reference", &ref)) {
        if ((rc = get_uint(ref, "spp", 1, 1u << 24, 256, &st->ref_spp, file)) ||
            (rc = get_uint(ref, "max_bounces", 0, 1024, 64, &st->ref_bounces, file)))
            return rc;
        json_object *cs, *tse;
        if (json_object_object_get_ex(ref, "target_se", &tse) && !json_object_is_type(tse, json_type_null)) {
            st->ref_target_se = json_object_get_double(tse);
            if (!(st->ref_target_se > 0))
                return fail_json(file, "/reference/target_se", "must be a positive relative standard error");
        }
        if (json_object_object_get_ex(ref, "convergence_spp", &cs)) {
            if (!json_object_is_type(cs, json_type_array) || json_object_array_length(cs) > 32)
                return fail_json(file, "/reference/convergence_spp", "must be a list of at most 32 sample counts");
            for (size_t i = 0; i < json_object_array_length(cs); i++) {
                int k = json_object_get_int(json_object_array_get_idx(cs, i));
                if (k < 1 || (uint32_t)k >= st->ref_spp)
                    return fail_json(file, "/reference/convergence_spp", "each count must be 1 .. spp-1");
                st->conv_spp[st->conv_n++] = (uint32_t)k;
            }
        }
    }
    if (!json_object_object_get_ex(o, "methods", &v))
        return fail_json(file, "/methods", "required (\"all\" or a list)");
    st->runs = calloc(MAX_RUNS, sizeof *st->runs);
    if (!st->runs)
        return cli_fail(EXIT_RUN, "out of memory");
    if (json_object_is_type(v, json_type_string) && !strcmp(json_object_get_string(v), "all")) {
        for (uint32_t i = 0; i < reg->count; i++)
            if ((rc = expand_method(st, file, out_dir, reg->items[i].method, NULL, "/methods")))
                return rc;
        return EXIT_OK;
    }
    if (!json_object_is_type(v, json_type_array))
        return fail_json(file, "/methods", "must be \"all\" or a list of {\"method\": id, \"params\": {...}}");
    for (size_t i = 0; i < json_object_array_length(v); i++) {
        json_object *e = json_object_array_get_idx(v, i), *id, *params = NULL;
        char mpath[64];
        snprintf(mpath, sizeof mpath, "/methods/%zu", i);
        if (!json_object_is_type(e, json_type_object) || !json_object_object_get_ex(e, "method", &id))
            return fail_json(file, mpath, "needs \"method\"");
        json_object_object_get_ex(e, "params", &params);
        if (params && !json_object_is_type(params, json_type_object))
            return fail_json(file, mpath, "\"params\" must be an object");
        const char *mid = json_object_get_string(id);
        if (!strcmp(mid, "all")) {
            for (uint32_t k = 0; k < reg->count; k++)
                if ((rc = expand_method(st, file, out_dir, reg->items[k].method, NULL, mpath)))
                    return rc;
            continue;
        }
        const gi_method *m = gi_plugins_find(reg, mid);
        if (!m) {
            char msg[256];
            snprintf(msg, sizeof msg, "no method '%s' is installed (see gibench methods)", mid);
            return fail_json(file, mpath, msg);
        }
        if ((rc = expand_method(st, file, out_dir, m, params, mpath)))
            return rc;
    }
    return EXIT_OK;
}

/* Log-log interpolation of the path tracer's time at error e; extrapolates
 * with slope -1 (relMSE ~ 1/time for an unbiased estimator). *extrapolated
 * is set when e lies outside the curve. */
static double pt_time_at(const study_scene *sc, double e, int *extrapolated)
{
    *extrapolated = 0;
    if (sc->curve_n == 0 || !(e > 0))
        return NAN;
    /* curve sorted by time, error decreasing */
    for (uint32_t i = 0; i + 1 < sc->curve_n; i++) {
        double e0 = sc->curve_e[i], e1 = sc->curve_e[i + 1];
        if ((e <= e0 && e >= e1) || (e >= e0 && e <= e1)) {
            double t = (log(e) - log(e0)) / (log(e1) - log(e0));
            if (!isfinite(t))
                t = 0;
            return exp(log(sc->curve_t[i]) + t * (log(sc->curve_t[i + 1]) - log(sc->curve_t[i])));
        }
    }
    *extrapolated = 1;
    uint32_t k = e > sc->curve_e[0] ? 0 : sc->curve_n - 1;
    return sc->curve_t[k] * sc->curve_e[k] / e;
}

static double rec_num(json_object *o, const char *k1, const char *k2, const char *k3)
{
    const char *keys[3] = {k1, k2, k3};
    for (int i = 0; i < 3 && keys[i]; i++) {
        json_object *v;
        if (!o || !json_object_object_get_ex(o, keys[i], &v))
            return NAN;
        o = v;
    }
    return json_object_get_double(o);
}

static int build_references(study *st, const char *out_dir, gi_plugins *reg)
{
    char why[1024];
    for (uint32_t si = 0; si < st->scene_count; si++) {
        study_scene *sc = &st->scenes[si];
        char dir[2048], stem[256];
        snprintf(stem, sizeof stem, "%s", sc->stem); /* a copy: -Wrestrict sees sc->stem and the outputs as one object */
        snprintf(dir, sizeof dir, "%s/references", out_dir);
        cli_mkdirs(dir);
        snprintf(sc->ref_full, sizeof sc->ref_full, "%s/%s_b%u_%uspp.exr", dir, stem, st->ref_bounces, st->ref_spp);
        fprintf(stderr, "study: reference %s (%u spp, %u bounces)\n", sc->stem, st->ref_spp, st->ref_bounces);
        if (!runner_reference(sc->path, st->camera, st->width, st->height, st->ref_spp, st->ref_target_se, st->ref_bounces, st->seed,
                              st->time, st->timeout_s * 10, sc->ref_full, why, sizeof why))
            return cli_fail(EXIT_RUN, "study: %s", why);
        /* bounce-matched references for every method bounce count in use */
        for (uint32_t r = 0; r < st->run_count; r++) {
            if (st->runs[r].scene_index != (int)si || st->runs[r].bounces >= st->ref_bounces)
                continue;
            uint32_t b = st->runs[r].bounces, k = 0;
            while (k < sc->matched_count && sc->matched_bounces[k] != b)
                k++;
            if (k == sc->matched_count && k < 8) {
                sc->matched_bounces[k] = b;
                snprintf(sc->ref_matched[k], sizeof sc->ref_matched[k], "%s/%s_b%u_%uspp.exr", dir, stem, b,
                         st->ref_spp);
                fprintf(stderr, "study: bounce-matched reference %s (%u bounces)\n", sc->stem, b);
                if (!runner_reference(sc->path, st->camera, st->width, st->height, st->ref_spp, st->ref_target_se, b, st->seed, st->time,
                                      st->timeout_s * 10, sc->ref_matched[k], why, sizeof why))
                    return cli_fail(EXIT_RUN, "study: %s", why);
                sc->matched_count++;
            }
        }
        /* the path tracer's convergence: k-spp images (another seed) against the reference */
        for (uint32_t c = 0; c < st->conv_n; c++) {
            char img[4096], stats[4200];
            snprintf(img, sizeof img, "%s/%s_conv_%uspp.exr", dir, stem, st->conv_spp[c]);
            if (!runner_reference(sc->path, st->camera, st->width, st->height, st->conv_spp[c], 0.0, st->ref_bounces,
                                  st->seed + 7919, st->time, st->timeout_s, img, why, sizeof why))
                return cli_fail(EXIT_RUN, "study: %s", why);
            snprintf(stats, sizeof stats, "%s.json", img);
            json_object *sj = cli_read_json(stats);
            json_object *m = runner_diff(img, sc->ref_full, NULL, st->exposure, why, sizeof why);
            double t = rec_num(sj, "wall_seconds", NULL, NULL), e = rec_num(m, "relmse", NULL, NULL);
            if (isfinite(t) && isfinite(e) && t > 0 && e > 0 && sc->curve_n < 32) {
                sc->curve_t[sc->curve_n] = t;
                sc->curve_e[sc->curve_n] = e;
                sc->curve_n++;
            }
            json_object_put(sj);
            json_object_put(m);
        }
    }
    (void)reg;
    return EXIT_OK;
}

static void attach_refs(study *st, study_run *r)
{
    study_scene *sc = &st->scenes[r->scene_index];
    r->spec.ref_full = sc->ref_full;
    r->spec.ref_matched = sc->ref_full;
    for (uint32_t k = 0; k < sc->matched_count; k++)
        if (sc->matched_bounces[k] == r->bounces)
            r->spec.ref_matched = sc->ref_matched[k];
}

/* Runs every run not yet done: `jobs` worker processes, each taking runs
 * i, i+jobs, ...; results land in each run's result.json. */
static void execute_runs(study *st, uint32_t jobs, int fresh, gi_plugins *reg)
{
    gi_error err;
    for (uint32_t i = 0; i < st->run_count; i++)
        attach_refs(st, &st->runs[i]);
    if (jobs <= 1) {
        for (uint32_t i = 0; i < st->run_count && !cli_interrupted; i++) {
            study_run *r = &st->runs[i];
            fprintf(stderr, "study: run %u/%u %s\n", i + 1, st->run_count, r->id);
            gi_scene *s = gi_scene_load(r->spec.scene, &err);
            char why[256];
            const gi_method *m = gi_plugins_find(reg, r->spec.method);
            if (s && m && !cli_caps_cover(m, s, r->spec.animate_fps > 0, why, sizeof why))
                r->record = runner_not_applicable(&r->spec, why);
            else
                r->record = runner_execute(&r->spec, !fresh);
            gi_scene_free(s);
        }
        return;
    }
    pid_t *pids = calloc(jobs, sizeof *pids);
    for (uint32_t j = 0; j < jobs && pids; j++) {
        pid_t pid = fork();
        if (pid == 0) {
            for (uint32_t i = j; i < st->run_count && !cli_interrupted; i += jobs) {
                fprintf(stderr, "study: [worker %u] run %u/%u %s\n", j, i + 1, st->run_count, st->runs[i].id);
                json_object_put(runner_execute(&st->runs[i].spec, !fresh));
            }
            _exit(0);
        }
        pids[j] = pid;
    }
    for (uint32_t j = 0; j < jobs && pids; j++)
        if (pids[j] > 0)
            waitpid(pids[j], NULL, 0);
    free(pids);
    /* collect: every worker wrote result.json; resume picks them up */
    for (uint32_t i = 0; i < st->run_count; i++) {
        study_run *r = &st->runs[i];
        gi_scene *s = gi_scene_load(r->spec.scene, &err);
        char why[256];
        const gi_method *m = gi_plugins_find(reg, r->spec.method);
        if (s && m && !cli_caps_cover(m, s, 0, why, sizeof why))
            r->record = runner_not_applicable(&r->spec, why);
        else
            r->record = runner_execute(&r->spec, 1);
        gi_scene_free(s);
    }
}

/* Error-against-time charts per scene and the equal-error speed-up column. */
static void charts_and_speedups(study *st, const char *out_dir, json_object *meta, json_object *runs)
{
    json_object *chart_list = json_object_new_array();
    char md[8192] = "";
    for (uint32_t si = 0; si < st->scene_count; si++) {
        study_scene *sc = &st->scenes[si];
        /* group runs by method */
        const char *methods[32];
        uint32_t nm = 0;
        for (uint32_t i = 0; i < st->run_count; i++) {
            if (st->runs[i].scene_index != (int)si)
                continue;
            int seen = 0;
            for (uint32_t k = 0; k < nm; k++)
                seen |= !strcmp(methods[k], st->runs[i].spec.method);
            if (!seen && nm < 32)
                methods[nm++] = st->runs[i].spec.method;
        }
        gi_chart_series series[33];
        double *xs = calloc((size_t)(nm + 1) * MAX_RUNS, sizeof *xs), *ys = calloc((size_t)(nm + 1) * MAX_RUNS, sizeof *ys);
        uint32_t ns = 0;
        for (uint32_t k = 0; k < nm && xs && ys; k++) {
            double *x = xs + (size_t)ns * MAX_RUNS, *y = ys + (size_t)ns * MAX_RUNS;
            uint32_t c = 0;
            for (uint32_t i = 0; i < st->run_count; i++) {
                study_run *r = &st->runs[i];
                if (r->scene_index != (int)si || strcmp(r->spec.method, methods[k]))
                    continue;
                double fm = rec_num(r->record, "frame_ms", "median", NULL);
                double e = rec_num(r->record, "metrics", "full", "relmse");
                if (!(fm > 0) || !(e > 0))
                    continue;
                double t = fm * r->spec.frames / 1000.0;
                x[c] = t;
                y[c] = e;
                c++;
                int extrapolated;
                double tpt = pt_time_at(sc, e, &extrapolated);
                if (isfinite(tpt)) {
                    json_object_object_add(r->record, "pt_time_at_equal_error_s", json_object_new_double(tpt));
                    json_object_object_add(r->record, "speedup_vs_pt", json_object_new_double(tpt / t));
                    json_object_object_add(r->record, "speedup_extrapolated", json_object_new_boolean(extrapolated));
                }
            }
            series[ns] = (gi_chart_series){methods[k], x, y, c, 0};
            ns++;
        }
        if (sc->curve_n)
            series[ns++] = (gi_chart_series){"path tracer (Embree, CPU)", sc->curve_t, sc->curve_e, sc->curve_n, 2};
        char name[512], path[4700], title[512];
        snprintf(name, sizeof name, "chart_%s_error_vs_time.png", sc->stem);
        snprintf(path, sizeof path, "%s/%s", out_dir, name);
        snprintf(title, sizeof title, "%s: relMSE against time (full-GI reference)", sc->stem);
        gi_chart_desc desc = {title, "time to image (s): frames x median frame time", "relMSE", 1, 1, 0, 0};
        gi_error err;
        if (gi_chart_write_png(path, &desc, series, ns, &err) == GI_OK)
            json_object_array_add(chart_list, json_object_new_string(name));
        else
            fprintf(stderr, "gibench: warning: chart %s not written: %s\n", name, err.text);
        free(xs);
        free(ys);
        size_t used = strlen(md);
        snprintf(md + used, sizeof md - used,
                 "Path tracer convergence on %s (relMSE against the %u-spp reference, another seed):", sc->stem,
                 st->ref_spp);
        for (uint32_t c = 0; c < sc->curve_n; c++) {
            used = strlen(md);
            snprintf(md + used, sizeof md - used, " %.3g s → %.3g;", sc->curve_t[c], sc->curve_e[c]);
        }
        used = strlen(md);
        snprintf(md + used, sizeof md - used, "\n\n");
    }
    size_t used = strlen(md);
    snprintf(md + used, sizeof md - used,
             "| run | method | params | time to image (s) | relMSE full | path tracer time at equal error (s) | "
             "speed-up |\n|---|---|---|---:|---:|---:|---:|\n");
    for (size_t i = 0; i < json_object_array_length(runs); i++) {
        json_object *o = json_object_array_get_idx(runs, i), *v;
        double sp = rec_num(o, "speedup_vs_pt", NULL, NULL);
        if (!isfinite(sp))
            continue;
        int ex = json_object_object_get_ex(o, "speedup_extrapolated", &v) && json_object_get_boolean(v);
        used = strlen(md);
        snprintf(md + used, sizeof md - used, "| %s | %s | `%s` | %.4g | %.4g | %.4g | %.3g%s |\n",
                 json_object_get_string(json_object_object_get(o, "run")),
                 json_object_get_string(json_object_object_get(o, "method")),
                 json_object_get_string(json_object_object_get(o, "params")),
                 rec_num(o, "frame_ms", "median", NULL) * rec_num(o, "frames", NULL, NULL) / 1000.0,
                 rec_num(o, "metrics", "full", "relmse"), rec_num(o, "pt_time_at_equal_error_s", NULL, NULL), sp,
                 ex ? " (extrapolated)" : "");
    }
    json_object_object_add(meta, "charts", chart_list);
    json_object_object_add(meta, "markdown", json_object_new_string(md));
}

int cmd_study(int argc, char **argv)
{
    const char *file = NULL, *out = NULL;
    unsigned long jobs = 1;
    int fresh = 0;
    for (int i = 0; i < argc; i++) {
        if (!strcmp(argv[i], "--out") && i + 1 < argc)
            out = argv[++i];
        else if (!strcmp(argv[i], "--jobs") && i + 1 < argc) {
            if (!cli_parse_uint(argv[++i], 1, 64, &jobs))
                return cli_fail(EXIT_USAGE, "study: --jobs '%s' is not an integer in 1..64", argv[i]);
        } else if (!strcmp(argv[i], "--resume"))
            fresh = 0;
        else if (!strcmp(argv[i], "--fresh"))
            fresh = 1;
        else if (argv[i][0] == '-')
            return cli_fail(EXIT_USAGE, "study: unknown or incomplete option '%s'", argv[i]);
        else if (!file)
            file = argv[i];
        else
            return cli_fail(EXIT_USAGE, "study: one study file at a time");
    }
    if (!file || !out)
        return cli_fail(EXIT_USAGE, "study: usage: gibench study STUDY.json --out DIR [--jobs N] [--resume|--fresh]");
    gi_plugins *reg = cli_load_plugins(0);
    study st;
    memset(&st, 0, sizeof st);
    int rc = load_study(&st, file, out, reg);
    if (rc == EXIT_OK && !cli_mkdirs(out))
        rc = cli_fail(EXIT_RUN, "study: cannot create %s", out);
    if (rc == EXIT_OK) {
        cli_install_signal_handlers();
        fprintf(stderr, "study: %s: %u runs on %u scenes\n", st.name, st.run_count, st.scene_count);
        rc = build_references(&st, out, reg);
    }
    if (rc == EXIT_OK) {
        execute_runs(&st, (uint32_t)jobs, fresh, reg);
        json_object *runs = json_object_new_array();
        char renderer[256] = "";
        int failed = 0;
        for (uint32_t i = 0; i < st.run_count; i++) {
            json_object *v;
            if (!st.runs[i].record)
                continue;
            if (!renderer[0] && json_object_object_get_ex(st.runs[i].record, "renderer", &v))
                snprintf(renderer, sizeof renderer, "%s", json_object_get_string(v));
            if (json_object_object_get_ex(st.runs[i].record, "status", &v) && !strcmp(json_object_get_string(v), "failed"))
                failed++;
            json_object_array_add(runs, json_object_get(st.runs[i].record));
        }
        char title[512], refdesc[256];
        snprintf(title, sizeof title, "gibench study: %s (%ux%u, %u frames)", st.name, st.width, st.height, st.frames);
        snprintf(refdesc, sizeof refdesc, "path traced (Embree), %u spp, %u bounces; bounce-matched the same spp",
                 st.ref_spp, st.ref_bounces);
        json_object *meta = report_meta_new(title, "study", argc, argv, renderer, refdesc);
        char ref_png[512];
        snprintf(ref_png, sizeof ref_png, "references/%s_b%u_%uspp.png", st.scenes[0].stem, st.ref_bounces, st.ref_spp);
        json_object_object_add(meta, "reference_png", json_object_new_string(ref_png));
        charts_and_speedups(&st, out, meta, runs);
        char why[1024];
        if (!report_write(out, runs, meta, why, sizeof why))
            rc = cli_fail(EXIT_RUN, "study: %s", why);
        else
            fprintf(stderr, "study: wrote %s/report.md, index.html, runs.csv (%d failed runs)\n", out, failed);
        if (rc == EXIT_OK && cli_interrupted)
            rc = cli_fail(EXIT_RUN, "study: interrupted; rerun the same command to resume");
        json_object_put(runs);
        json_object_put(meta);
    }
    for (uint32_t i = 0; st.runs && i < st.run_count; i++) {
        json_object_put(st.runs[i].record);
        for (int k = 0; k < MAX_KEYS; k++)
            free(st.runs[i].params[k]);
    }
    free(st.runs);
    json_object_put(st.root);
    gi_plugins_free(reg);
    return rc;
}
