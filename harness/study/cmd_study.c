/* gibench study: a declarative experiment (harness/studies/NAME.json)
 * expanded into independent runs, executed in child processes by a worker
 * pool, cached by the hash of each run's configuration, and reported with
 * tables and error-against-time charts that include the path tracer's own
 * convergence curve. The file format is documented in README.md ("Studies"). */
#define _POSIX_C_SOURCE 200809L
#include "study.h"
#include "view_file.h"

#include "charts.h"
#include "gi/cache.h"
#include "report.h"
#include "runner.h"
#include "slurm.h"
#include "tradeoff.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#define MAX_RUNS 4096
#define MAX_SWEEP 64
#define MAX_KEYS 64 /* parameters of one entry: as many as render takes (--param) */
#define MAX_SCENES 16
#define MAX_REFS 512 /* an animated run compared frame by frame needs a set per frame */

/* What a run is made with: the study's top-level values, overridden per
 * method entry (README.md, "Studies"). */
typedef struct run_settings {
    int scenes[MAX_SCENES]; /* indices into study.scenes */
    uint32_t scene_n;
    uint32_t width, height, frames, warmup;
    uint32_t repeats; /* each with seed + r; an entry's repeats are interleaved */
    float time, animate_fps;
    int cache;   /* 0: render --no-cache (precomputation timed afresh) */
    int compare; /* 0: no references, no metrics (timing-only runs) */
    const char *label;
} run_settings;

typedef struct study_run {
    run_spec spec;
    char id[512], dir[4096], rel[1024];
    char *params[MAX_KEYS];
    int scene_index;
    int ref_index;    /* -1: not compared */
    uint32_t bounces; /* the method's max_bounces + 1 */
    uint64_t setting; /* every input but the seed: runs of one setting are repeats */
    json_object *record;
    /* an animated compared run: the reference set of each frame's time, and
     * the file names handed to the runner (run_spec.frame_ref_*) */
    int *frame_ref;
    uint32_t frame_ref_n;
    const char **fr_full, **fr_matched, **fr_alt;
} study_run;

typedef struct study_scene {
    const char *path;
    char stem[256];
    uint64_t hash; /* its content: the file, every object's geometry, the environment map */
    uint32_t triangles, vertices; /* for scale studies (records get scene_triangles) */
} study_scene;

/* The references of one scene at one size and scene time. */
typedef struct study_ref {
    int scene_index;
    uint32_t width, height;
    float time;
    char name[320]; /* the scene's stem, plus size and time where a scene has several */
    char ref_full[4096];
    char ref_matched[8][4096];
    uint32_t matched_bounces[8];
    uint32_t matched_count;
    /* the path tracer's convergence: full GI, and for each matched bounce count */
    tradeoff_pt_curve pt_full, pt_matched[8];
    char missing[1100]; /* gibench study --slurm-collect: why the set was not made, or "" */
    int frame_only; /* used only by animated runs' frames: no convergence curve, no tradeoff table
                     */
    int want_alt;   /* a frame: also the full-GI reference with another seed (the noise floor) */
    char ref_alt[4096];
} study_ref;

typedef struct study {
    json_object *root;
    const char *name;
    uint32_t seed;
    uint32_t ref_spp, ref_bounces;
    double ref_target_se; /* 0: none */
    int ref_pixel_center; /* "pixel": "center": references sample pixel centres */
    uint32_t conv_spp[32], conv_n;
    float exposure;
    const char *camera;
    double timeout_s;
    run_settings base;
    study_scene scenes[MAX_SCENES];
    uint32_t scene_count;
    study_ref *refs; /* MAX_REFS of them, on the heap */
    uint32_t ref_count;
    json_object *charts; /* the "charts" list, or NULL */
    const char *timer;   /* "timer": GIBENCH_TIMER for the runs, or NULL */
    study_run *runs;
    uint32_t run_count;
} study;

static int fail_json(const char *file, const char *path, const char *what)
{
    return cli_fail(EXIT_USAGE, "%s: %s: %s", file, path, what);
}

/* o[key] as an integer in [min, max] (absent or null: def); `prefix` is the
 * JSON path of o for messages. */
static int get_uint(json_object *o, const char *prefix, const char *key, uint32_t min, uint32_t max,
                    uint32_t def, uint32_t *out, const char *file)
{
    json_object *v;
    *out = def;
    if (!json_object_object_get_ex(o, key, &v) || json_object_is_type(v, json_type_null))
        return EXIT_OK;
    if (!json_object_is_type(v, json_type_int) || json_object_get_int64(v) < min ||
        json_object_get_int64(v) > max) {
        char msg[128];
        snprintf(msg, sizeof msg, "must be an integer in [%u, %u]", min, max);
        char path[160];
        snprintf(path, sizeof path, "%s/%s", prefix, key);
        return fail_json(file, path, msg);
    }
    *out = (uint32_t)json_object_get_int64(v);
    return EXIT_OK;
}

/* o[key] as a number in [min, max] (absent or null: def). */
static int get_number(json_object *o, const char *prefix, const char *key, double min, double max,
                      double def, double *out, const char *file)
{
    json_object *v;
    *out = def;
    if (!json_object_object_get_ex(o, key, &v) || json_object_is_type(v, json_type_null))
        return EXIT_OK;
    double d = json_object_get_double(v);
    if ((!json_object_is_type(v, json_type_int) && !json_object_is_type(v, json_type_double)) ||
        !(d >= min) || !(d <= max)) {
        char msg[128], path[160];
        snprintf(msg, sizeof msg, "must be a number in [%g, %g]", min, max);
        snprintf(path, sizeof path, "%s/%s", prefix, key);
        return fail_json(file, path, msg);
    }
    *out = d;
    return EXIT_OK;
}

/* o[key] as a string (absent: def; null too when null_ok). */
static int get_string(json_object *o, const char *prefix, const char *key, int null_ok,
                      const char *def, const char **out, const char *file)
{
    json_object *v;
    *out = def;
    if (!json_object_object_get_ex(o, key, &v) ||
        (null_ok && json_object_is_type(v, json_type_null)))
        return EXIT_OK;
    if (!json_object_is_type(v, json_type_string)) {
        char path[160];
        snprintf(path, sizeof path, "%s/%s", prefix, key);
        return fail_json(file, path, null_ok ? "must be a string or null" : "must be a string");
    }
    *out = json_object_get_string(v);
    return EXIT_OK;
}

/* json-c keeps the last of two equal keys in an object and drops the
 * first without a word; a study file that gives "params" (or "spp", ...)
 * twice is refused instead, naming the key's JSON path and its line. The
 * text has already parsed as strict JSON, so a small scanner suffices:
 * strings, the brackets and commas around them. Keys compare as written
 * (escapes are not decoded). Returns EXIT_OK or EXIT_USAGE after printing. */
typedef struct key_frame {
    int is_object, want_key;
    size_t index;    /* arrays: the element being read */
    const char *key; /* objects: the key being read */
    size_t key_len;
    const char **keys; /* objects: keys seen (into the text) */
    size_t *lens, count, cap;
} key_frame;

static int check_duplicate_keys(const char *file, const char *text, size_t n)
{
    enum { MAX_DEPTH = 64 }; /* json-c stops at 32 */
    key_frame st[MAX_DEPTH];
    int top = -1, rc = EXIT_OK;
    size_t line = 1;
    for (size_t i = 0; i < n && rc == EXIT_OK; i++) {
        char c = text[i];
        if (c == '\n') {
            line++;
        } else if (c == '"') {
            size_t j = i + 1;
            while (j < n && text[j] != '"')
                j += text[j] == '\\' ? 2 : 1;
            if (j > n)
                j = n;
            key_frame *f = top >= 0 ? &st[top] : NULL;
            if (f && f->is_object && f->want_key) {
                const char *k = text + i + 1;
                size_t kl = j - i - 1;
                for (size_t q = 0; q < f->count; q++)
                    if (f->lens[q] == kl && !memcmp(f->keys[q], k, kl)) {
                        char path[512];
                        size_t used = 0;
                        for (int d = 0; d < top && used < sizeof path; d++) {
                            int w = st[d].is_object
                                        ? snprintf(path + used, sizeof path - used, "/%.*s",
                                                   (int)st[d].key_len, st[d].key)
                                        : snprintf(path + used, sizeof path - used, "/%zu",
                                                   st[d].index);
                            used += w > 0 ? (size_t)w : 0;
                        }
                        if (used < sizeof path)
                            snprintf(path + used, sizeof path - used, "/%.*s", (int)kl, k);
                        char what[64];
                        snprintf(what, sizeof what, "key given twice (line %zu)", line);
                        rc = fail_json(file, path, what);
                        break;
                    }
                if (rc == EXIT_OK && f->count == f->cap) {
                    size_t cap = f->cap ? 2 * f->cap : 8;
                    const char **keys = realloc(f->keys, cap * sizeof *keys);
                    if (keys)
                        f->keys = keys;
                    size_t *lens = keys ? realloc(f->lens, cap * sizeof *lens) : NULL;
                    if (lens)
                        f->lens = lens;
                    if (!keys || !lens)
                        rc = cli_fail(EXIT_RUN, "%s: out of memory", file);
                    else
                        f->cap = cap;
                }
                if (rc == EXIT_OK) {
                    f->keys[f->count] = k;
                    f->lens[f->count++] = kl;
                    f->key = k;
                    f->key_len = kl;
                    f->want_key = 0;
                }
            }
            for (size_t q = i + 1; q < j; q++)
                line += text[q] == '\n';
            i = j;
        } else if (c == '{' || c == '[') {
            if (top + 1 >= MAX_DEPTH)
                break; /* deeper than json-c reads: it refused the file already */
            key_frame *f = &st[++top];
            memset(f, 0, sizeof *f);
            f->is_object = c == '{';
            f->want_key = f->is_object;
        } else if ((c == '}' || c == ']') && top >= 0) {
            free(st[top].keys);
            free(st[top].lens);
            top--;
        } else if (c == ',' && top >= 0) {
            if (st[top].is_object)
                st[top].want_key = 1;
            else
                st[top].index++;
        }
    }
    for (; top >= 0; top--) {
        free(st[top].keys);
        free(st[top].lens);
    }
    return rc;
}

