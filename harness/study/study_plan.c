/* A study expanded into runs (docs/studies.md, "gibench study"): each parameter's
 * sweep (a value, a list or a range), the Cartesian product of an entry's
 * sweeps over its scenes and repeats, each run's identity (the hash of
 * every input that changes its result), and the reference sets (scene,
 * size, time) that the compared runs need, with their names. */
#define _POSIX_C_SOURCE 200809L
#include "study_internal.h"

#include "gi/cache.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The text of one sweep value: numbers as JSON wrote them, booleans and
 * strings as they are. 0 when the value has no such text (null, list, object). */
static int scalar_text(json_object *e, const char **out)
{
    if (!json_object_is_type(e, json_type_int) && !json_object_is_type(e, json_type_double) &&
        !json_object_is_type(e, json_type_boolean) && !json_object_is_type(e, json_type_string))
        return 0;
    *out = json_object_get_string(e);
    return *out != NULL;
}

/* Appends "name=value" to out[0..*n), refusing a value the range already
 * holds (a step or a count finer than the values can resolve). */
static int push_value(const char *file, const char *path, const char *name, const char *value,
                      char out[][128], int *n)
{
    char kv[128];
    if (snprintf(kv, sizeof kv, "%s=%s", name, value) >= (int)sizeof kv)
        return study_fail_json(file, path, "the value is too long");
    for (int i = 0; i < *n; i++)
        if (!strcmp(out[i], kv))
            return study_fail_json(
                file, path, "the range gives the same value twice (its step is lost to rounding)");
    memcpy(out[(*n)++], kv, sizeof kv);
    return EXIT_OK;
}

/* The values of a range object. Their number is computed and bounded
 * (at most MAX_SWEEP) before any is written, and integer ranges are
 * stepped in integers, so that no rounding can stretch the loop. */
static int range_values(const char *file, const char *path, const char *name, json_object *v,
                        char out[][128], int *n)
{
    static const char *const keys[] = {"from", "to", "step", "count", "scale", NULL};
    json_object_object_foreach(v, key, val)
    {
        (void)val;
        int ok = 0;
        for (int i = 0; keys[i]; i++)
            ok |= !strcmp(keys[i], key);
        if (!ok)
            return study_fail_json(
                file, path,
                "a range has only \"from\", \"to\", \"step\" or \"count\", and \"scale\"");
    }
    json_object *from, *to, *step = NULL, *count = NULL, *scale = NULL;
    if (!json_object_object_get_ex(v, "from", &from) || !json_object_object_get_ex(v, "to", &to))
        return study_fail_json(file, path, "a range needs \"from\" and \"to\"");
    int has_step = json_object_object_get_ex(v, "step", &step),
        has_count = json_object_object_get_ex(v, "count", &count);
    if (has_step == has_count)
        return study_fail_json(file, path, "a range needs \"step\" or \"count\" (one of them)");
    json_object *nums[3] = {from, to, has_step ? step : NULL};
    for (int k = 0; k < 3; k++)
        if (nums[k] && ((!json_object_is_type(nums[k], json_type_int) &&
                         !json_object_is_type(nums[k], json_type_double)) ||
                        !isfinite(json_object_get_double(nums[k]))))
            return study_fail_json(file, path,
                                   "\"from\", \"to\" and \"step\" must be finite numbers");
    int log_scale = 0;
    if (json_object_object_get_ex(v, "scale", &scale)) {
        const char *sv =
            json_object_is_type(scale, json_type_string) ? json_object_get_string(scale) : "";
        if (has_step || (strcmp(sv, "lin") && strcmp(sv, "log")))
            return study_fail_json(file, path, "\"scale\" is \"lin\" or \"log\", with \"count\"");
        log_scale = !strcmp(sv, "log");
    }
    int is_int = json_object_is_type(from, json_type_int) && json_object_is_type(to, json_type_int);
    double a = json_object_get_double(from), b = json_object_get_double(to);
    char text[64];
    *n = 0;
    if (has_count) {
        if (!json_object_is_type(count, json_type_int) || json_object_get_int64(count) < 1 ||
            json_object_get_int64(count) > MAX_SWEEP)
            return study_fail_json(file, path, "\"count\" must be an integer in 1..64");
        if (log_scale && !(a > 0 && b > 0))
            return study_fail_json(file, path, "a log range needs positive \"from\" and \"to\"");
        int c = (int)json_object_get_int64(count);
        for (int i = 0; i < c; i++) {
            double t = c == 1 ? 0.0 : (double)i / (c - 1);
            double x = log_scale ? exp(log(a) + t * (log(b) - log(a))) : a + t * (b - a);
            if (is_int)
                snprintf(text, sizeof text, "%lld", (long long)llround(x));
            else
                snprintf(text, sizeof text, "%.9g", x);
            int rc = push_value(file, path, name, text, out, n);
            if (rc != EXIT_OK)
                return rc;
        }
        return EXIT_OK;
    }
    if (is_int && json_object_is_type(step, json_type_int)) {
        int64_t ia = json_object_get_int64(from), ib = json_object_get_int64(to),
                is = json_object_get_int64(step);
        if (is <= 0)
            return study_fail_json(file, path, "\"step\" must be positive");
        if (ib < ia)
            return study_fail_json(file, path, "the range is empty (\"to\" is below \"from\")");
        uint64_t steps = ((uint64_t)ib - (uint64_t)ia) / (uint64_t)is; /* exact: ib >= ia */
        if (steps > MAX_SWEEP - 1)
            return study_fail_json(file, path, "the range gives more than 64 values");
        for (uint64_t i = 0; i <= steps; i++) {
            snprintf(text, sizeof text, "%lld", (long long)(ia + (int64_t)i * is));
            int rc = push_value(file, path, name, text, out, n);
            if (rc != EXIT_OK)
                return rc;
        }
        return EXIT_OK;
    }
    double s = json_object_get_double(step);
    if (!(s > 0))
        return study_fail_json(file, path, "\"step\" must be positive");
    if (b < a)
        return study_fail_json(file, path, "the range is empty (\"to\" is below \"from\")");
    double span = (b - a) / s;
    if (!(span <= MAX_SWEEP - 1 + 1e-9))
        return study_fail_json(file, path, "the range gives more than 64 values");
    int steps = (int)floor(span + 1e-9);
    for (int i = 0; i <= steps; i++) {
        snprintf(text, sizeof text, "%.9g", a + i * s);
        int rc = push_value(file, path, name, text, out, n);
        if (rc != EXIT_OK)
            return rc;
    }
    return EXIT_OK;
}

