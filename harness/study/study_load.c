/* The study file read and checked (docs/studies.md, "gibench study"): the top-level
 * keys, the reference settings, the method entries, the run settings that
 * either may give (scenes, size, frames, time, animate, ...), each scene
 * loaded once, and the "charts" list. The runs are planned in study_plan.c. */
#define _POSIX_C_SOURCE 200809L
#include "study_internal.h"
#include "view_file.h"

#include "gi/cache.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void stem_of(const char *path, char *out, size_t size)
{
    const char *b = strrchr(path, '/');
    b = b ? b + 1 : path;
    size_t n = strlen(b) < size ? strlen(b) : size - 1;
    memcpy(out, b, n);
    out[n] = '\0';
    char *dot = strrchr(out, '.');
    if (dot)
        *dot = '\0';
}

/* The scene's index in the study, loading (and so validating) it once;
 * `name` is the scene as the study names it, resolved from the study's base
 * folder (study_paths.c). */
static int scene_index(study *st, const char *file, const char *jpath, const char *name, int *out)
{
    char path[4096];
    study_resolve(st, name, path, sizeof path);
    for (uint32_t i = 0; i < st->scene_count; i++)
        if (!strcmp(st->scenes[i].path, path)) {
            *out = (int)i;
            return EXIT_OK;
        }
    if (st->scene_count == MAX_SCENES)
        return study_fail_json(file, jpath, "more than 16 scenes in one study");
    int rc = study_check_readable(st, file, jpath, name, path);
    if (rc != EXIT_OK)
        return rc;
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
    /* run ids are keyed on the content: two names of one scene would give
     * two runs of one id (and run at once under --jobs) */
    for (uint32_t i = 0; i < st->scene_count; i++)
        if (st->scenes[i].hash == hash)
            return cli_fail(EXIT_USAGE, "%s: %s: %s has the same content as %s, listed already",
                            file, jpath, name, st->scenes[i].name);
    study_scene *sc = &st->scenes[st->scene_count];
    sc->name = name;
    snprintf(sc->path, sizeof sc->path, "%s", path);
    sc->hash = hash;
    sc->triangles = triangles;
    sc->vertices = vertices;
    stem_of(path, sc->stem, sizeof sc->stem);
    *out = (int)st->scene_count++;
    return EXIT_OK;
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
            return study_fail_json(file, path, "a list of 1 to 16 scene files is required");
        rs->scene_n = 0;
        for (size_t i = 0; i < json_object_array_length(v); i++) {
            json_object *e = json_object_array_get_idx(v, i);
            char ep[200];
            snprintf(ep, sizeof ep, "%s/%zu", path, i);
            if (!json_object_is_type(e, json_type_string))
                return study_fail_json(file, ep, "a scene is a file name");
            int rc = scene_index(st, file, ep, json_object_get_string(e), &rs->scenes[rs->scene_n]);
            if (rc != EXIT_OK)
                return rc;
            for (uint32_t k = 0; k < rs->scene_n; k++)
                if (rs->scenes[k] == rs->scenes[rs->scene_n])
                    return study_fail_json(file, ep, "scene listed twice (one run id for both)");
            rs->scene_n++;
        }
    }
    if (json_object_object_get_ex(o, "size", &v)) {
        snprintf(path, sizeof path, "%s/size", prefix);
        if (!json_object_is_type(v, json_type_array) || json_object_array_length(v) != 2)
            return study_fail_json(file, path, "must be [width, height]");
        json_object *jw = json_object_array_get_idx(v, 0), *jh = json_object_array_get_idx(v, 1);
        int64_t w = json_object_get_int64(jw), h = json_object_get_int64(jh);
        if (!json_object_is_type(jw, json_type_int) || !json_object_is_type(jh, json_type_int) ||
            !gi_image_size_ok((unsigned long long)w, (unsigned long long)h) || w < 1 || h < 1)
            return study_fail_json(file, path,
                                   "width and height must be integers, " GI_IMAGE_SIZE_RULE);
        rs->width = (uint32_t)w;
        rs->height = (uint32_t)h;
    }
    int rc;
    if ((rc = study_get_uint(o, prefix, "frames", 1, 100000, rs->frames, &rs->frames, file)) ||
        (rc = study_get_uint(o, prefix, "warmup", 0, 1000, rs->warmup, &rs->warmup, file)) ||
        (rc = study_get_uint(o, prefix, "repeats", 1, 100, rs->repeats, &rs->repeats, file)))
        return rc;
    if (rs->warmup >= rs->frames)
        rs->warmup = rs->frames > 1 ? rs->frames - 1 : 0;
    double d;
    if ((rc = study_get_number(o, prefix, "time", 0.0, 1e6, rs->time, &d, file)))
        return rc;
    rs->time = (float)d;
    if (json_object_object_get_ex(o, "animate", &v) && !json_object_is_type(v, json_type_null)) {
        d = json_object_get_double(v);
        if ((!json_object_is_type(v, json_type_int) && !json_object_is_type(v, json_type_double)) ||
            !(d > 0) || !(d <= 1e4)) {
            snprintf(path, sizeof path, "%s/animate", prefix);
            return study_fail_json(
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
                return study_fail_json(file, path, "must be true or false");
            }
            *dest[k] = json_object_get_boolean(v);
        }
    if (json_object_object_get_ex(o, "label", &v)) {
        if (!json_object_is_type(v, json_type_string)) {
            snprintf(path, sizeof path, "%s/label", prefix);
            return study_fail_json(file, path, "must be a string");
        }
        rs->label = json_object_get_string(v);
    }
    return EXIT_OK;
}