/* The study file as strict JSON (no trailing commas, no comments, nothing
 * after the top-level value); NULL after printing where it goes wrong. */
static json_object *read_strict_json(const char *file)
{
    size_t n = 0;
    char *text = gi_file_read_all(file, &n);
    if (!text) {
        cli_fail(EXIT_USAGE, "%s: cannot read the study file", file);
        return NULL;
    }
    json_tokener *tok = json_tokener_new();
    json_object *o = NULL;
    if (tok) {
        json_tokener_set_flags(tok, JSON_TOKENER_STRICT);
        o = json_tokener_parse_ex(tok, text, (int)n);
        enum json_tokener_error e = json_tokener_get_error(tok);
        size_t end = json_tokener_get_parse_end(tok);
        if (e == json_tokener_continue)
            e = json_tokener_error_parse_eof;
        if (e != json_tokener_success || !o) {
            size_t line = 1;
            for (size_t i = 0; i < end && i < n; i++)
                line += text[i] == '\n';
            cli_fail(EXIT_USAGE, "%s: line %zu: not valid JSON: %s", file, line,
                     json_tokener_error_desc(e));
            json_object_put(o);
            o = NULL;
        }
        json_tokener_free(tok);
    }
    if (o && check_duplicate_keys(file, text, n) != EXIT_OK) {
        json_object_put(o);
        o = NULL;
    }
    free(text);
    return o;
}

/* Rejects keys of o that are not in `known` (NULL-terminated). */
static int check_keys(json_object *o, const char *const *known, const char *prefix,
                      const char *file)
{
    if (!json_object_is_type(o, json_type_object))
        return fail_json(file, *prefix ? prefix : "/", "must be an object {key: value}");
    json_object_object_foreach(o, key, val)
    {
        (void)val;
        int ok = 0;
        for (int i = 0; known[i]; i++)
            ok |= !strcmp(known[i], key);
        if (!ok) {
            char path[256];
            snprintf(path, sizeof path, "%s/%s", prefix, key);
            return fail_json(file, path, "unknown key");
        }
    }
    return EXIT_OK;
}
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
        return fail_json(file, path, "the value is too long");
    for (int i = 0; i < *n; i++)
        if (!strcmp(out[i], kv))
            return fail_json(file, path,
                             "the range gives the same value twice (its step is lost to rounding)");
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
            return fail_json(
                file, path,
                "a range has only \"from\", \"to\", \"step\" or \"count\", and \"scale\"");
    }
    json_object *from, *to, *step = NULL, *count = NULL, *scale = NULL;
    if (!json_object_object_get_ex(v, "from", &from) || !json_object_object_get_ex(v, "to", &to))
        return fail_json(file, path, "a range needs \"from\" and \"to\"");
    int has_step = json_object_object_get_ex(v, "step", &step),
        has_count = json_object_object_get_ex(v, "count", &count);
    if (has_step == has_count)
        return fail_json(file, path, "a range needs \"step\" or \"count\" (one of them)");
    json_object *nums[3] = {from, to, has_step ? step : NULL};
    for (int k = 0; k < 3; k++)
        if (nums[k] && ((!json_object_is_type(nums[k], json_type_int) &&
                         !json_object_is_type(nums[k], json_type_double)) ||
                        !isfinite(json_object_get_double(nums[k]))))
            return fail_json(file, path, "\"from\", \"to\" and \"step\" must be finite numbers");
    int log_scale = 0;
    if (json_object_object_get_ex(v, "scale", &scale)) {
        const char *sv =
            json_object_is_type(scale, json_type_string) ? json_object_get_string(scale) : "";
        if (has_step || (strcmp(sv, "lin") && strcmp(sv, "log")))
            return fail_json(file, path, "\"scale\" is \"lin\" or \"log\", with \"count\"");
        log_scale = !strcmp(sv, "log");
    }
    int is_int = json_object_is_type(from, json_type_int) && json_object_is_type(to, json_type_int);
    double a = json_object_get_double(from), b = json_object_get_double(to);
    char text[64];
    *n = 0;
    if (has_count) {
        if (!json_object_is_type(count, json_type_int) || json_object_get_int64(count) < 1 ||
            json_object_get_int64(count) > MAX_SWEEP)
            return fail_json(file, path, "\"count\" must be an integer in 1..64");
        if (log_scale && !(a > 0 && b > 0))
            return fail_json(file, path, "a log range needs positive \"from\" and \"to\"");
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
            return fail_json(file, path, "\"step\" must be positive");
        if (ib < ia)
            return fail_json(file, path, "the range is empty (\"to\" is below \"from\")");
        uint64_t steps = ((uint64_t)ib - (uint64_t)ia) / (uint64_t)is; /* exact: ib >= ia */
        if (steps > MAX_SWEEP - 1)
            return fail_json(file, path, "the range gives more than 64 values");
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
        return fail_json(file, path, "\"step\" must be positive");
    if (b < a)
        return fail_json(file, path, "the range is empty (\"to\" is below \"from\")");
    double span = (b - a) / s;
    if (!(span <= MAX_SWEEP - 1 + 1e-9))
        return fail_json(file, path, "the range gives more than 64 values");
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
            return fail_json(file, path, "a sweep needs 1 to 64 values");
        for (size_t i = 0; i < len; i++) {
            if (!scalar_text(json_object_array_get_idx(v, i), &text))
                return fail_json(file, path, "sweep values must be numbers, booleans or strings");
            if (snprintf(out[*n], 128, "%s=%s", name, text) >= 128)
                return fail_json(file, path, "the value is too long");
            (*n)++;
        }
        return EXIT_OK;
    }
    if (json_object_is_type(v, json_type_object))
        return range_values(file, path, name, v, out, n);
    if (!scalar_text(v, &text))
        return fail_json(file, path, "a value is a number, a boolean, a string, a list or a range");
    if (snprintf(out[0], 128, "%s=%s", name, text) >= 128)
        return fail_json(file, path, "the value is too long");
    *n = 1;
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