/* Values of one parameter: a scalar, a list, or a range
 * {"from": a, "to": b, "step": s} / {"from": a, "to": b, "count": n, "scale": "log"}.
 * Written as text "name=value", at most MAX_SWEEP of them. */
static int sweep_values(const char *file, const char *mpath, const char *name, json_object *v,
                        char out[][128], int *n)
{
    char path[512];
    snprintf(path, sizeof path, "%s/params/%s", mpath, name);
    *n = 0;
    const char *text;
    if (json_object_is_type(v, json_type_array)) {
        size_t len = json_object_array_length(v);
        if (len == 0 || len > MAX_SWEEP)
            return study_fail_json(file, path, "a sweep needs 1 to 64 values");
        for (size_t i = 0; i < len; i++) {
            if (!scalar_text(json_object_array_get_idx(v, i), &text))
                return study_fail_json(file, path,
                                       "sweep values must be numbers, booleans or strings");
            if (snprintf(out[*n], 128, "%s=%s", name, text) >= 128)
                return study_fail_json(file, path, "the value is too long");
            (*n)++;
        }
        return EXIT_OK;
    }
    if (json_object_is_type(v, json_type_object))
        return range_values(file, path, name, v, out, n);
    if (!scalar_text(v, &text))
        return study_fail_json(file, path,
                               "a value is a number, a boolean, a string, a list or a range");
    if (snprintf(out[0], 128, "%s=%s", name, text) >= 128)
        return study_fail_json(file, path, "the value is too long");
    *n = 1;
    return EXIT_OK;
}