/* Checks the "charts" list (each chart is drawn after the runs). */
static int check_charts(json_object *charts, const char *file)
{
    if (!json_object_is_type(charts, json_type_array) || json_object_array_length(charts) > 32)
        return study_fail_json(file, "/charts", "must be a list of at most 32 charts");
    static const char *known[] = {"file",  "title", "where",   "x",       "y", "series",
                                  "log_x", "log_y", "x_label", "y_label", NULL};
    for (size_t i = 0; i < json_object_array_length(charts); i++) {
        json_object *c = json_object_array_get_idx(charts, i), *v;
        char path[64];
        snprintf(path, sizeof path, "/charts/%zu", i);
        if (!json_object_is_type(c, json_type_object))
            return study_fail_json(file, path, "a chart is an object");
        int rc = study_check_keys(c, known, path, file);
        if (rc != EXIT_OK)
            return rc;
        const char *need[3] = {"file", "x", "y"};
        for (int k = 0; k < 3; k++)
            if (!json_object_object_get_ex(c, need[k], &v) ||
                !json_object_is_type(v, json_type_string) || !*json_object_get_string(v))
                return study_fail_json(file, path,
                                       "a chart needs \"file\", \"x\" and \"y\" (strings)");
        const char *f = json_object_get_string(json_object_object_get(c, "file"));
        size_t n = strlen(f);
        if (n < 5 || strcmp(f + n - 4, ".png") || strchr(f, '/'))
            return study_fail_json(file, path, "\"file\" must be a plain file name ending in .png");
        if (json_object_object_get_ex(c, "where", &v) && !json_object_is_type(v, json_type_object))
            return study_fail_json(file, path, "\"where\" must be an object {field: value}");
        if (json_object_object_get_ex(c, "series", &v) && !json_object_is_type(v, json_type_string))
            return study_fail_json(file, path, "\"series\" must be a field name");
        const char *texts[3] = {"title", "x_label", "y_label"}, *flags[2] = {"log_x", "log_y"};
        for (int k = 0; k < 3; k++)
            if (json_object_object_get_ex(c, texts[k], &v) &&
                !json_object_is_type(v, json_type_string))
                return study_fail_json(file, path,
                                       "\"title\", \"x_label\" and \"y_label\" must be strings");
        for (int k = 0; k < 2; k++)
            if (json_object_object_get_ex(c, flags[k], &v) &&
                !json_object_is_type(v, json_type_boolean))
                return study_fail_json(file, path, "\"log_x\" and \"log_y\" must be true or false");
    }
    return EXIT_OK;
}

/* The top-level keys besides "reference" and "methods": the name, the
 * camera, the run settings every method entry starts from, the seed,
 * exposure, timeout, timer and the "charts" list. */