/* The scene's index in the study, loading (and so validating) it once. */
static int scene_index(study *st, const char *file, const char *jpath, const char *path, int *out)
{
    for (uint32_t i = 0; i < st->scene_count; i++)
        if (!strcmp(st->scenes[i].path, path)) {
            *out = (int)i;
            return EXIT_OK;
        }
    if (st->scene_count == MAX_SCENES)
        return fail_json(file, jpath, "more than 16 scenes in one study");
    gi_error err;
    gi_scene *s = gi_scene_load(path, &err);
    if (!s)
        return cli_fail(EXIT_USAGE, "%s: %s: %s", file, jpath, err.text);
    /* "camera": "view:FILE.json", a view saved by gibench view: its camera
     * and moved objects; the view's content joins the scene's in the key */
    view_file view;
    char why[600];
    int is_view = view_camera_read(st->camera, &view, why, sizeof why);
    if (is_view < 0) {
        gi_scene_free(s);
        return cli_fail(EXIT_USAGE, "%s: /camera: %s", file, why);
    }
    if (is_view) {
        int ok = view_file_check_nodes(&view, s, why, sizeof why);
        view_file_free(&view);
        if (!ok) {
            gi_scene_free(s);
            return cli_fail(EXIT_USAGE, "%s: /camera: %s with %s: %s", file, st->camera + 5, path,
                            why);
        }
    }
    int has_camera = !st->camera || is_view || gi_scene_find_camera(s, st->camera) >= 0;
    uint32_t triangles = s->triangle_count, vertices = s->vertex_count;
    /* the scene by its content, not its name */
    uint64_t hash = cli_scene_content_hash(s, path);
    gi_scene_free(s);
    if (is_view) {
        size_t n = 0;
        unsigned char *bytes = (unsigned char *)gi_file_read_all(st->camera + 5, &n);
        for (size_t i = 0; bytes && i < n; i++)
            hash = (hash ^ bytes[i]) * 0x100000001b3ull; /* FNV-1a over the view's bytes */
        free(bytes);
    }
    if (!has_camera)
        return cli_fail(EXIT_USAGE, "%s: /camera: %s has no camera '%s'", file, path, st->camera);
    study_scene *sc = &st->scenes[st->scene_count];
    sc->path = path;
    sc->hash = hash;
    sc->triangles = triangles;
    sc->vertices = vertices;
    stem_of(path, sc->stem, sizeof sc->stem);
    *out = (int)st->scene_count++;
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
static void name_refs(study *st)
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

/* Reads the run settings that a method entry (or the top level) may give:
 * scenes, size, frames, warmup, time, animate, cache, compare, label. */
static int parse_settings(study *st, json_object *o, const char *prefix, const char *file,
                          run_settings *rs)
{
    json_object *v;
    char path[160];
    if (json_object_object_get_ex(o, "scenes", &v)) {
        snprintf(path, sizeof path, "%s/scenes", prefix);
        if (!json_object_is_type(v, json_type_array) || json_object_array_length(v) == 0 ||
            json_object_array_length(v) > MAX_SCENES)
            return fail_json(file, path, "a list of 1 to 16 scene files is required");
        rs->scene_n = 0;
        for (size_t i = 0; i < json_object_array_length(v); i++) {
            json_object *e = json_object_array_get_idx(v, i);
            char ep[200];
            snprintf(ep, sizeof ep, "%s/%zu", path, i);
            if (!json_object_is_type(e, json_type_string))
                return fail_json(file, ep, "a scene is a file name");
            int rc = scene_index(st, file, ep, json_object_get_string(e), &rs->scenes[rs->scene_n]);
            if (rc != EXIT_OK)
                return rc;
            rs->scene_n++;
        }
    }
    if (json_object_object_get_ex(o, "size", &v)) {
        snprintf(path, sizeof path, "%s/size", prefix);
        if (!json_object_is_type(v, json_type_array) || json_object_array_length(v) != 2)
            return fail_json(file, path, "must be [width, height]");
        json_object *jw = json_object_array_get_idx(v, 0), *jh = json_object_array_get_idx(v, 1);
        int64_t w = json_object_get_int64(jw), h = json_object_get_int64(jh);
        if (!json_object_is_type(jw, json_type_int) || !json_object_is_type(jh, json_type_int) ||
            w < 1 || h < 1 || w > 16384 || h > 16384)
            return fail_json(file, path, "width and height must be integers in 1..16384");
        rs->width = (uint32_t)w;
        rs->height = (uint32_t)h;
    }
    int rc;
    if ((rc = get_uint(o, prefix, "frames", 1, 100000, rs->frames, &rs->frames, file)) ||
        (rc = get_uint(o, prefix, "warmup", 0, 1000, rs->warmup, &rs->warmup, file)) ||
        (rc = get_uint(o, prefix, "repeats", 1, 100, rs->repeats, &rs->repeats, file)))
        return rc;
    if (rs->warmup >= rs->frames)
        rs->warmup = rs->frames > 1 ? rs->frames - 1 : 0;
    double d;
    if ((rc = get_number(o, prefix, "time", 0.0, 1e6, rs->time, &d, file)))
        return rc;
    rs->time = (float)d;
    if (json_object_object_get_ex(o, "animate", &v) && !json_object_is_type(v, json_type_null)) {
        d = json_object_get_double(v);
        if ((!json_object_is_type(v, json_type_int) && !json_object_is_type(v, json_type_double)) ||
            !(d > 0) || !(d <= 1e4)) {
            snprintf(path, sizeof path, "%s/animate", prefix);
            return fail_json(
                file, path,
                "must be a positive frame rate (frames per second of scene time, at most 1e4)");
        }
        rs->animate_fps = (float)d;
    }
    const char *flags[2] = {"cache", "compare"};
    int *dest[2] = {&rs->cache, &rs->compare};
    for (int k = 0; k < 2; k++)
        if (json_object_object_get_ex(o, flags[k], &v)) {
            if (!json_object_is_type(v, json_type_boolean)) {
                snprintf(path, sizeof path, "%s/%s", prefix, flags[k]);
                return fail_json(file, path, "must be true or false");
            }
            *dest[k] = json_object_get_boolean(v);
        }
    if (json_object_object_get_ex(o, "label", &v)) {
        if (!json_object_is_type(v, json_type_string)) {
            snprintf(path, sizeof path, "%s/label", prefix);
            return fail_json(file, path, "must be a string");
        }
        rs->label = json_object_get_string(v);
    }
    return EXIT_OK;
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
                 st->camera ? st->camera : "-", rs->width, rs->height, rs->frames, rs->warmup,
                 (double)rs->time, (double)rs->animate_fps, (double)st->exposure,
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
static int expand_method(study *st, const char *file, const char *out_dir, const gi_method *m,
                         json_object *params, const char *mpath, const run_settings *rs)
{
    static char values[MAX_KEYS][MAX_SWEEP][128];
    int counts[MAX_KEYS], nk = 0;
    if (params) {
        json_object_object_foreach(params, name, v)
        {
            if (nk == MAX_KEYS)
                return fail_json(file, mpath, "more than 64 parameters");
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
        return fail_json(file, mpath, msg);
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

/* Checks the "charts" list (each chart is drawn after the runs). */
static int check_charts(json_object *charts, const char *file)
{
    if (!json_object_is_type(charts, json_type_array) || json_object_array_length(charts) > 32)
        return fail_json(file, "/charts", "must be a list of at most 32 charts");
    static const char *known[] = {"file",  "title", "where",   "x",       "y", "series",
                                  "log_x", "log_y", "x_label", "y_label", NULL};
    for (size_t i = 0; i < json_object_array_length(charts); i++) {
        json_object *c = json_object_array_get_idx(charts, i), *v;
        char path[64];
        snprintf(path, sizeof path, "/charts/%zu", i);
        if (!json_object_is_type(c, json_type_object))
            return fail_json(file, path, "a chart is an object");
        int rc = check_keys(c, known, path, file);
        if (rc != EXIT_OK)
            return rc;
        const char *need[3] = {"file", "x", "y"};
        for (int k = 0; k < 3; k++)
            if (!json_object_object_get_ex(c, need[k], &v) ||
                !json_object_is_type(v, json_type_string) || !*json_object_get_string(v))
                return fail_json(file, path, "a chart needs \"file\", \"x\" and \"y\" (strings)");
        const char *f = json_object_get_string(json_object_object_get(c, "file"));
        size_t n = strlen(f);
        if (n < 5 || strcmp(f + n - 4, ".png") || strchr(f, '/'))
            return fail_json(file, path, "\"file\" must be a plain file name ending in .png");
        if (json_object_object_get_ex(c, "where", &v) && !json_object_is_type(v, json_type_object))
            return fail_json(file, path, "\"where\" must be an object {field: value}");
        if (json_object_object_get_ex(c, "series", &v) && !json_object_is_type(v, json_type_string))
            return fail_json(file, path, "\"series\" must be a field name");
        const char *texts[3] = {"title", "x_label", "y_label"}, *flags[2] = {"log_x", "log_y"};
        for (int k = 0; k < 3; k++)
            if (json_object_object_get_ex(c, texts[k], &v) &&
                !json_object_is_type(v, json_type_string))
                return fail_json(file, path,
                                 "\"title\", \"x_label\" and \"y_label\" must be strings");
        for (int k = 0; k < 2; k++)
            if (json_object_object_get_ex(c, flags[k], &v) &&
                !json_object_is_type(v, json_type_boolean))
                return fail_json(file, path, "\"log_x\" and \"log_y\" must be true or false");
    }
    return EXIT_OK;
}

static int load_study(study *st, const char *file, const char *out_dir, gi_plugins *reg)
{
    st->refs = calloc(MAX_REFS, sizeof *st->refs);
    if (!st->refs)
        return cli_fail(EXIT_RUN, "out of memory");
    st->root = read_strict_json(file);
    if (!st->root)
        return EXIT_USAGE;
    json_object *o = st->root, *v;
    if (!json_object_is_type(o, json_type_object))
        return fail_json(file, "/", "a study is a JSON object");
    static const char *known[] = {"name",    "description", "scenes",  "size",     "frames",
                                  "warmup",  "repeats",     "seed",    "camera",   "time",
                                  "animate", "cache",       "compare", "exposure", "timeout",
                                  "methods", "reference",   "charts",  "timer",    NULL};
    int rc = check_keys(o, known, "", file);
    if (rc != EXIT_OK)
        return rc;
    const char *desc;
    if ((rc = get_string(o, "", "name", 0, "study", &st->name, file)) ||
        (rc = get_string(o, "", "description", 0, NULL, &desc, file)) ||
        (rc = get_string(o, "", "camera", 1, NULL, &st->camera, file)))
        return rc;
    if (!json_object_object_get_ex(o, "scenes", &v))
        return fail_json(file, "/scenes", "a list of 1 to 16 scene files is required");
    run_settings *b = &st->base;
    b->width = b->height = 128;
    b->frames = 8;
    b->warmup = 1;
    b->repeats = 1;
    b->cache = 1;
    b->compare = 1;
    if ((rc = parse_settings(st, o, "", file, b)))
        return rc;
    if ((rc = get_uint(o, "", "seed", 0, 0x7FFFFFFF, 1, &st->seed, file)))
        return rc;
    double exposure;
    if ((rc = get_number(o, "", "exposure", -64.0, 64.0, 0.0, &exposure, file)) ||
        (rc = get_number(o, "", "timeout", 0.0, 1e6, 600.0, &st->timeout_s, file)))
        return rc;
    st->exposure = (float)exposure;
    if (!(st->timeout_s > 0))
        return fail_json(file, "/timeout", "must be a positive number of seconds");
    if (json_object_object_get_ex(o, "timer", &v)) {
        /* the stage timers of every run (GIBENCH_TIMER, inherited by the children) */
        const char *tv = json_object_get_string(v);
        if (!json_object_is_type(v, json_type_string) ||
            (strcmp(tv, "query") && strcmp(tv, "finish") && strcmp(tv, "cputime")))
            return fail_json(file, "/timer", "must be \"finish\", \"query\" or \"cputime\"");
        st->timer = tv;
    }
    if (json_object_object_get_ex(o, "charts", &v)) {
        if ((rc = check_charts(v, file)))
            return rc;
        st->charts = v;
    }

    json_object *ref;
    st->ref_spp = 256;
    st->ref_bounces = 64;
    if (json_object_object_get_ex(o, "reference", &ref)) {
        if (!json_object_is_type(ref, json_type_object))
            return fail_json(file, "/reference", "must be an object {\"spp\": ..., ...}");
        if ((rc = get_uint(ref, "/reference", "spp", 1, 1u << 24, 256, &st->ref_spp, file)) ||
            (rc = get_uint(ref, "/reference", "max_bounces", 0, 1024, 64, &st->ref_bounces, file)))
            return rc;
        json_object *cs, *tse, *px;
        static const char *ref_keys[] = {"spp",   "target_se", "max_bounces", "convergence_spp",
                                         "pixel", NULL};
        if ((rc = check_keys(ref, ref_keys, "/reference", file)))
            return rc;
        if (json_object_object_get_ex(ref, "pixel", &px)) {
            const char *pv = json_object_get_string(px);
            if (!json_object_is_type(px, json_type_string) ||
                (strcmp(pv, "box") && strcmp(pv, "center")))
                return fail_json(file, "/reference/pixel",
                                 "must be \"box\" (the pixel's average) or \"center\"");
            st->ref_pixel_center = !strcmp(pv, "center");
        }
        if (json_object_object_get_ex(ref, "target_se", &tse) &&
            !json_object_is_type(tse, json_type_null)) {
            st->ref_target_se = json_object_get_double(tse);
            if (!(st->ref_target_se > 0))
                return fail_json(file, "/reference/target_se",
                                 "must be a positive relative standard error");
        }
        if (json_object_object_get_ex(ref, "convergence_spp", &cs)) {
            if (!json_object_is_type(cs, json_type_array) || json_object_array_length(cs) > 32)
                return fail_json(file, "/reference/convergence_spp",
                                 "must be a list of at most 32 sample counts");
            for (size_t i = 0; i < json_object_array_length(cs); i++) {
                json_object *kj = json_object_array_get_idx(cs, i);
                int64_t k = json_object_get_int64(kj);
                if (!json_object_is_type(kj, json_type_int) || k < 1 || (uint64_t)k >= st->ref_spp)
                    return fail_json(file, "/reference/convergence_spp",
                                     "each count must be 1 .. spp-1");
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
            if ((rc = expand_method(st, file, out_dir, reg->items[i].method, NULL, "/methods", b)))
                return rc;
        name_refs(st);
        return EXIT_OK;
    }
    if (!json_object_is_type(v, json_type_array) || json_object_array_length(v) == 0)
        return fail_json(
            file, "/methods",
            "must be \"all\" or a non-empty list of {\"method\": id, \"params\": {...}}");
    static const char *entry_keys[] = {"method", "params",  "label",   "scenes", "size",
                                       "frames", "warmup",  "repeats", "time",   "animate",
                                       "cache",  "compare", NULL};
    for (size_t i = 0; i < json_object_array_length(v); i++) {
        json_object *e = json_object_array_get_idx(v, i), *id, *params = NULL;
        char mpath[64];
        snprintf(mpath, sizeof mpath, "/methods/%zu", i);
        if (!json_object_is_type(e, json_type_object) ||
            !json_object_object_get_ex(e, "method", &id))
            return fail_json(file, mpath, "needs \"method\"");
        if (!json_object_is_type(id, json_type_string))
            return fail_json(file, mpath, "\"method\" must be a method id (a string) or \"all\"");
        if ((rc = check_keys(e, entry_keys, mpath, file)))
            return rc;
        run_settings rs = *b;
        if ((rc = parse_settings(st, e, mpath, file, &rs)))
            return rc;
        json_object_object_get_ex(e, "params", &params);
        if (params && !json_object_is_type(params, json_type_object))
            return fail_json(file, mpath, "\"params\" must be an object");
        const char *mid = json_object_get_string(id);
        if (!strcmp(mid, "all")) {
            if (params)
                return fail_json(file, mpath,
                                 "\"all\" runs every method with its defaults: no \"params\"");
            for (uint32_t k = 0; k < reg->count; k++)
                if ((rc = expand_method(st, file, out_dir, reg->items[k].method, NULL, mpath, &rs)))
                    return rc;
            continue;
        }
        const gi_method *m = gi_plugins_find(reg, mid);
        if (!m) {
            char msg[256];
            snprintf(msg, sizeof msg, "no method '%s' is installed (see gibench methods)", mid);
            return fail_json(file, mpath, msg);
        }
        if ((rc = expand_method(st, file, out_dir, m, params, mpath, &rs)))
            return rc;
    }
    name_refs(st);
    return EXIT_OK;
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

/* The path tracer's convergence curve at one bounce limit: an image of
 * each convergence_spp count (another seed) against `reference`. The
 * full-GI images keep their old names (references made before per-bounce
 * curves are reused). */
static int pt_convergence(study *st, const char *out_dir, const study_ref *sc, const char *scene,
                          uint32_t bounces, const char *reference, tradeoff_pt_curve *curve,
                          char *why, size_t why_size)
{
    const char *px = st->ref_pixel_center ? "_center" : "";
    curve->n = 0;
    for (uint32_t c = 0; c < st->conv_n; c++) {
        char img[4096], stats[4200], b[32] = "";
        if (bounces != st->ref_bounces)
            snprintf(b, sizeof b, "b%u_", bounces);
        char stem[320];
        snprintf(stem, sizeof stem, "%s", sc->name);
        snprintf(img, sizeof img, "%s/references/%s_conv_%s%uspp%s.exr", out_dir, stem, b,
                 st->conv_spp[c], px);
        if (!runner_reference(scene, st->scenes[sc->scene_index].hash, st->camera, sc->width,
                              sc->height, st->conv_spp[c], 0.0, bounces, st->seed + 7919, sc->time,
                              st->ref_pixel_center, st->timeout_s, img, why, why_size))
            return 0;
        snprintf(stats, sizeof stats, "%s.json", img);
        json_object *sj = cli_read_json(stats);
        json_object *m = runner_diff(img, reference, NULL, NULL, st->exposure, why, why_size);
        /* the path tracer's time to the image, measured as the methods'
         * frames are: its render's CPU time (every thread) in studies timed
         * by CPU time, else its render's wall time (all threads); the BVH
         * build, like a method's prepare, is not in it. Images made before
         * the CPU time was recorded give their whole wall time. */
        double t = rec_num(sj,
                           st->timer && !strcmp(st->timer, "cputime") ? "render_cpu_seconds"
                                                                      : "render_seconds",
                           NULL, NULL);
        if (!isfinite(t))
            t = rec_num(sj, "wall_seconds", NULL, NULL);
        double e = rec_num(m, "relmse", NULL, NULL);
        if (isfinite(t) && isfinite(e) && t > 0 && e > 0 && curve->n < TRADEOFF_PT_POINTS) {
            curve->t[curve->n] = t;
            curve->e[curve->n] = e;
            curve->n++;
        }
        json_object_put(sj);
        json_object_put(m);
    }
    return 1;
}

/* Whether run r compares with reference set ri (its final image, or one of its frames). */
static int run_uses_ref(const study_run *r, uint32_t ri)
{
    if (r->ref_index == (int)ri)
        return 1;
    for (uint32_t f = 0; f < r->frame_ref_n; f++)
        if (r->frame_ref[f] == (int)ri)
            return 1;
    return 0;
}

/* One reference set: the full-GI reference, the bounce-matched ones for
 * every method bounce count in use and, with `curves`, the path tracer's
 * convergence images. 1 when all exist (made now or before), else 0 with why. */
static int build_reference_set(study *st, const char *out_dir, uint32_t ri, int curves, char *why,
                               size_t why_size)
{
    study_ref *sc = &st->refs[ri];
    const char *path = st->scenes[sc->scene_index].path;
    char dir[2048], stem[320];
    snprintf(stem, sizeof stem, "%s",
             sc->name); /* a copy: -Wrestrict sees sc->name and the outputs as one object */
    snprintf(dir, sizeof dir, "%s/references", out_dir);
    cli_mkdirs(dir);
    /* the file name carries every setting that changes the image, so that
     * runs compared with an older reference are not taken as done */
    const char *px = st->ref_pixel_center ? "_center" : "";
    snprintf(sc->ref_full, sizeof sc->ref_full, "%s/%s_b%u_%uspp%s.exr", dir, stem, st->ref_bounces,
             st->ref_spp, px);
    fprintf(stderr, "study: reference %s (%ux%u, %u spp, %u bounces)\n", stem, sc->width,
            sc->height, st->ref_spp, st->ref_bounces);
    if (!runner_reference(path, st->scenes[sc->scene_index].hash, st->camera, sc->width, sc->height,
                          st->ref_spp, st->ref_target_se, st->ref_bounces, st->seed, sc->time,
                          st->ref_pixel_center, st->timeout_s * 10, sc->ref_full, why, why_size))
        return 0;
    /* the noise floor of an animation frame: the same reference with another seed */
    if (sc->want_alt) {
        snprintf(sc->ref_alt, sizeof sc->ref_alt, "%s/%s_b%u_%uspp%s_alt.exr", dir, stem,
                 st->ref_bounces, st->ref_spp, px);
        fprintf(stderr, "study: reference %s, second seed (noise floor)\n", stem);
        if (!runner_reference(path, st->scenes[sc->scene_index].hash, st->camera, sc->width,
                              sc->height, st->ref_spp, st->ref_target_se, st->ref_bounces,
                              st->seed + 1000003u, sc->time, st->ref_pixel_center,
                              st->timeout_s * 10, sc->ref_alt, why, why_size))
            return 0;
    }
    /* bounce-matched references for every method bounce count in use */
    for (uint32_t r = 0; r < st->run_count; r++) {
        if (!run_uses_ref(&st->runs[r], ri) || st->runs[r].bounces >= st->ref_bounces)
            continue;
        uint32_t b = st->runs[r].bounces, k = 0;
        while (k < sc->matched_count && sc->matched_bounces[k] != b)
            k++;
        if (k == sc->matched_count && k < 8) {
            sc->matched_bounces[k] = b;
            snprintf(sc->ref_matched[k], sizeof sc->ref_matched[k], "%s/%s_b%u_%uspp%s.exr", dir,
                     stem, b, st->ref_spp, px);
            fprintf(stderr, "study: bounce-matched reference %s (%u bounces)\n", stem, b);
            if (!runner_reference(path, st->scenes[sc->scene_index].hash, st->camera, sc->width,
                                  sc->height, st->ref_spp, st->ref_target_se, b, st->seed, sc->time,
                                  st->ref_pixel_center, st->timeout_s * 10, sc->ref_matched[k], why,
                                  why_size))
                return 0;
            sc->matched_count++;
        }
    }
    if (!curves || sc->frame_only)
        return 1;
    /* the path tracer's convergence, for full GI and for each bounce
     * count in use: k-spp images (another seed) against the reference
     * of the same bounce count */
    sc->pt_full.bounces = st->ref_bounces;
    if (!pt_convergence(st, out_dir, sc, path, st->ref_bounces, sc->ref_full, &sc->pt_full, why,
                        why_size))
        return 0;
    for (uint32_t k = 0; k < sc->matched_count; k++) {
        sc->pt_matched[k].bounces = sc->matched_bounces[k];
        if (!pt_convergence(st, out_dir, sc, path, sc->matched_bounces[k], sc->ref_matched[k],
                            &sc->pt_matched[k], why, why_size))
            return 0;
    }
    return 1;
}

/* gibench study --slurm-collect: a missing reference set is reported with
 * its runs, not fatal (slurm_mark_missing_refs) */
static const slurm_options *slurm_collecting;
static void slurm_mark_missing_ref(study *st, uint32_t ri, const char *why);

static int build_references(study *st, const char *out_dir)
{
    char why[1024];
    for (uint32_t ri = 0; ri < st->ref_count; ri++) {
        if (build_reference_set(st, out_dir, ri, 1, why, sizeof why))
            continue;
        if (!slurm_collecting)
            return cli_fail(EXIT_RUN, "study: %s", why);
        slurm_mark_missing_ref(st, ri, why);
    }
    return EXIT_OK;
}

static void attach_refs(study *st, study_run *r)
{
    r->spec.ref_full = r->spec.ref_matched = NULL;
    if (r->ref_index < 0)
        return;
    study_ref *sc = &st->refs[r->ref_index];
    r->spec.ref_full = sc->ref_full;
    r->spec.ref_matched = sc->ref_full;
    for (uint32_t k = 0; k < sc->matched_count; k++)
        if (sc->matched_bounces[k] == r->bounces)
            r->spec.ref_matched = sc->ref_matched[k];
    for (uint32_t f = 0; f < r->frame_ref_n; f++) {
        const study_ref *fr = &st->refs[r->frame_ref[f]];
        r->fr_full[f] = fr->ref_full;
        r->fr_matched[f] = fr->ref_full;
        for (uint32_t k = 0; k < fr->matched_count; k++)
            if (fr->matched_bounces[k] == r->bounces)
                r->fr_matched[f] = fr->ref_matched[k];
        r->fr_alt[f] = fr->ref_alt[0] ? fr->ref_alt : NULL;
    }
    r->spec.frame_ref_count = r->frame_ref_n;
    r->spec.frame_ref_full = r->fr_full;
    r->spec.frame_ref_matched = r->fr_matched;
    r->spec.frame_ref_alt = r->fr_alt;
}

/* A record for a run, or "n/a" when the method's caps do not cover its scene. */
static json_object *run_or_skip(study_run *r, gi_plugins *reg, int resume)
{
    gi_error err;
    gi_scene *s = gi_scene_load(r->spec.scene, &err);
    char why[256];
    const gi_method *m = gi_plugins_find(reg, r->spec.method);
    json_object *rec;
    if (s && m && !cli_caps_cover(m, s, r->spec.animate_fps > 0, why, sizeof why))
        rec = runner_not_applicable(&r->spec, why);
    else
        rec = runner_execute(&r->spec, resume);
    gi_scene_free(s);
    return rec;
}

/* Progress of one worker's share of the runs: one line per run, saying
 * whether it ran or came from a earlier result, with elapsed time and an
 * ETA from the runs executed so far. */
typedef struct run_progress {
    double start, ran_seconds;
    uint32_t ran, left;
} run_progress;

static void report_run(run_progress *p, const study *st, uint32_t i, json_object *rec,
                       double seconds, const char *who)
{
    json_object *v;
    const char *status =
        json_object_object_get_ex(rec, "status", &v) ? json_object_get_string(v) : "?";
    int cached = json_object_object_get_ex(rec, "cached", &v) && json_object_get_boolean(v);
    json_object_object_del(rec, "cached"); /* what the runner told us, not part of the record */
    const char *what = !strcmp(status, "ok") ? (cached ? "cached" : "ran") : status;
    if (!strcmp(what, "ran") || !strcmp(what, "failed")) {
        p->ran++;
        p->ran_seconds += seconds;
    }
    if (p->left)
        p->left--;
    char el[32], eta[32] = "?";
    cli_format_duration(gi_now() - p->start, el, sizeof el);
    if (p->ran)
        cli_format_duration(p->ran_seconds / p->ran * p->left, eta, sizeof eta);
    const run_spec *s = &st->runs[i].spec;
    char params[256] = "";
    for (uint32_t k = 0; k < s->param_count; k++) {
        size_t used = strlen(params);
        snprintf(params + used, sizeof params - used, "%s%s", k ? "," : " ", s->params[k]);
    }
    fprintf(stderr, "study: %s[%u/%u] %s %s (%s%s) %.1f s; elapsed %s, ETA %s\n", who, i + 1,
            st->run_count, what, st->runs[i].id, s->method, params, seconds, el,
            p->left ? eta : "0:00");
}

/* Runs every run not yet done: `jobs` worker processes, each taking runs
 * i, i+jobs, ...; results land in each run's result.json. */
static void execute_runs(study *st, uint32_t jobs, int fresh, gi_plugins *reg)
{
    for (uint32_t i = 0; i < st->run_count; i++)
        attach_refs(st, &st->runs[i]);
    if (jobs <= 1) {
        /* once interrupted, the runs left are not started: they are
         * reported as interrupted (or as done, when a result is cached) */
        run_progress p = {gi_now(), 0, 0, st->run_count};
        for (uint32_t i = 0; i < st->run_count; i++) {
            double t0 = gi_now();
            st->runs[i].record = run_or_skip(&st->runs[i], reg, !fresh || cli_interrupted);
            if (!cli_interrupted)
                report_run(&p, st, i, st->runs[i].record, gi_now() - t0, "");
            else
                json_object_object_del(st->runs[i].record, "cached");
        }
        return;
    }
    pid_t *pids = calloc(jobs, sizeof *pids);
    for (uint32_t j = 0; j < jobs && pids; j++) {
        pid_t pid = fork();
        if (pid == 0) {
            run_progress p = {gi_now(), 0, 0, (st->run_count - j + jobs - 1) / jobs};
            char who[32];
            snprintf(who, sizeof who, "worker %u ", j);
            for (uint32_t i = j; i < st->run_count && !cli_interrupted; i += jobs) {
                double t0 = gi_now();
                json_object *rec = run_or_skip(&st->runs[i], reg, !fresh);
                if (!cli_interrupted)
                    report_run(&p, st, i, rec, gi_now() - t0, who);
                json_object_put(rec);
            }
            _exit(0);
        }
        pids[j] = pid;
    }
    /* An interrupted study passes SIGTERM on to its workers (a SIGTERM sent
     * to the study alone does not reach them), which stop their runs'
     * process groups (cli_run) and start no more. */
    int forwarded = 0;
    for (uint32_t j = 0; j < jobs && pids; j++) {
        while (pids[j] > 0 && waitpid(pids[j], NULL, 0) < 0 && errno == EINTR) {
            if (cli_interrupted && !forwarded) {
                for (uint32_t k = 0; k < jobs; k++)
                    if (pids[k] > 0)
                        kill(pids[k], SIGTERM);
                forwarded = 1;
            }
        }
    }
    free(pids);
    /* collect: every worker wrote result.json; resume picks them up */
    for (uint32_t i = 0; i < st->run_count; i++) {
        st->runs[i].record = run_or_skip(&st->runs[i], reg, 1);
        json_object_object_del(st->runs[i].record, "cached");
    }
}

/* The path of a reference relative to the output directory (they all lie in references/). */
static json_object *ref_rel(const char *path)
{
    const char *base = strrchr(path, '/');
    char rel[4200];
    snprintf(rel, sizeof rel, "references/%s", base ? base + 1 : path);
    return json_object_new_string(rel);
}

/* For the report's image viewer: per reference set, its full-GI and
 * bounce-matched references and the runs compared with them (report.h). */
static void reference_sets(study *st, json_object *meta)
{
    json_object *sets = json_object_new_array();
    for (uint32_t ri = 0; ri < st->ref_count; ri++) {
        study_ref *sc = &st->refs[ri];
        /* the references of an animation's inner frames hold no run's final
         * image: no viewer for them (the table and charts report them) */
        int holds_runs = 0;
        for (uint32_t i = 0; i < st->run_count; i++)
            holds_runs |= st->runs[i].ref_index == (int)ri;
        if (sc->frame_only && !holds_runs)
            continue;
        json_object *set = json_object_new_object(), *matched = json_object_new_array(),
                    *ids = json_object_new_array();
        json_object_object_add(set, "name", json_object_new_string(sc->name));
        json_object_object_add(set, "full", ref_rel(sc->ref_full));
        json_object_object_add(set, "bounces", json_object_new_int((int)st->ref_bounces));
        for (uint32_t k = 0; k < sc->matched_count; k++) {
            json_object *m = json_object_new_object();
            json_object_object_add(m, "image", ref_rel(sc->ref_matched[k]));
            json_object_object_add(m, "bounces", json_object_new_int((int)sc->matched_bounces[k]));
            json_object_array_add(matched, m);
        }
        json_object_object_add(set, "matched", matched);
        for (uint32_t i = 0; i < st->run_count; i++)
            if (st->runs[i].ref_index == (int)ri)
                json_object_array_add(ids, json_object_new_string(st->runs[i].id));
        json_object_object_add(set, "runs", ids);
        json_object_array_add(sets, set);
    }
    json_object_object_add(meta, "references", sets);
    json_object_object_add(meta, "exposure", json_object_new_double(st->exposure));
}

/* Per reference set: the error-against-time charts with every run's
 * convergence curve, the Pareto fronts and the path tracer's curves, and
 * the equal-error and equal-time tables (tradeoff.h). */
static void charts_and_speedups(study *st, const char *out_dir, json_object *meta,
                                json_object *chart_list)
{
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
                        gi_chart_write_png, chart_list, &md);
    }
    free(tr);
    json_object_object_add(meta, "markdown", json_object_new_string(md.s ? md.s : ""));
    free(md.s);
}

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

/* Animated runs compared frame by frame (README.md, "Animated runs"): a
 * table of every such run (markdown, into meta "animation_markdown") and,
 * per scene, charts of relMSE, frame time and frame-to-frame change
 * against the frame index, one series per run. */
static void animation_report(study *st, const char *out_dir, json_object *meta,
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
    gi_text_put(
        &md,
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
        &md,
        "| run | method | params | label | frames | fps | frame ms (median) | relMSE full mean | "
        "relMSE full max | relMSE matched mean | leaked energy | change method | change reference "
        "| flicker full | flicker matched | temporal error | noise floor |\n"
        "|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for (uint32_t i = 0; i < st->run_count; i++) {
        study_run *r = &st->runs[i];
        json_object *v;
        if (!r->frame_ref_n || !r->record)
            continue;
        const char *status =
            json_object_object_get_ex(r->record, "status", &v) ? json_object_get_string(v) : "?";
        char params[600] = "";
        for (uint32_t k = 0; k < r->spec.param_count; k++) {
            size_t used = strlen(params);
            snprintf(params + used, sizeof params - used, "%s%s", k ? "," : "", r->spec.params[k]);
        }
        gi_text_put(&md, "| %s | %s | `%s` | %s |", r->id, r->spec.method,
                    params[0] ? params : "(defaults)", r->spec.label ? r->spec.label : "");
        if (strcmp(status, "ok")) {
            const char *reason =
                json_object_object_get_ex(r->record, "reason", &v) ? json_object_get_string(v) : "";
            gi_text_put(&md, " %s: %s | | | | | | | | | | | | |\n", status, reason);
            continue;
        }
        gi_text_put(&md, " %u | %g |", r->frame_ref_n, (double)r->spec.animate_fps);
        const char *keys[] = {"frame_ms_median",         "relmse_full_mean",
                              "relmse_full_max",         "relmse_matched_mean",
                              "leaked_energy_full_mean", "change_method_mean",
                              "change_ref_full_mean",    "flicker_full",
                              "flicker_matched",         "temporal_error_full_mean",
                              "noise_floor_full_mean"};
        for (size_t k = 0; k < sizeof keys / sizeof keys[0]; k++)
            md_cell(&md, anim_num(r->record, keys[k]));
        gi_text_put(&md, "\n");
    }
    gi_text_put(&md, "\n");
    json_object_object_add(meta, "animation_markdown", json_object_new_string(md.s ? md.s : ""));
    free(md.s);

    /* charts, per scene */
    for (uint32_t sc = 0; sc < st->scene_count; sc++) {
        const char *what[3] = {"relmse", "frame_ms", "change"};
        const char *ylab[3] = {"relMSE against the full-GI reference of the frame",
                               "frame time (ms; update + render)",
                               "mean |frame - previous frame| (linear, per pixel and channel)"};
        for (int c = 0; c < 3; c++) {
            anim_series ser[32];
            gi_chart_series cs[32];
            uint32_t n = 0;
            double seen_fps[16];
            uint32_t nseen = 0;
            for (uint32_t i = 0; i < st->run_count && n < 30; i++) {
                study_run *r = &st->runs[i];
                json_object *v;
                if (!r->frame_ref_n || !r->record || r->scene_index != (int)sc ||
                    !json_object_object_get_ex(r->record, "status", &v) ||
                    strcmp(json_object_get_string(v), "ok"))
                    continue;
                char label[200];
                size_t used = (size_t)snprintf(label, sizeof label, "%s", r->spec.method);
                for (uint32_t k = 0; k < r->spec.param_count && used < sizeof label; k++)
                    used += (size_t)snprintf(label + used, sizeof label - used, " %s",
                                             r->spec.params[k]);
                if (r->spec.label && used < sizeof label)
                    snprintf(label + used, sizeof label - used, " [%s]", r->spec.label);
                const char *key = c == 0 ? "relmse_full" : c == 1 ? "frame_ms" : "change_method";
                if (anim_series_from(r->record, key, label, &ser[n])) {
                    cs[n] = (gi_chart_series){
                        ser[n].label, ser[n].x, ser[n].y, ser[n].n, GI_CHART_LINE_MARKERS, 0,
                        NULL,         NULL,     NULL,     NULL};
                    n++;
                }
                /* the references' own change and noise floor, once per frame rate */
                uint32_t q = 0;
                while (q < nseen && seen_fps[q] != r->spec.animate_fps)
                    q++;
                if (c == 2 && q == nseen && nseen < 16 && n < 30) {
                    seen_fps[nseen++] = r->spec.animate_fps;
                    char l2[200];
                    snprintf(l2, sizeof l2, "reference change (%g fps)",
                             (double)r->spec.animate_fps);
                    if (anim_series_from(r->record, "change_ref_full", l2, &ser[n])) {
                        cs[n] = (gi_chart_series){
                            ser[n].label, ser[n].x, ser[n].y, ser[n].n, GI_CHART_DASHED, 0,
                            NULL,         NULL,     NULL,     NULL};
                        n++;
                    }
                    snprintf(l2, sizeof l2, "reference noise floor, two seeds (%g fps)",
                             (double)r->spec.animate_fps);
                    if (anim_series_from(r->record, "noise_floor_full", l2, &ser[n])) {
                        cs[n] = (gi_chart_series){
                            ser[n].label, ser[n].x, ser[n].y, ser[n].n, GI_CHART_DASHED, 0,
                            NULL,         NULL,     NULL,     NULL};
                        n++;
                    }
                }
            }
            if (n) {
                char file[512], path[4700], title[512];
                snprintf(file, sizeof file, "chart_%s_anim_%s.png", st->scenes[sc].stem, what[c]);
                snprintf(path, sizeof path, "%s/%s", out_dir, file);
                snprintf(title, sizeof title, "%s, animated: %s per frame", st->scenes[sc].stem,
                         c == 0   ? "relMSE"
                         : c == 1 ? "frame time"
                                  : "frame-to-frame change");
                gi_chart_desc desc = {title, "frame index (from 0)", ylab[c], 0, c == 0, 0, 0, NULL,
                                      0};
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
    }
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

/* The study's own charts ("charts" in the study file): y against x over the
 * finished runs that match "where", one series per value of "series". A y
 * that is a list (e.g. frame_samples_ms) gives one series per run, against
 * its position in the list. */
static void user_charts(study *st, const char *out_dir, json_object *runs, json_object *chart_list)
{
    if (!st->charts)
        return;
    size_t nr = json_object_array_length(runs);
    /* runs timed under different GL renderers (cluster nodes) never share a
     * series: their label names the renderer */
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
    for (size_t ci = 0; ci < json_object_array_length(st->charts); ci++) {
        json_object *c = json_object_array_get_idx(st->charts, ci), *v, *where = NULL;
        const char *file = json_object_get_string(json_object_object_get(c, "file"));
        const char *xf = json_object_get_string(json_object_object_get(c, "x"));
        const char *yf = json_object_get_string(json_object_object_get(c, "y"));
        const char *sf =
            json_object_object_get_ex(c, "series", &v) ? json_object_get_string(v) : NULL;
        json_object_object_get_ex(c, "where", &where);
        char *labels[32] = {0};
        double *pts[32] = {0}; /* (x, y) pairs */
        uint32_t counts[32] = {0}, ns = 0;
        int listed[32] = {0}; /* series drawn from a list field */
        for (size_t i = 0; i < nr; i++) {
            json_object *rec = json_object_array_get_idx(runs, i);
            if (!json_object_object_get_ex(rec, "status", &v) ||
                strcmp(json_object_get_string(v), "ok"))
                continue;
            int match = 1;
            if (where) {
                json_object_object_foreach(where, k, want) match &= field_equals(rec, k, want);
            }
            if (!match)
                continue;
            json_object *y = record_field(rec, yf);
            int is_list = y && json_object_is_type(y, json_type_array);
            char label[256];
            if (is_list && !sf)
                snprintf(label, sizeof label, "%s",
                         json_object_get_string(json_object_object_get(rec, "run")));
            else if (sf) {
                json_object *s = record_field(rec, sf);
                const char *leaf = strrchr(sf, '.') ? strrchr(sf, '.') + 1 : sf;
                snprintf(label, sizeof label, "%s=%s", leaf, s ? json_object_get_string(s) : "?");
                json_object_put(s);
            } else
                snprintf(label, sizeof label, "%s", yf);
            json_object *rn;
            if (mixed && json_object_object_get_ex(rec, "renderer", &rn)) {
                size_t used = strlen(label);
                snprintf(label + used, sizeof label - used, " [%s]", json_object_get_string(rn));
            }
            uint32_t k = 0;
            while (k < ns && strcmp(labels[k], label))
                k++;
            if (k == ns) {
                if (ns == 32) {
                    json_object_put(y);
                    continue;
                }
                labels[ns] = strdup(label);
                pts[ns] = calloc((size_t)2 * MAX_RUNS, sizeof(double));
                ns++;
            }
            if (is_list) {
                listed[k] = 1;
                for (size_t j = 0;
                     j < json_object_array_length(y) && counts[k] < MAX_RUNS && pts[k]; j++) {
                    if (!json_object_array_get_idx(y, j))
                        continue; /* null: no value at this position (a warm-up frame, frame 0's
                                     change) */
                    pts[k][2 * counts[k]] = (double)(j + 1);
                    pts[k][2 * counts[k] + 1] =
                        json_object_get_double(json_object_array_get_idx(y, j));
                    counts[k]++;
                }
            } else if (pts[k] && counts[k] < MAX_RUNS) {
                json_object *x = record_field(rec, xf);
                pts[k][2 * counts[k]] = field_num(x);
                pts[k][2 * counts[k] + 1] = field_num(y);
                counts[k]++;
                json_object_put(x);
            }
            json_object_put(y);
        }
        /* Runs of one series at the same x (repeats, or settings the
         * chart does not tell apart) become one point: the median y, with
         * the min-max spread as an error bar. Series drawn from a list
         * (one run each) keep their points. */
        gi_chart_series series[32];
        double *xy[32][4] = {{0}};
        double ticks[13];
        uint32_t tick_n = 0;
        int any_list = 0;
        for (uint32_t k = 0; k < ns; k++) {
            if (pts[k])
                qsort(pts[k], counts[k], 2 * sizeof(double), cmp_point);
            for (int a = 0; a < 4; a++)
                xy[k][a] = malloc((counts[k] + 1) * sizeof(double));
            uint32_t m = 0;
            int spread = 0;
            for (uint32_t j = 0; j < counts[k] && xy[k][0] && xy[k][1] && xy[k][2] && xy[k][3];) {
                uint32_t e = j + 1;
                while (!listed[k] && e < counts[k] && pts[k][2 * e] == pts[k][2 * j])
                    e++;
                double ys[MAX_RUNS];
                for (uint32_t q = j; q < e; q++)
                    ys[q - j] = pts[k][2 * q + 1];
                qsort(ys, e - j, sizeof(double), cmp_double_asc);
                uint32_t cnt = e - j;
                xy[k][0][m] = pts[k][2 * j];
                xy[k][1][m] = cnt % 2 ? ys[cnt / 2] : 0.5 * (ys[cnt / 2 - 1] + ys[cnt / 2]);
                xy[k][2][m] = ys[0];
                xy[k][3][m] = ys[cnt - 1];
                spread |= cnt > 1 && ys[cnt - 1] > ys[0];
                m++;
                j = e;
            }
            any_list |= listed[k];
            /* the distinct x values of every series: ticks at the swept values */
            for (uint32_t j = 0; j < m && tick_n <= 12; j++) {
                uint32_t t = 0;
                while (t < tick_n && ticks[t] != xy[k][0][j])
                    t++;
                if (t == tick_n && isfinite(xy[k][0][j]))
                    ticks[tick_n++] = xy[k][0][j];
            }
            series[k] = (gi_chart_series){labels[k],
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
        const char *title =
            json_object_object_get_ex(c, "title", &v) ? json_object_get_string(v) : file;
        const char *xl =
            json_object_object_get_ex(c, "x_label", &v) ? json_object_get_string(v) : xf;
        const char *yl =
            json_object_object_get_ex(c, "y_label", &v) ? json_object_get_string(v) : yf;
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
        snprintf(path, sizeof path, "%s/%s", out_dir, file);
        gi_error err;
        if (ns == 0)
            fprintf(stderr, "gibench: warning: chart %s: no finished run matches\n", file);
        else if (gi_chart_write_png(path, &desc, series, ns, &err) == GI_OK)
            json_object_array_add(chart_list, json_object_new_string(file));
        else
            fprintf(stderr, "gibench: warning: chart %s not written: %s\n", file, err.text);
        for (uint32_t k = 0; k < ns; k++) {
            free(labels[k]);
            free(pts[k]);
            for (int a = 0; a < 4; a++)
                free(xy[k][a]);
        }
    }
}

/* --dry-run: what the study would do, without doing it. */
static void print_plan(const study *st)
{
    printf("study %s: %u runs, %u scenes, %u reference sets\n", st->name, st->run_count,
           st->scene_count, st->ref_count);
    for (uint32_t i = 0; i < st->ref_count; i++)
        printf("reference %s: %s %ux%u time %g\n", st->refs[i].name,
               st->scenes[st->refs[i].scene_index].path, st->refs[i].width, st->refs[i].height,
               (double)st->refs[i].time);
    for (uint32_t i = 0; i < st->run_count; i++) {
        const study_run *r = &st->runs[i];
        const run_spec *s = &r->spec;
        printf("run %s: %s %s %ux%u frames %u warmup %u%s%s%s%s", r->id, s->scene, s->method,
               s->width, s->height, s->frames, s->warmup, s->animate_fps > 0 ? " animate" : "",
               s->no_cache ? " no-cache" : "",
               r->ref_index < 0 ? " not-compared"
               : r->frame_ref_n ? " per-frame"
                                : "",
               s->label ? " label=" : "");
        if (s->label)
            printf("%s", s->label);
        for (uint32_t k = 0; k < s->param_count; k++)
            printf(" %s", s->params[k]);
        printf("\n");
    }
}

static void study_free(study *st)
{
    for (uint32_t i = 0; st->runs && i < st->run_count; i++) {
        json_object_put(st->runs[i].record);
        for (int k = 0; k < MAX_KEYS; k++)
            free(st->runs[i].params[k]);
        free(st->runs[i].frame_ref);
        free(st->runs[i].fr_full);
        free(st->runs[i].fr_matched);
        free(st->runs[i].fr_alt);
    }
    free(st->runs);
    free(st->refs);
    json_object_put(st->root);
    memset(st, 0, sizeof *st);
}

int study_check(const char *file, gi_plugins *reg)
{
    study *st = calloc(1, sizeof *st); /* over a megabyte: not on the stack */
    if (!st)
        return cli_fail(EXIT_RUN, "study: out of memory");
    int rc = load_study(st, file, ".", reg);
    study_free(st);
    free(st);
    return rc;
}

/* One study at a time per --out: an exclusive flock() on DIR/.gibench-study.lock,
 * taken before anything (references included) is built and held until the
 * study exits; the kernel releases it when the process dies, crashed or not.
 * The file holds the holder's pid and is left in place (unlinking it would
 * let a third study lock a new file while a second waits on the old one).
 * The descriptor is close-on-exec, so runs started by the study do not hold
 * it. Returns the descriptor, or -1 after printing why (*rc set). */
static int lock_out_dir(const char *out, int *rc)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/.gibench-study.lock", out);
    int fd = open(path, O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0644);
    if (fd < 0) {
        *rc = cli_fail(EXIT_RUN, "study: cannot open the lock %s: %s", path, strerror(errno));
        return -1;
    }
    while (flock(fd, LOCK_EX | LOCK_NB) != 0) {
        if (errno == EINTR)
            continue;
        if (errno == EWOULDBLOCK) {
            char pid[32] = "";
            ssize_t n = pread(fd, pid, sizeof pid - 1, 0);
            pid[n > 0 ? n : 0] = '\0';
            pid[strcspn(pid, "\n")] = '\0';
            *rc = cli_fail(EXIT_USAGE, "study: %s is in use by another study (pid %s holds %s)",
                           out, pid[0] ? pid : "unknown", path);
        } else {
            *rc = cli_fail(EXIT_RUN, "study: cannot lock %s: %s", path, strerror(errno));
        }
        close(fd);
        return -1;
    }
    char pid[32];
    int len = snprintf(pid, sizeof pid, "%ld\n", (long)getpid());
    if (ftruncate(fd, 0) != 0 || pwrite(fd, pid, (size_t)len, 0) != len) {
        *rc = cli_fail(EXIT_RUN, "study: cannot write the lock %s: %s", path, strerror(errno));
        close(fd);
        return -1;
    }
    return fd;
}

/* ---- gibench study --slurm (slurm.h): the same cells as Slurm array tasks ---- */

static void slurm_mark_missing_ref(study *st, uint32_t ri, const char *why)
{
    snprintf(st->refs[ri].missing, sizeof st->refs[ri].missing, "%s", why);
}

/* What the planned cells are: a task refuses to run a study that has
 * changed since it was submitted (its index would name another cell). */
static uint64_t slurm_plan_hash(const study *st)
{
    uint64_t h = gi_hash64(st->name, strlen(st->name), st->run_count * 131u + st->ref_count);
    for (uint32_t i = 0; i < st->ref_count; i++)
        h = gi_hash64(st->refs[i].name, strlen(st->refs[i].name), h);
    for (uint32_t i = 0; i < st->run_count; i++)
        h = gi_hash64(st->runs[i].id, strlen(st->runs[i].id), h);
    return h;
}

/* --cell KIND:K:PLAN: one array task. "ref": reference set K, as the local
 * runner builds it; "run": run K, after checking that its references exist,
 * exactly as the local runner runs it (runner_execute, resuming). Exit 0
 * when the cell is done (or not applicable), 1 when it failed. */
static int slurm_cell(study *st, const char *out, gi_plugins *reg, const char *cell)
{
    char kind[8];
    unsigned long k;
    unsigned long long plan;
    if (sscanf(cell, "%7[a-z]:%lu:%llx", kind, &k, &plan) != 3 ||
        (strcmp(kind, "ref") && strcmp(kind, "run")))
        return cli_fail(EXIT_USAGE, "study: --cell '%s' is not ref:K:PLAN or run:K:PLAN", cell);
    if (plan != slurm_plan_hash(st))
        return cli_fail(EXIT_USAGE,
                        "study: the study's plan changed since it was submitted: resubmit it");
    uint32_t n = !strcmp(kind, "ref") ? st->ref_count : st->run_count;
    if (k >= n)
        return cli_fail(EXIT_USAGE, "study: --cell %s: the study has %u such cells", cell, n);
    char why[1024];
    if (!strcmp(kind, "ref")) {
        if (!build_reference_set(st, out, (uint32_t)k, 1, why, sizeof why))
            return cli_fail(EXIT_RUN, "study: %s", why);
        fprintf(stderr, "study: reference set %s done\n", st->refs[k].name);
        return EXIT_OK;
    }
    study_run *r = &st->runs[k];
    if (r->ref_index >= 0) {
        runner_set_collect_only(1); /* the references stage made them */
        int ok = build_reference_set(st, out, (uint32_t)r->ref_index, 0, why, sizeof why);
        runner_set_collect_only(0);
        if (!ok)
            return cli_fail(EXIT_RUN, "study: run %s: %s", r->id, why);
    }
    attach_refs(st, r);
    double t0 = gi_now();
    r->record = run_or_skip(r, reg, 1);
    json_object *v;
    const char *status =
        json_object_object_get_ex(r->record, "status", &v) ? json_object_get_string(v) : "?";
    int cached = json_object_object_get_ex(r->record, "cached", &v) && json_object_get_boolean(v);
    const char *reason =
        json_object_object_get_ex(r->record, "reason", &v) ? json_object_get_string(v) : "";
    fprintf(stderr, "study: run %s: %s%s%s%s (%.1f s)\n", r->id, status, cached ? " (cached)" : "",
            reason[0] ? ": " : "", reason, gi_now() - t0);
    return !strcmp(status, "ok") || !strcmp(status, "n/a") ? EXIT_OK : EXIT_RUN;
}

/* --slurm: plans the cells as the local runner does, leaves out those
 * already done (resume), and hands the rest to Slurm (slurm_run). */
static int slurm_submit_study(study *st, const char *file, const char *out, gi_plugins *reg,
                              const slurm_options *so)
{
    uint32_t *ref_tasks = calloc(st->ref_count + 1, sizeof *ref_tasks);
    uint32_t *run_tasks = calloc(st->run_count + 1, sizeof *run_tasks);
    if (!ref_tasks || !run_tasks) {
        free(ref_tasks);
        free(run_tasks);
        return cli_fail(EXIT_RUN, "study: out of memory");
    }
    uint32_t nref = 0, nrun = 0, cached = 0, na = 0;
    char why[1024];
    runner_set_collect_only(1);
    for (uint32_t i = 0; i < st->ref_count; i++)
        if (!build_reference_set(st, out, i, 0, why, sizeof why))
            ref_tasks[nref++] = i;
    for (uint32_t i = 0; i < st->run_count; i++) {
        study_run *r = &st->runs[i];
        attach_refs(st, r);
        json_object *rec = run_or_skip(r, reg, 1), *v;
        const char *status =
            json_object_object_get_ex(rec, "status", &v) ? json_object_get_string(v) : "";
        if (json_object_object_get_ex(rec, "cached", &v))
            cached++;
        else if (!strcmp(status, "n/a"))
            na++;
        else
            run_tasks[nrun++] = i;
        json_object_put(rec);
    }
    runner_set_collect_only(0);
    fprintf(stderr,
            "study: %s: %u reference sets (%u to make), %u runs (%u done before, %u not "
            "applicable, %u to run)\n",
            st->name, st->ref_count, nref, st->run_count, cached, na, nrun);
    slurm_stage refs = {"ref", ref_tasks, nref}, runs = {"run", run_tasks, nrun};
    int rc = slurm_run(so, file, out, st->name, slurm_plan_hash(st), &refs, &runs);
    free(ref_tasks);
    free(run_tasks);
    return rc;
}

/* --slurm-collect REFJOB,RUNJOB: the records of every run from the cells'
 * results, running nothing; a cell without a result is a failed run whose
 * reason is how its Slurm task ended. */
static void slurm_collect_runs(study *st, gi_plugins *reg, const char *out, const char *jobs)
{
    char ref_job[64] = "-", run_job[64] = "-";
    sscanf(jobs, "%63[^,],%63s", ref_job, run_job);
    slurm_tasks *rt = slurm_tasks_query(out, "ref", ref_job),
                *mt = slurm_tasks_query(out, "run", run_job);
    runner_set_collect_only(1);
    for (uint32_t i = 0; i < st->run_count; i++) {
        study_run *r = &st->runs[i];
        attach_refs(st, r);
        json_object *rec = run_or_skip(r, reg, 1), *v;
        if (json_object_object_get_ex(rec, "cached", &v)) {
            json_object_object_del(rec, "cached");
        } else if (json_object_object_get_ex(rec, "status", &v) &&
                   !strcmp(json_object_get_string(v), "failed")) {
            char why[2200], task[1000];
            if (r->ref_index >= 0 && st->refs[r->ref_index].missing[0]) {
                slurm_tasks_describe(rt, (uint32_t)r->ref_index, task, sizeof task);
                snprintf(why, sizeof why, "no reference (%s): %s", st->refs[r->ref_index].missing,
                         task);
            } else {
                slurm_tasks_describe(mt, i, task, sizeof task);
                snprintf(why, sizeof why, "no result: %s", task);
            }
            json_object_object_add(rec, "reason", json_object_new_string(why));
            json_object_object_del(rec, "config");
            fprintf(stderr, "study: run %s: %s\n", r->id, why);
        }
        r->record = rec;
    }
    runner_set_collect_only(0);
    slurm_tasks_free(rt);
    slurm_tasks_free(mt);
}

int cmd_study(int argc, char **argv)
{
    const char *file = NULL, *out = NULL;
    unsigned long jobs = 1;
    int fresh = 0, dry = 0, taken;
    slurm_options so = {0};
    for (int i = 0; i < argc; i++) {
        if ((taken = slurm_take_option(argc, argv, &i, &so)) != 0) {
            if (taken < 0)
                return EXIT_USAGE;
        } else if (!strcmp(argv[i], "--out") && i + 1 < argc)
            out = argv[++i];
        else if (!strcmp(argv[i], "--jobs") && i + 1 < argc) {
            if (!cli_parse_uint(argv[++i], 1, 64, &jobs))
                return cli_fail(EXIT_USAGE, "study: --jobs '%s' is not an integer in 1..64",
                                argv[i]);
        } else if (!strcmp(argv[i], "--resume"))
            fresh = 0;
        else if (!strcmp(argv[i], "--fresh"))
            fresh = 1;
        else if (!strcmp(argv[i], "--dry-run"))
            dry = 1;
        else if (argv[i][0] == '-')
            return cli_fail(EXIT_USAGE, "study: unknown or incomplete option '%s'", argv[i]);
        else if (!file)
            file = argv[i];
        else
            return cli_fail(EXIT_USAGE, "study: one study file at a time");
    }
    if (!file || (!out && !dry))
        return cli_fail(
            EXIT_USAGE,
            "study: usage: gibench study STUDY.json --out DIR [--jobs N] [--resume|--fresh] "
            "[--dry-run] "
            "[--slurm [--partition P] [--gres G] [--time T] [--array-limit K] [--no-wait]]");
    if (!out)
        out = ".";
    so.dry_run = dry;
    int src = slurm_check(&so, file, out);
    if (src != EXIT_OK)
        return src;
    if (fresh && (so.enabled || so.cell || so.collect))
        return cli_fail(EXIT_USAGE,
                        "study: --fresh does not go with --slurm (remove the results to redo)");
    gi_plugins *reg = cli_load_plugins(0);
    study st;
    memset(&st, 0, sizeof st);
    int rc = load_study(&st, file, out, reg);
    if (rc == EXIT_OK && (so.enabled || so.cell)) {
        /* Slurm: submit the cells, or run one as an array task */
        if (st.timer)
            setenv("GIBENCH_TIMER", st.timer, 1);
        cli_install_signal_handlers();
        /* a study running locally in DIR refuses the submission; the lock
         * is given back at once, for the collect job to take */
        int lock_fd = -1;
        if (so.enabled && !dry && cli_mkdirs(out))
            lock_fd = lock_out_dir(out, &rc);
        if (lock_fd >= 0)
            close(lock_fd);
        if (rc == EXIT_OK)
            rc = so.cell ? slurm_cell(&st, out, reg, so.cell)
                         : slurm_submit_study(&st, file, out, reg, &so);
        study_free(&st);
        gi_plugins_free(reg);
        return rc;
    }
    if (rc == EXIT_OK && so.collect) {
        slurm_collecting = &so;
        runner_set_collect_only(1);
    }
    if (rc == EXIT_OK && dry)
        print_plan(&st);
    if (rc == EXIT_OK && !dry && !cli_mkdirs(out))
        rc = cli_fail(EXIT_RUN, "study: cannot create %s", out);
    int lock_fd = -1;
    if (rc == EXIT_OK && !dry)
        lock_fd = lock_out_dir(out, &rc);
    if (rc == EXIT_OK && !dry && st.timer)
        setenv("GIBENCH_TIMER", st.timer, 1);
    if (rc == EXIT_OK && !dry) {
        cli_install_signal_handlers();
        fprintf(stderr, "study: %s: %u runs on %u scenes\n", st.name, st.run_count, st.scene_count);
        rc = build_references(&st, out);
    }
    if (rc == EXIT_OK && !dry) {
        if (so.collect)
            slurm_collect_runs(&st, reg, out, so.collect);
        else
            execute_runs(&st, (uint32_t)jobs, fresh, reg);
        /* the scene's size, for scale studies (cached records too) */
        for (uint32_t i = 0; i < st.run_count; i++)
            if (st.runs[i].record) {
                const study_scene *sc = &st.scenes[st.runs[i].scene_index];
                json_object_object_add(st.runs[i].record, "scene_triangles",
                                       json_object_new_int64(sc->triangles));
                json_object_object_add(st.runs[i].record, "scene_vertices",
                                       json_object_new_int64(sc->vertices));
            }
        json_object *runs = json_object_new_array();
        char renderer[256] = "";
        int failed = 0, interrupted = 0;
        for (uint32_t i = 0; i < st.run_count; i++) {
            json_object *v;
            if (!st.runs[i].record)
                continue;
            if (!renderer[0] && json_object_object_get_ex(st.runs[i].record, "renderer", &v))
                snprintf(renderer, sizeof renderer, "%s", json_object_get_string(v));
            if (json_object_object_get_ex(st.runs[i].record, "status", &v) &&
                !strcmp(json_object_get_string(v), "failed"))
                failed++;
            if (json_object_object_get_ex(st.runs[i].record, "status", &v) &&
                !strcmp(json_object_get_string(v), "interrupted"))
                interrupted++;
            json_object_array_add(runs, json_object_get(st.runs[i].record));
        }
        char title[512], refdesc[256];
        snprintf(title, sizeof title, "gibench study: %s (%ux%u, %u frames)", st.name,
                 st.base.width, st.base.height, st.base.frames);
        snprintf(refdesc, sizeof refdesc,
                 "path traced (Embree), %u spp, %u bounces; bounce-matched the same spp%s",
                 st.ref_spp, st.ref_bounces,
                 st.ref_pixel_center ? "; camera rays through pixel centres" : "");
        json_object *meta = report_meta_new(title, "study", argc, argv, renderer, refdesc);
        if (st.ref_count) {
            char ref_png[512];
            snprintf(ref_png, sizeof ref_png, "references/%s_b%u_%uspp%s.png", st.refs[0].name,
                     st.ref_bounces, st.ref_spp, st.ref_pixel_center ? "_center" : "");
            json_object_object_add(meta, "reference_png", json_object_new_string(ref_png));
        }
        reference_sets(&st, meta);
        json_object *chart_list = json_object_new_array();
        charts_and_speedups(&st, out, meta, chart_list);
        animation_report(&st, out, meta, chart_list);
        user_charts(&st, out, runs, chart_list);
        json_object_object_add(meta, "charts", chart_list);
        char why[1024];
        if (!report_write(out, runs, meta, why, sizeof why))
            rc = cli_fail(EXIT_RUN, "study: %s", why);
        else
            fprintf(stderr,
                    "study: wrote %s/report.md, index.html, runs.csv, frames.csv, curves.csv (%d "
                    "failed runs)\n",
                    out, failed);
        if (rc == EXIT_OK && cli_interrupted)
            rc = cli_fail(EXIT_RUN,
                          "study: interrupted (%d runs to redo); rerun the same command to resume",
                          interrupted);
        json_object_put(runs);
        json_object_put(meta);
    }
    study_free(&st);
    gi_plugins_free(reg);
    if (lock_fd >= 0)
        close(lock_fd); /* releases the lock */
    return rc;
}