/* The references a compared run needs: one set per scene, size and time. */
static int ref_index(study *st, int scene, uint32_t w, uint32_t h, float time, int frame)
{
    for (uint32_t i = 0; i < st->ref_count; i++) {
        study_ref *r = &st->refs[i];
        if (r->scene_index == scene && r->width == w && r->height == h && r->time == time) {
            if (!frame)
                r->frame_only = 0; /* a still run compares with it too */
            r->want_alt |= frame;
            return (int)i;
        }
    }
    if (st->ref_count == MAX_REFS)
        return -1;
    study_ref *r = &st->refs[st->ref_count];
    memset(r, 0, sizeof *r);
    r->scene_index = scene;
    r->width = w;
    r->height = h;
    r->time = time;
    r->frame_only = frame;
    r->want_alt = frame;
    return (int)st->ref_count++;
}

/* Names the reference sets: the scene's stem, with size and time added
 * where one scene has several. */
void study_name_refs(study *st)
{
    for (uint32_t i = 0; i < st->ref_count; i++) {
        study_ref *r = &st->refs[i];
        int shared = 0;
        /* the sets of animation frames do not rename the others */
        for (uint32_t k = 0; k < st->ref_count; k++)
            shared |=
                k != i && st->refs[k].scene_index == r->scene_index && !st->refs[k].frame_only;
        /* two scenes of one name (in different folders) get apart by content */
        char stem[300];
        const study_scene *sc = &st->scenes[r->scene_index];
        int same_name = 0;
        for (uint32_t k = 0; k < st->scene_count; k++)
            same_name |= (int)k != r->scene_index && !strcmp(st->scenes[k].stem, sc->stem);
        if (same_name)
            snprintf(stem, sizeof stem, "%s-%08x", sc->stem, (unsigned)(sc->hash & 0xFFFFFFFFu));
        else
            snprintf(stem, sizeof stem, "%s", sc->stem);
        if (r->frame_only) {
            /* the frame's time as %g, or all its digits where two frames would share a name */
            snprintf(r->name, sizeof r->name, "%.280s_%ux%u_t%g", stem, r->width, r->height,
                     (double)r->time);
            for (uint32_t k = 0; k < i; k++)
                if (!strcmp(st->refs[k].name, r->name))
                    snprintf(r->name, sizeof r->name, "%.280s_%ux%u_t%.9g", stem, r->width,
                             r->height, (double)r->time);
        } else if (!shared)
            snprintf(r->name, sizeof r->name, "%s", stem);
        else if (r->time == 0.0f)
            snprintf(r->name, sizeof r->name, "%s_%ux%u", stem, r->width, r->height);
        else
            snprintf(r->name, sizeof r->name, "%s_%ux%u_t%g", stem, r->width, r->height,
                     (double)r->time);
    }
}