static int load_top_level(study *st, json_object *o, const char *file)
{
    json_object *v;
    static const char *known[] = {
        "name",    "description", "scenes",    "size",    "frames", "warmup",  "repeats",
        "seed",    "camera",      "time",      "animate", "cache",  "compare", "exposure",
        "timeout", "methods",     "reference", "charts",  "timer",  "base",    NULL};
    int rc = study_check_keys(o, known, "", file);
    if (rc != EXIT_OK)
        return rc;
    const char *desc;
    if ((rc = study_get_string(o, "", "name", 0, "study", &st->name, file)) ||
        (rc = study_get_string(o, "", "description", 0, NULL, &desc, file)) ||
        (rc = study_get_string(o, "", "camera", 1, NULL, &st->camera, file)))
        return rc;
    st->camera_name = st->camera;
    if (st->camera && !strncmp(st->camera, "view:", 5)) {
        /* a saved view is a file like the scenes: from the study's base */
        char path[4096];
        study_resolve(st, st->camera + 5, path, sizeof path);
        if ((rc = study_check_readable(st, file, "/camera", st->camera + 5, path)))
            return rc;
        snprintf(st->camera_buf, sizeof st->camera_buf, "view:%s", path);
        st->camera = st->camera_buf;
    }
    if (!json_object_object_get_ex(o, "scenes", &v))
        return study_fail_json(file, "/scenes", "a list of 1 to 16 scene files is required");
    run_settings *b = &st->base;
    b->width = b->height = 128;
    b->frames = 8;
    b->warmup = 1;
    b->repeats = 1;
    b->cache = 1;
    b->compare = 1;
    if ((rc = parse_settings(st, o, "", file, b)))
        return rc;
    if ((rc = study_get_uint(o, "", "seed", 0, 0x7FFFFFFF, 1, &st->seed, file)))
        return rc;
    double exposure;
    if ((rc = study_get_number(o, "", "exposure", -64.0, 64.0, 0.0, &exposure, file)) ||
        (rc = study_get_number(o, "", "timeout", 0.0, 1e6, 600.0, &st->timeout_s, file)))
        return rc;
    st->exposure = (float)exposure;
    if (!(st->timeout_s > 0))
        return study_fail_json(file, "/timeout", "must be a positive number of seconds");
    if (json_object_object_get_ex(o, "timer", &v)) {
        /* the stage timers of every run (GIBENCH_TIMER, inherited by the children) */
        const char *tv = json_object_get_string(v);
        if (!json_object_is_type(v, json_type_string) ||
            (strcmp(tv, "query") && strcmp(tv, "finish") && strcmp(tv, "cputime")))
            return study_fail_json(file, "/timer", "must be \"finish\", \"query\" or \"cputime\"");
        st->timer = tv;
    }
    if (json_object_object_get_ex(o, "charts", &v)) {
        if ((rc = check_charts(v, file)))
            return rc;
        st->charts = v;
    }
    return EXIT_OK;
}

/* "reference": the path tracer's settings for the references (defaults
 * when the study gives none). */
static int load_reference(study *st, json_object *o, const char *file)
{
    json_object *ref;
    int rc;
    st->ref_spp = 256;
    st->ref_bounces = 64;
    st->conv_repeats = 3;
    if (!json_object_object_get_ex(o, "reference", &ref))
        return EXIT_OK;
    if (!json_object_is_type(ref, json_type_object))
        return study_fail_json(file, "/reference", "must be an object {\"spp\": ..., ...}");
    if ((rc = study_get_uint(ref, "/reference", "spp", 1, 1u << 24, 256, &st->ref_spp, file)) ||
        (rc = study_get_uint(ref, "/reference", "max_bounces", 0, 1024, 64, &st->ref_bounces,
                             file)) ||
        /* every point of the path tracer's curve timed this often (issue 34: one
         * sample is no measurement on machines whose speed drifts) */
        (rc = study_get_uint(ref, "/reference", "convergence_repeats", 3, 64, 3, &st->conv_repeats,
                             file)))
        return rc;
    json_object *cs, *tse, *px;
    static const char *ref_keys[] = {
        "spp", "target_se", "max_bounces", "convergence_spp", "pixel", "convergence_repeats", NULL};
    if ((rc = study_check_keys(ref, ref_keys, "/reference", file)))
        return rc;
    if (json_object_object_get_ex(ref, "pixel", &px)) {
        const char *pv = json_object_get_string(px);
        if (!json_object_is_type(px, json_type_string) ||
            (strcmp(pv, "box") && strcmp(pv, "center")))
            return study_fail_json(file, "/reference/pixel",
                                   "must be \"box\" (the pixel's average) or \"center\"");
        st->ref_pixel_center = !strcmp(pv, "center");
    }
    if (json_object_object_get_ex(ref, "target_se", &tse) &&
        !json_object_is_type(tse, json_type_null)) {
        st->ref_target_se = json_object_get_double(tse);
        if (!(st->ref_target_se > 0))
            return study_fail_json(file, "/reference/target_se",
                                   "must be a positive relative standard error");
    }
    if (json_object_object_get_ex(ref, "convergence_spp", &cs)) {
        if (!json_object_is_type(cs, json_type_array) || json_object_array_length(cs) > 32)
            return study_fail_json(file, "/reference/convergence_spp",
                                   "must be a list of at most 32 sample counts");
        for (size_t i = 0; i < json_object_array_length(cs); i++) {
            json_object *kj = json_object_array_get_idx(cs, i);
            int64_t k = json_object_get_int64(kj);
            if (!json_object_is_type(kj, json_type_int) || k < 1 || (uint64_t)k >= st->ref_spp)
                return study_fail_json(file, "/reference/convergence_spp",
                                       "each count must be 1 .. spp-1");
            st->conv_spp[st->conv_n++] = (uint32_t)k;
        }
    }
    return EXIT_OK;
}