static int add_run(study *st, const char *file, const char *out_dir, const gi_method *m,
                   char combo[][128], int nk, uint32_t repeat, const run_settings *rs)
{
    for (uint32_t k = 0; k < rs->scene_n; k++) {
        int si = rs->scenes[k];
        if (st->run_count == MAX_RUNS)
            return cli_fail(EXIT_USAGE, "%s: more than %d runs", file, MAX_RUNS);
        study_run *r = &st->runs[st->run_count];
        memset(r, 0, sizeof *r);
        char
            key[MAX_KEYS * 128 + 4096]; /* every parameter's text: a cut key would merge two runs */
        /* every input that changes the result: the scene by its content, the
         * method, seed, camera, size, frames, times, exposure, timer mode,
         * cache and comparison, and each parameter */
        snprintf(key, sizeof key,
                 "%016llx|%s|seed=%u|camera=%s|%ux%u|%u/%u|%.9g|%.9g|ev=%.9g|timer=%s|%d|%d",
                 (unsigned long long)st->scenes[si].hash, m->id, st->seed + repeat,
                 st->camera_name ? st->camera_name : "-", rs->width, rs->height, rs->frames,
                 rs->warmup, (double)rs->time, (double)rs->animate_fps, (double)st->exposure,
                 st->timer ? st->timer : "-", rs->cache, rs->compare);
        for (int p = 0; p < nk; p++) {
            r->params[p] = strdup(combo[p]);
            size_t used = strlen(key);
            snprintf(key + used, sizeof key - used, "|%s", combo[p]);
        }
        uint64_t h = gi_hash64(key, strlen(key), 0);
        /* the same key with the repeat's seed left out */
        char *seed_at = strstr(key, "|seed=");
        if (seed_at) {
            char *end = strchr(seed_at + 1, '|');
            if (end)
                memmove(seed_at, end, strlen(end) + 1);
        }
        r->setting = gi_hash64(key, strlen(key), 0);
        snprintf(r->id, sizeof r->id, "%s-%s-%08x", st->scenes[si].stem, m->id,
                 (unsigned)(h & 0xFFFFFFFFu));
        snprintf(r->rel, sizeof r->rel, "runs/%s", r->id);
        snprintf(r->dir, sizeof r->dir, "%s/%s", out_dir, r->rel);
        r->scene_index = si;
        r->bounces = m->max_bounces + 1;
        r->ref_index = -1;
        if (rs->compare && rs->animate_fps > 0) {
            /* compared frame by frame: a reference set per frame's scene
             * time (as render computes it); the run's final image is its
             * last frame, compared with the last set */
            r->frame_ref = calloc(rs->frames, sizeof *r->frame_ref);
            r->fr_full = calloc(rs->frames, sizeof *r->fr_full);
            r->fr_matched = calloc(rs->frames, sizeof *r->fr_matched);
            r->fr_alt = calloc(rs->frames, sizeof *r->fr_alt);
            if (!r->frame_ref || !r->fr_full || !r->fr_matched || !r->fr_alt)
                return cli_fail(EXIT_RUN, "out of memory");
            r->frame_ref_n = rs->frames;
            for (uint32_t f = 0; f < rs->frames; f++) {
                float t = rs->time + (float)f / rs->animate_fps;
                r->frame_ref[f] = ref_index(st, si, rs->width, rs->height, t, 1);
                if (r->frame_ref[f] < 0)
                    return cli_fail(
                        EXIT_USAGE,
                        "%s: more than %d (scene, size, time) reference sets (an animated "
                        "compared run needs one per frame)",
                        file, MAX_REFS);
            }
            r->ref_index = r->frame_ref[rs->frames - 1];
        } else if (rs->compare) {
            r->ref_index = ref_index(st, si, rs->width, rs->height, rs->time, 0);
            if (r->ref_index < 0)
                return cli_fail(EXIT_USAGE, "%s: more than %d (scene, size, time) reference sets",
                                file, MAX_REFS);
        }
        run_spec *s = &r->spec;
        s->run_id = r->id;
        s->scene = st->scenes[si].path;
        s->method = m->id;
        s->camera = st->camera;
        s->width = rs->width;
        s->height = rs->height;
        s->frames = rs->frames;
        s->warmup = rs->warmup;
        s->seed = st->seed + repeat;
        s->time = rs->time;
        s->animate_fps = rs->animate_fps;
        s->no_cache = !rs->cache;
        s->label = rs->label;
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
int study_expand_method(study *st, const char *file, const char *out_dir, const gi_method *m,
                        json_object *params, const char *mpath, const run_settings *rs)
{
    static char values[MAX_KEYS][MAX_SWEEP][128];
    int counts[MAX_KEYS], nk = 0;
    if (params) {
        json_object_object_foreach(params, name, v)
        {
            if (nk == MAX_KEYS)
                return study_fail_json(file, mpath, "more than 64 parameters");
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
    /* the number of runs the entry makes, bounded before any is made */
    uint64_t cells = (uint64_t)rs->repeats * rs->scene_n;
    for (int k = 0; k < nk && cells <= MAX_RUNS; k++)
        cells *= (uint64_t)counts[k];
    if (cells > MAX_RUNS - st->run_count) {
        char msg[128];
        snprintf(msg, sizeof msg, "the study makes more than %d runs", MAX_RUNS);
        return study_fail_json(file, mpath, msg);
    }
    /* repeats outermost: the entry's whole sweep once per repeat, so that
     * slow spells of a shared machine spread over all variants alike */
    for (uint32_t rep = 0; rep < rs->repeats; rep++) {
        int idx[MAX_KEYS] = {0};
        for (;;) {
            char combo[MAX_KEYS][128];
            for (int k = 0; k < nk; k++)
                snprintf(combo[k], 128, "%s", values[k][idx[k]]);
            int rc = add_run(st, file, out_dir, m, combo, nk, rep, rs);
            if (rc != EXIT_OK)
                return rc;
            int k = 0;
            while (k < nk && ++idx[k] == counts[k])
                idx[k++] = 0;
            if (k == nk)
                break;
        }
    }
    return EXIT_OK;
}