/* Entry i of the "methods" list: its settings over the top level's, then
 * its runs (every installed method's defaults for "method": "all"). */
static int load_method_entry(study *st, json_object *e, size_t i, const char *file,
                             const char *out_dir, gi_plugins *reg)
{
    static const char *entry_keys[] = {"method", "params",  "label",   "scenes", "size",
                                       "frames", "warmup",  "repeats", "time",   "animate",
                                       "cache",  "compare", NULL};
    json_object *id, *params = NULL;
    int rc;
    char mpath[64];
    snprintf(mpath, sizeof mpath, "/methods/%zu", i);
    if (!json_object_is_type(e, json_type_object) || !json_object_object_get_ex(e, "method", &id))
        return study_fail_json(file, mpath, "needs \"method\"");
    if (!json_object_is_type(id, json_type_string))
        return study_fail_json(file, mpath, "\"method\" must be a method id (a string) or \"all\"");
    if ((rc = study_check_keys(e, entry_keys, mpath, file)))
        return rc;
    run_settings rs = st->base;
    if ((rc = parse_settings(st, e, mpath, file, &rs)))
        return rc;
    json_object_object_get_ex(e, "params", &params);
    if (params && !json_object_is_type(params, json_type_object))
        return study_fail_json(file, mpath, "\"params\" must be an object");
    const char *mid = json_object_get_string(id);
    if (!strcmp(mid, "all")) {
        if (params)
            return study_fail_json(file, mpath,
                                   "\"all\" runs every method with its defaults: no \"params\"");
        for (uint32_t k = 0; k < reg->count; k++)
            if ((rc = study_expand_method(st, file, out_dir, reg->items[k].method, NULL, mpath,
                                          &rs)))
                return rc;
        return EXIT_OK;
    }
    const gi_method *m = gi_plugins_find(reg, mid);
    if (!m) {
        char msg[256];
        snprintf(msg, sizeof msg, "no method '%s' is installed (see gibench methods)", mid);
        return study_fail_json(file, mpath, msg);
    }
    return study_expand_method(st, file, out_dir, m, params, mpath, &rs);
}

/* "methods": "all" (every installed method with its defaults) or a list
 * of entries, expanded into the study's runs. */
static int load_methods(study *st, json_object *o, const char *file, const char *out_dir,
                        gi_plugins *reg)
{
    json_object *v;
    int rc;
    if (!json_object_object_get_ex(o, "methods", &v))
        return study_fail_json(file, "/methods", "required (\"all\" or a list)");
    st->runs = calloc(MAX_RUNS, sizeof *st->runs);
    if (!st->runs)
        return cli_fail(EXIT_RUN, "out of memory");
    if (json_object_is_type(v, json_type_string) && !strcmp(json_object_get_string(v), "all")) {
        for (uint32_t i = 0; i < reg->count; i++)
            if ((rc = study_expand_method(st, file, out_dir, reg->items[i].method, NULL, "/methods",
                                          &st->base)))
                return rc;
        return EXIT_OK;
    }
    if (!json_object_is_type(v, json_type_array) || json_object_array_length(v) == 0)
        return study_fail_json(
            file, "/methods",
            "must be \"all\" or a non-empty list of {\"method\": id, \"params\": {...}}");
    for (size_t i = 0; i < json_object_array_length(v); i++)
        if ((rc = load_method_entry(st, json_object_array_get_idx(v, i), i, file, out_dir, reg)))
            return rc;
    return EXIT_OK;
}

int study_load(study *st, const char *file, const char *out_dir, gi_plugins *reg)
{
    st->refs = calloc(MAX_REFS, sizeof *st->refs);
    if (!st->refs)
        return cli_fail(EXIT_RUN, "out of memory");
    st->root = study_read_strict_json(file);
    if (!st->root)
        return EXIT_USAGE;
    if (!json_object_is_type(st->root, json_type_object))
        return study_fail_json(file, "/", "a study is a JSON object");
    int rc;
    if ((rc = study_set_base(st, st->root, file)) || (rc = load_top_level(st, st->root, file)) ||
        (rc = load_reference(st, st->root, file)) ||
        (rc = load_methods(st, st->root, file, out_dir, reg)))
        return rc;
    study_name_refs(st);
    return EXIT_OK;
}
