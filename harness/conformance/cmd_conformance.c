/* gibench conformance: the same checks for every method plugin, with no
 * code of its own for any of them (README "Conformance suite").
 *
 * The checks of one method form a fixed list of items (furnace, the shipped
 * scenes, determinism, resize and second prepare, updates, parameters,
 * unknown parameters, light types). The parent runs the list in a child
 * process (`gibench conformance --run-items --method M --from K`), which
 * prints a line when it starts an item and one with the item's result. Each
 * item runs under an alarm (--item-timeout): a crash, a hang or a GL abort
 * costs that item alone; the parent records it as failed with the child's
 * own last line and starts a new child at the next item. Items are then
 * grouped into the table's checks (check "scenes" = all scene items). */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"
#include "proc.h"

#include "gi/image.h"
#include "gi/log.h"
#include "gi/vecmath.h"

#include <dirent.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#ifndef GIBENCH_SOURCE_DIR
#define GIBENCH_SOURCE_DIR "."
#endif

#define CONF_DATA GIBENCH_SOURCE_DIR "/tests/data/conformance"
#define CONF_SCENES GIBENCH_SOURCE_DIR "/scenes"
#define MAX_ITEMS 512
/* The furnace: the image mean within 2 % of the closed form, and 90 % of
 * the pixels within 5 % (Monte Carlo methods are noisy per pixel; the
 * second bound catches errors that cancel in the mean). */
#define FURNACE_TOL 0.02
#define FURNACE_PIXEL_TOL 0.05
#define FURNACE_PIXEL_SHARE 0.90

/* ------------------------------------------------------------------ items */

typedef struct conf_item {
    char group[32]; /* the table's check */
    char arg[600];  /* scene path, parameter "k=v", light kind, rho ... */
} conf_item;

typedef struct conf_opts {
    const char *method;
    uint32_t size;
    double item_timeout;
    int json;
} conf_opts;

/* Shipped scenes, sorted, full paths. */
static uint32_t list_scenes(char names[][512], uint32_t max)
{
    DIR *d = opendir(CONF_SCENES);
    uint32_t n = 0;
    if (!d)
        return 0;
    struct dirent *e;
    while ((e = readdir(d)) && n < max) {
        size_t len = strlen(e->d_name);
        if ((len > 5 && !strcmp(e->d_name + len - 5, ".gltf")) ||
            (len > 4 && !strcmp(e->d_name + len - 4, ".glb")))
            snprintf(names[n++], 512, "%s/%s", CONF_SCENES, e->d_name);
    }
    closedir(d);
    for (uint32_t i = 1; i < n; i++) /* insertion sort: a stable order for the item indices */
        for (uint32_t j = i; j > 0 && strcmp(names[j - 1], names[j]) > 0; j--) {
            char t[512];
            memcpy(t, names[j], 512);
            memcpy(names[j], names[j - 1], 512);
            memcpy(names[j - 1], t, 512);
        }
    return n;
}

static void add_item(conf_item *items, uint32_t *n, const char *group, const char *fmt, ...)
{
    if (*n >= MAX_ITEMS)
        return;
    conf_item *it = &items[(*n)++];
    snprintf(it->group, sizeof it->group, "%s", group);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(it->arg, sizeof it->arg, fmt, ap);
    va_end(ap);
}

/* Parameter values: ints and floats at min and max, booleans both ways,
 * enums at every choice. */
static void param_items(const gi_method *m, conf_item *items, uint32_t *n)
{
    for (const gi_param_desc *d = m->params; d && d->name; d++) {
        switch (d->type) {
        case GI_PARAM_INT:
            add_item(items, n, "params", "%s=%lld", d->name, (long long)d->min);
            add_item(items, n, "params", "%s=%lld", d->name, (long long)d->max);
            break;
        case GI_PARAM_FLOAT:
            add_item(items, n, "params", "%s=%.9g", d->name, d->min);
            add_item(items, n, "params", "%s=%.9g", d->name, d->max);
            break;
        case GI_PARAM_BOOL:
            add_item(items, n, "params", "%s=false", d->name);
            add_item(items, n, "params", "%s=true", d->name);
            break;
        case GI_PARAM_ENUM: {
            char c[64];
            int choices = 1;
            for (const char *p = d->choices ? d->choices : ""; *p; p++)
                choices += *p == '|';
            for (int k = 0; k < choices; k++)
                add_item(items, n, "params", "%s=%s", d->name, gi_param_choice(d, k, c, sizeof c));
            break;
        }
        }
    }
}

static const char *const check_order[] = {
    "furnace_0.5",       "furnace_0.8",     "scenes",        "determinism",   "resize_prepare",
    "update_transforms", "update_vertices", "update_lights", "update_camera", "params",
    "unknown_params",    "light_area",      "light_point",   "light_spot",    "light_directional",
    "light_environment"};
#define CHECK_COUNT (sizeof check_order / sizeof check_order[0])

static uint32_t build_items(const gi_method *m, conf_item *items)
{
    uint32_t n = 0;
    static char scenes[64][512];
    add_item(items, &n, "furnace_0.5", "050");
    add_item(items, &n, "furnace_0.8", "080");
    uint32_t ns = list_scenes(scenes, 64);
    for (uint32_t i = 0; i < ns; i++)
        add_item(items, &n, "scenes", "%s", scenes[i]);
    add_item(items, &n, "determinism", "-");
    add_item(items, &n, "resize_prepare", "-");
    add_item(items, &n, "update_transforms", "-");
    add_item(items, &n, "update_vertices", "-");
    add_item(items, &n, "update_lights", "-");
    add_item(items, &n, "update_camera", "-");
    param_items(m, items, &n);
    add_item(items, &n, "unknown_params", "-");
    add_item(items, &n, "light_area", "area");
    add_item(items, &n, "light_point", "point");
    add_item(items, &n, "light_spot", "spot");
    add_item(items, &n, "light_directional", "directional");
    add_item(items, &n, "light_environment", "environment");
    return n;
}

/* --------------------------------------------------- the child: sessions */

typedef enum { R_PASS = 0, R_FAIL = 1, R_NA = 2 } conf_status;
static const char *const status_name[] = {"pass", "fail", "n/a"};

typedef struct scene_ref {
    gi_scene *scene;
    gi_gpu_scene *gs;
} scene_ref;

typedef struct session {
    const gi_method *m;
    gi_gpu *gpu;
    cli_host host;
    int host_ready;
    void *inst;
    gi_params *params;
    GLuint tex, fbo;
    uint32_t w, h;
    char why[1024];
} session;

static void scene_free(scene_ref *s)
{
    gi_gpu_scene_free(s->gs);
    gi_scene_free(s->scene);
    s->gs = NULL;
    s->scene = NULL;
}

static int scene_open(session *S, const char *path, float t, scene_ref *out)
{
    gi_error err;
    memset(out, 0, sizeof *out);
    out->scene = gi_scene_load(path, &err);
    if (!out->scene) {
        snprintf(S->why, sizeof S->why, "%s", err.text);
        return 0;
    }
    out->gs = gi_gpu_scene_upload(S->gpu, out->scene, &err);
    if (!out->gs) {
        snprintf(S->why, sizeof S->why, "%s", err.text);
        scene_free(out);
        return 0;
    }
    gi_gpu_scene_set_time(out->gs, t);
    return 1;
}

static void instance_free(session *S)
{
    if (S->inst)
        S->m->destroy(S->inst);
    S->inst = NULL;
    gi_params_free(S->params);
    S->params = NULL;
    if (S->host_ready)
        cli_host_free(&S->host);
    S->host_ready = 0;
}

static int method_error(session *S, const char *what, gi_result r)
{
    const char *msg = S->inst ? S->m->last_error(S->inst) : "";
    snprintf(S->why, sizeof S->why, "%s failed (%s)%s%s", what, gi_result_name(r),
             msg && *msg ? ": " : "", msg ? msg : "");
    return 0;
}

/* A new instance with parameters kv[0..n), prepared on scene sc. */
static int instance_new(session *S, const char *const *kv, uint32_t n, const scene_ref *sc)
{
    gi_error err;
    instance_free(S);
    S->params = gi_params_parse(S->m->id, S->m->params, kv, n, &err);
    if (!S->params) {
        snprintf(S->why, sizeof S->why, "%s", err.text);
        return 0;
    }
    /* No cache directory: precomputation runs afresh, nothing is kept. */
    cli_host_init(&S->host, S->m->id, NULL, sc->gs, gi_gpu_renderer(S->gpu),
                  gi_gpu_is_software(S->gpu));
    S->host.show_progress = 0;
    S->host_ready = 1;
    gi_error cerr;
    gi_result r = gi_method_create(S->m, &S->host.host, S->params, &S->inst, &cerr);
    if (r != GI_OK) {
        snprintf(S->why, sizeof S->why, "%s", cerr.text);
        return 0;
    }
    r = S->m->prepare(S->inst, sc->gs);
    if (r != GI_OK)
        return method_error(S, "prepare", r);
    return 1;
}

static int target_size(session *S, uint32_t w, uint32_t h)
{
    if (S->tex && S->w == w && S->h == h)
        return 1;
    if (S->fbo)
        glDeleteFramebuffers(1, &S->fbo);
    if (S->tex)
        glDeleteTextures(1, &S->tex);
    glCreateTextures(GL_TEXTURE_2D, 1, &S->tex);
    glTextureStorage2D(S->tex, 1, GL_RGBA32F, (GLsizei)w, (GLsizei)h);
    glCreateFramebuffers(1, &S->fbo);
    glNamedFramebufferTexture(S->fbo, GL_COLOR_ATTACHMENT0, S->tex, 0);
    S->w = w;
    S->h = h;
    return 1;
}

/* The view of the scene's first camera at time t; shift moves the eye
 * along the camera's right axis (the camera-change check). */
static void make_view(const gi_scene *s, float t, uint32_t w, uint32_t h, float shift,
                      uint32_t seed, gi_view *v)
{
    gi_camera_frame cf = gi_scene_camera_at(s, s->camera_count ? 0 : -1, t);
    if (shift != 0.0f) {
        gi_vec3 right =
            gi_v3(cf.world_from_camera[0], cf.world_from_camera[1], cf.world_from_camera[2]);
        cf.eye = gi_v3_add(cf.eye, gi_v3_scale(right, shift));
        cf.world_from_camera[12] = cf.eye.x;
        cf.world_from_camera[13] = cf.eye.y;
        cf.world_from_camera[14] = cf.eye.z;
    }
    gi_view_from_camera(&cf, w, h, t, v);
    v->seed = seed;
}

/* Renders `frames` frames (frame_index first, first + 1, ...) and reads the image back. */
static gi_image *render_frames(session *S, const scene_ref *sc, float t, uint32_t w, uint32_t h,
                               uint32_t frames, uint32_t first, float shift, uint32_t seed)
{
    gi_error err;
    target_size(S, w, h);
    const float black[4] = {0, 0, 0, 1};
    glClearNamedFramebufferfv(S->fbo, GL_COLOR, 0, black);
    gi_target target = {S->tex, S->fbo, w, h};
    for (uint32_t f = 0; f < frames; f++) {
        gi_view v;
        make_view(sc->scene, t, w, h, shift, seed, &v);
        v.frame_index = first + f;
        gi_result r = S->m->render(S->inst, &v, &target);
        if (r != GI_OK) {
            method_error(S, "render", r);
            return NULL;
        }
        if (gi_gl_check("after render", &err) != GI_OK) {
            snprintf(S->why, sizeof S->why, "%s", err.text);
            return NULL;
        }
    }
    gi_image *img = gi_gpu_read_texture(S->tex, w, h);
    if (!img)
        snprintf(S->why, sizeof S->why, "out of memory reading the image back");
    return img;
}

/* A fresh instance on sc, `frames` frames at t = 0 of size x size with
 * `seed`: the image, or NULL with the reason kept in S. */
static gi_image *fresh_render(session *S, const scene_ref *sc, uint32_t size, uint32_t frames,
                              uint32_t seed)
{
    return instance_new(S, NULL, 0, sc)
               ? render_frames(S, sc, 0.0f, size, size, frames, 0, 0.0f, seed)
               : NULL;
}

static int update(session *S, scene_ref *sc, uint32_t flags, float t)
{
    gi_gpu_scene_set_time(sc->gs, t);
    gi_changes ch = {flags, t, ~0ull};
    gi_result r = S->m->update(S->inst, sc->gs, &ch);
    return r == GI_OK ? 1 : method_error(S, "update", r);
}

/* ------------------------------------------------------- image measures */

typedef struct img_stats {
    double mean; /* of (R + G + B) / 3 over finite pixels */
    uint64_t nonfinite, negative;
} img_stats;

static img_stats measure(const gi_image *img)
{
    img_stats st = {0, 0, 0};
    size_t n = (size_t)img->width * img->height, used = 0;
    double sum = 0.0;
    for (size_t i = 0; i < n; i++) {
        const float *p = &img->rgba[4 * i];
        if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2])) {
            st.nonfinite++;
            continue;
        }
        if (p[0] < 0.0f || p[1] < 0.0f || p[2] < 0.0f)
            st.negative++;
        sum += (p[0] + p[1] + p[2]) / 3.0;
        used++;
    }
    st.mean = used ? sum / (double)used : 0.0;
    return st;
}

/* Mean absolute difference over RGB relative to the mean of b (same size). */
static double rel_diff(const gi_image *a, const gi_image *b)
{
    size_t n = (size_t)a->width * a->height;
    double d = 0.0, m = 0.0;
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++) {
            d += fabs((double)a->rgba[4 * i + c] - (double)b->rgba[4 * i + c]);
            m += fabs((double)b->rgba[4 * i + c]);
        }
    return d / (m + 1e-12);
}

/* "finite and non-negative", else a reason. */
static int sane(const gi_image *img, char *why, size_t size)
{
    img_stats st = measure(img);
    if (st.nonfinite) {
        snprintf(why, size, "%llu of %u pixels are NaN or Inf", (unsigned long long)st.nonfinite,
                 img->width * img->height);
        return 0;
    }
    if (st.negative) {
        snprintf(why, size, "%llu of %u pixels are negative", (unsigned long long)st.negative,
                 img->width * img->height);
        return 0;
    }
    return 1;
}

/* ------------------------------------------------------------- the checks */

typedef struct result {
    conf_status status;
    char detail[1024];
} result;

static conf_status set(result *r, conf_status s, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(r->detail, sizeof r->detail, fmt, ap);
    va_end(ap);
    r->status = s;
    return s;
}

static conf_status fail_why(result *r, session *S)
{
    return set(r, R_FAIL, "%s", S->why);
}

static uint32_t frames_for(const gi_method *m, uint32_t progressive_frames)
{
    return (m->caps & GI_CAP_PROGRESSIVE) ? progressive_frames : 1;
}

static void conf_path(char *out, size_t size, const char *name)
{
    snprintf(out, size, "%s/%s", CONF_DATA, name);
}

/* The richest small scene the method's caps cover: the determinism,
 * resize and camera checks run on it; the parameter sweep on the same
 * scenes made of one object (one_object: per-object precomputation such as
 * csm's N^2 maps costs a third). */
static int pick_scene_from(session *S, int one_object, char *path, size_t size, scene_ref *sc,
                           result *r)
{
    static const char *const names[] = {"all.gltf",   "area_point.gltf",  "area.gltf",
                                        "point.gltf", "directional.gltf", "environment.gltf"};
    char why[256] = "";
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        if (one_object && i < 2)
            snprintf(path, size, "%s/one_object_%s", CONF_DATA, names[i]);
        else
            conf_path(path, size, names[i]);
        if (!scene_open(S, path, 0.0f, sc)) {
            set(r, R_FAIL, "%s", S->why);
            return 0;
        }
        if (cli_caps_cover(S->m, sc->scene, 0, why, sizeof why))
            return 1;
        scene_free(sc);
    }
    set(r, R_NA, "no test scene within the caps (%s)", why);
    return 0;
}

static int pick_scene(session *S, char *path, size_t size, scene_ref *sc, result *r)
{
    return pick_scene_from(S, 0, path, size, sc, r);
}

/* Closed emitting sphere seen from its centre: Le * sum_{k=0..B} rho^k with
 * B = max_bounces + 1, the bounce count of the reference `compare` pairs
 * the method with (the emitter itself is k = 0). */
static conf_status check_furnace(session *S, const conf_opts *o, const char *arg, result *r)
{
    char path[512], why[256];
    snprintf(path, sizeof path, "%s/furnace_%s.gltf", CONF_DATA, arg);
    double rho = atof(arg) / 100.0, Le = 1.0;
    scene_ref sc;
    if (!scene_open(S, path, 0.0f, &sc))
        return fail_why(r, S);
    if (!cli_caps_cover(S->m, sc.scene, 0, why, sizeof why)) {
        scene_free(&sc);
        return set(r, R_NA, "%s", why);
    }
    uint32_t B = S->m->max_bounces + 1;
    double expect = 0.0;
    for (uint32_t k = 0; k <= B; k++)
        expect += Le * pow(rho, (double)k);
    gi_image *img = fresh_render(S, &sc, o->size, frames_for(S->m, 4), 1);
    scene_free(&sc);
    if (!img)
        return fail_why(r, S);
    if (!sane(img, why, sizeof why)) {
        gi_image_free(img);
        return set(r, R_FAIL, "%s", why);
    }
    size_t n = (size_t)img->width * img->height, within = 0;
    double worst = 0.0;
    for (size_t i = 0; i < n; i++) {
        double v = (img->rgba[4 * i] + img->rgba[4 * i + 1] + img->rgba[4 * i + 2]) / 3.0;
        double e = fabs(v / expect - 1.0);
        within += e <= FURNACE_PIXEL_TOL;
        worst = e > worst ? e : worst;
    }
    double mean = measure(img).mean, dev = mean / expect - 1.0, frac = (double)within / (double)n;
    gi_image_free(img);
    int ok = fabs(dev) <= FURNACE_TOL && frac >= FURNACE_PIXEL_SHARE;
    return set(r, ok ? R_PASS : R_FAIL,
               "rho %.1f, B = %u: mean %.4f, expected %.4f (%+.2f %%); %.1f %% of pixels within 5 "
               "%% (worst %.1f %%)",
               rho, B, mean, expect, 100.0 * dev, 100.0 * frac, 100.0 * worst);
}

static conf_status check_scene(session *S, const conf_opts *o, const char *path, result *r)
{
    char why[256];
    scene_ref sc;
    if (!scene_open(S, path, 0.0f, &sc))
        return fail_why(r, S);
    if (!cli_caps_cover(S->m, sc.scene, 0, why, sizeof why)) {
        scene_free(&sc);
        return set(r, R_NA, "%s", why);
    }
    gi_image *img = fresh_render(S, &sc, o->size, 1, 1);
    scene_free(&sc);
    if (!img)
        return fail_why(r, S);
    int ok = sane(img, why, sizeof why);
    double mean = measure(img).mean;
    gi_image_free(img);
    return ok ? set(r, R_PASS, "finite, non-negative, mean %.4g", mean) : set(r, R_FAIL, "%s", why);
}

static conf_status check_determinism(session *S, const conf_opts *o, result *r)
{
    char path[512];
    scene_ref sc;
    if (!pick_scene(S, path, sizeof path, &sc, r))
        return r->status;
    uint32_t frames = frames_for(S->m, 2);
    gi_image *a = fresh_render(S, &sc, o->size, frames, 7);
    gi_image *b = a ? fresh_render(S, &sc, o->size, frames, 7) : NULL;
    scene_free(&sc);
    if (!a || !b) {
        gi_image_free(a);
        return fail_why(r, S);
    }
    size_t n = (size_t)a->width * a->height, differ = 0;
    for (size_t i = 0; i < n; i++)
        differ += memcmp(&a->rgba[4 * i], &b->rgba[4 * i], 3 * sizeof(float)) != 0;
    double d = rel_diff(b, a);
    gi_image_free(a);
    gi_image_free(b);
    const char *base = strrchr(path, '/') + 1;
    if (differ)
        return set(r, R_FAIL,
                   "%s, seed 7, two fresh instances: %zu of %zu pixels differ (mean relative "
                   "difference %.2g)",
                   base, differ, n, d);
    return set(r, R_PASS, "%s, seed 7, two fresh instances, %u frame(s): bit-identical", base,
               frames);
}

static conf_status check_resize(session *S, const conf_opts *o, result *r)
{
    char path[512], why[256];
    scene_ref sc, sc2;
    if (!pick_scene(S, path, sizeof path, &sc, r))
        return r->status;
    uint32_t w2 = o->size + 16, h2 = o->size > 16 ? o->size - 8 : o->size,
             frames = frames_for(S->m, 2);
    gi_image *a = NULL, *b = NULL, *c = NULL;
    if (instance_new(S, NULL, 0, &sc)) {
        a = render_frames(S, &sc, 0.0f, o->size, o->size, frames, 0, 0.0f, 3);
        if (a)
            b = render_frames(S, &sc, 0.0f, w2, h2, frames, 0, 0.0f, 3);
        if (b)
            c = render_frames(S, &sc, 0.0f, o->size, o->size, frames, 0, 0.0f, 3);
    }
    if (!c) {
        scene_free(&sc);
        gi_image_free(a);
        gi_image_free(b);
        return fail_why(r, S);
    }
    conf_status st = R_PASS;
    double back = rel_diff(c, a);
    if (!sane(b, why, sizeof why))
        st = set(r, R_FAIL, "at %ux%u: %s", w2, h2, why);
    else if (measure(a).mean > 0 && !(measure(b).mean > 0))
        st = set(r, R_FAIL, "black at %ux%u after %ux%u", w2, h2, o->size, o->size);
    else if (back > 0.01)
        st =
            set(r, R_FAIL, "back at %ux%u the image differs from the first by %.2g (mean relative)",
                o->size, o->size, back);
    gi_image_free(a);
    gi_image_free(b);
    gi_image_free(c);
    if (st != R_PASS) {
        scene_free(&sc);
        return st;
    }
    /* A second prepare, on another scene, against a fresh instance there. */
    char path2[512];
    conf_path(path2, sizeof path2, strstr(path, "/area.gltf") ? "area_point.gltf" : "area.gltf");
    if (!scene_open(S, path2, 0.0f, &sc2)) {
        scene_free(&sc);
        return fail_why(r, S);
    }
    if (!cli_caps_cover(S->m, sc2.scene, 0, why,
                        sizeof why)) { /* then prepare the same scene again */
        scene_free(&sc2);
        conf_path(path2, sizeof path2, strrchr(path, '/') + 1);
        if (!scene_open(S, path2, 0.0f, &sc2)) {
            scene_free(&sc);
            return fail_why(r, S);
        }
    }
    gi_result res = S->m->prepare(S->inst, sc2.gs);
    gi_image *d = NULL, *e = NULL;
    if (res != GI_OK)
        method_error(S, "second prepare", res);
    else
        d = render_frames(S, &sc2, 0.0f, o->size, o->size, frames, 0, 0.0f, 3);
    if (d)
        e = fresh_render(S, &sc2, o->size, frames, 3);
    instance_free(S);
    scene_free(&sc);
    scene_free(&sc2);
    if (!e) {
        gi_image_free(d);
        return fail_why(r, S);
    }
    double again = rel_diff(d, e);
    int ok = sane(d, why, sizeof why);
    gi_image_free(d);
    gi_image_free(e);
    if (!ok)
        return set(r, R_FAIL, "after a second prepare: %s", why);
    if (again > 0.01)
        return set(r, R_FAIL,
                   "after a second prepare (%s) the image differs from a fresh instance's by %.2g",
                   strrchr(path2, '/') + 1, again);
    return set(r, R_PASS,
               "%ux%u -> %ux%u -> back (difference %.2g); second prepare on %s equals a fresh "
               "instance (%.2g)",
               o->size, o->size, w2, h2, back, strrchr(path2, '/') + 1, again);
}

/* An update between frames: the image after update() must be closer to a
 * fresh instance's image of the new state than the old image is (at most
 * a tenth of that distance: what the method did not take in shows), and
 * the new state must look different. */
static conf_status check_update(session *S, const conf_opts *o, const char *which, result *r)
{
    char path[512] = "", why[256];
    uint32_t cap = 0, flags = 0;
    float t1 = 0.0f, shift = 0.0f;
    const char *scene_name = NULL;
    int animated = 0;
    if (!strcmp(which, "transforms")) {
        cap = GI_CAP_RIGID_MOTION, flags = GI_CHANGED_TRANSFORMS, t1 = 1.5f,
        scene_name = "moving.gltf", animated = 1;
    } else if (!strcmp(which, "vertices")) {
        cap = GI_CAP_DEFORMATION, flags = GI_CHANGED_VERTICES, t1 = 2.0f;
    } else if (!strcmp(which, "lights")) {
        cap = GI_CAP_POINT_LIGHTS, flags = GI_CHANGED_LIGHTS, t1 = 1.5f,
        scene_name = "light_moving.gltf";
    } else {
        flags = GI_CHANGED_CAMERA, shift = 0.6f;
    }
    if (cap && !(S->m->caps & cap)) {
        static const char *const what[] = {
            "transforms", "rigid motion",
            "vertices",   "deformation",
            "lights",     "point lights (the light-change check moves a point light)"};
        const char *c = "";
        for (int i = 0; i < 6; i += 2)
            if (!strcmp(which, what[i]))
                c = what[i + 1];
        return set(r, R_NA, "%s does not claim %s", S->m->id, c);
    }
    scene_ref sc;
    if (!strcmp(which, "vertices"))
        snprintf(path, sizeof path, "%s/cornell_deform.gltf", CONF_SCENES);
    else if (scene_name)
        conf_path(path, sizeof path, scene_name);
    if (!strcmp(which, "camera")) {
        if (!pick_scene(S, path, sizeof path, &sc, r))
            return r->status;
    } else {
        if (!scene_open(S, path, 0.0f, &sc))
            return fail_why(r, S);
        if (!cli_caps_cover(S->m, sc.scene, animated, why, sizeof why)) {
            scene_free(&sc);
            return set(r, R_NA, "%s", why);
        }
    }
    uint32_t frames = frames_for(S->m, 2);
    gi_image *a = NULL, *b = NULL, *c = NULL;
    if (instance_new(S, NULL, 0, &sc)) {
        a = render_frames(S, &sc, 0.0f, o->size, o->size, frames, 0, 0.0f, 5);
        /* frame_index goes on counting: the method must see the change itself */
        if (a && update(S, &sc, flags, t1))
            b = render_frames(S, &sc, t1, o->size, o->size, frames, frames, shift, 5);
    }
    if (b && instance_new(S, NULL, 0, &sc)) /* the scene is at t1 now */
        c = render_frames(S, &sc, t1, o->size, o->size, frames, 0, shift, 5);
    instance_free(S);
    scene_free(&sc);
    if (!c) {
        gi_image_free(a);
        gi_image_free(b);
        return fail_why(r, S);
    }
    double old_d = rel_diff(a, c), new_d = rel_diff(b, c);
    int ok = sane(b, why, sizeof why);
    gi_image_free(a);
    gi_image_free(b);
    gi_image_free(c);
    const char *base = strrchr(path, '/') + 1;
    if (!ok)
        return set(r, R_FAIL, "after update: %s", why);
    if (!(old_d > 0.01))
        return set(r, R_FAIL,
                   "%s: the change does not show (difference %.2g); the check cannot judge", base,
                   old_d);
    if (!(new_d <= 0.1 * old_d))
        return set(r, R_FAIL,
                   "%s: after update() the image is %.3g from a fresh instance's of the new state "
                   "(the old image: %.3g); "
                   "limit a tenth",
                   base, new_d, old_d);
    return set(r, R_PASS, "%s: after update() %.3g from a fresh instance (the old image %.3g)",
               base, new_d, old_d);
}

static conf_status check_param(session *S, const conf_opts *o, const char *kv, result *r)
{
    char path[512], why[256];
    scene_ref sc;
    if (!pick_scene_from(S, 1, path, sizeof path, &sc, r))
        return r->status;
    const char *list[1] = {kv};
    gi_image *img = NULL;
    if (instance_new(S, list, 1, &sc))
        img = render_frames(S, &sc, 0.0f, o->size, o->size, frames_for(S->m, 2), 0, 0.0f, 1);
    instance_free(S);
    scene_free(&sc);
    if (!img)
        return fail_why(r, S);
    int ok = sane(img, why, sizeof why);
    gi_image_free(img);
    return ok ? set(r, R_PASS, "%s on %s", kv, strrchr(path, '/') + 1)
              : set(r, R_FAIL, "%s: %s", kv, why);
}

/* The host refuses what the table does not allow; checked on the method's
 * own table: an unknown name, and each parameter just outside its range or
 * with a choice it does not have. */
static conf_status check_unknown(session *S, result *r)
{
    char bad[64][128];
    uint32_t n = 0, accepted = 0;
    char first[160] = "";
    snprintf(bad[n++], 128, "conformance_no_such_parameter=1");
    for (const gi_param_desc *d = S->m->params; d && d->name && n < 64; d++) {
        if (d->type == GI_PARAM_INT || d->type == GI_PARAM_FLOAT)
            snprintf(bad[n++], 128, "%s=%.9g", d->name,
                     d->max + (d->type == GI_PARAM_INT ? 1.0 : fabs(d->max) + 1.0));
        else if (d->type == GI_PARAM_ENUM)
            snprintf(bad[n++], 128, "%s=conformance_no_such_choice", d->name);
        else
            snprintf(bad[n++], 128, "%s=maybe", d->name);
    }
    for (uint32_t i = 0; i < n; i++) {
        const char *kv = bad[i];
        gi_error err;
        gi_params *p = gi_params_parse(S->m->id, S->m->params, &kv, 1, &err);
        if (p) {
            if (!accepted++)
                snprintf(first, sizeof first, "%s", kv);
            gi_params_free(p);
        }
    }
    if (accepted)
        return set(r, R_FAIL, "%u of %u bad settings accepted, e.g. %s", accepted, n, first);
    return set(r, R_PASS, "%u bad settings refused (unknown name, out of range, no such choice)",
               n);
}

/* A scene lit only by one light type must come out non-black and brighter
 * than the same scene without that light. */
static conf_status check_light(session *S, const conf_opts *o, const char *kind, result *r)
{
    char path[512], dark[512], why[256];
    snprintf(path, sizeof path, "%s/%s.gltf", CONF_DATA, kind);
    conf_path(dark, sizeof dark, "dark.gltf");
    scene_ref sc, sd;
    if (!scene_open(S, path, 0.0f, &sc))
        return fail_why(r, S);
    if (!cli_caps_cover(S->m, sc.scene, 0, why, sizeof why)) {
        scene_free(&sc);
        return set(r, R_NA, "%s", why);
    }
    if (!scene_open(S, dark, 0.0f, &sd)) {
        scene_free(&sc);
        return fail_why(r, S);
    }
    uint32_t frames = frames_for(S->m, 2);
    gi_image *lit = fresh_render(S, &sc, o->size, frames, 1);
    gi_image *unlit = lit ? fresh_render(S, &sd, o->size, frames, 1) : NULL;
    instance_free(S);
    scene_free(&sc);
    scene_free(&sd);
    if (!unlit) {
        gi_image_free(lit);
        return fail_why(r, S);
    }
    int ok = sane(lit, why, sizeof why);
    double ml = measure(lit).mean, md = measure(unlit).mean;
    gi_image_free(lit);
    gi_image_free(unlit);
    if (!ok)
        return set(r, R_FAIL, "%s", why);
    if (!(ml > 1e-3) || !(ml > 2.0 * md + 1e-4))
        return set(r, R_FAIL,
                   "claims %s light but the scene lit only by it has mean %.3g (without it %.3g)",
                   kind, ml, md);
    return set(r, R_PASS, "mean %.4g lit, %.3g without the light", ml, md);
}

static conf_status run_item(session *S, const conf_opts *o, const conf_item *it, result *r)
{
    if (!strncmp(it->group, "furnace", 7))
        return check_furnace(S, o, it->arg, r);
    if (!strcmp(it->group, "scenes"))
        return check_scene(S, o, it->arg, r);
    if (!strcmp(it->group, "determinism"))
        return check_determinism(S, o, r);
    if (!strcmp(it->group, "resize_prepare"))
        return check_resize(S, o, r);
    if (!strncmp(it->group, "update_", 7))
        return check_update(S, o, it->group + 7, r);
    if (!strcmp(it->group, "params"))
        return check_param(S, o, it->arg, r);
    if (!strcmp(it->group, "unknown_params"))
        return check_unknown(S, r);
    if (!strncmp(it->group, "light_", 6))
        return check_light(S, o, it->arg, r);
    return set(r, R_FAIL, "unknown check %s", it->group);
}

/* The child: items from..count-1, one line when each starts and one with
 * its result; an alarm ends a hung item (and the process). */
/* The time limit of one item. A method that precomputes (caps
 * `precompute`) may take far longer at a parameter's extreme (csm's N=256
 * is 65 536 maps per object): the item checks that the value works, and
 * its limit only guards against a hang, so such items get five times the
 * limit. */
static double item_limit(const gi_method *m, const conf_item *it, double base)
{
    return (m->caps & GI_CAP_PRECOMPUTE) && !strcmp(it->group, "params") ? 5.0 * base : base;
}

static int run_items(const conf_opts *o, uint32_t from)
{
    gi_plugins *reg = cli_load_plugins(1);
    const gi_method *m = reg ? gi_plugins_find(reg, o->method) : NULL;
    if (!m) {
        gi_plugins_free(reg);
        return cli_fail(EXIT_USAGE, "conformance: no method '%s'", o->method);
    }
    static conf_item items[MAX_ITEMS];
    uint32_t n = build_items(m, items);
    for (uint32_t k = from; k < n; k++) {
        printf("ITEM-START %u %s %s\n", k, items[k].group, items[k].arg);
        fflush(stdout);
        alarm((unsigned)ceil(item_limit(m, &items[k], o->item_timeout)));
        double t0 = gi_now();
        session S;
        memset(&S, 0, sizeof S);
        S.m = m;
        result r = {R_FAIL, ""};
        gi_error err;
        if (!strcmp(items[k].group, "unknown_params")) {
            run_item(&S, o, &items[k], &r);
        } else if (!(S.gpu = gi_gpu_create(NULL, &err))) {
            set(&r, R_FAIL, "%s", err.text);
        } else {
            run_item(&S, o, &items[k], &r);
            instance_free(&S);
            if (S.fbo)
                glDeleteFramebuffers(1, &S.fbo);
            if (S.tex)
                glDeleteTextures(1, &S.tex);
            gi_gpu_destroy(S.gpu);
        }
        alarm(0);
        for (char *c = r.detail; *c; c++) /* one line */
            if (*c == '\n' || *c == '\t')
                *c = ' ';
        printf("ITEM-RESULT %u %s %.3f\t%s\n", k, status_name[r.status], gi_now() - t0, r.detail);
        fflush(stdout);
    }
    gi_plugins_free(reg);
    return EXIT_OK;
}

/* --------------------------------------------------------------- parent */

typedef struct item_result {
    conf_status status;
    char detail[1024];
    double seconds;
} item_result;

/* Reads the child's log: results of items, and the last item started. */
static int parse_log(const char *log, item_result *res, uint32_t n, int *started)
{
    FILE *f = fopen(log, "r");
    if (!f)
        return 0;
    char line[2048];
    *started = -1;
    while (fgets(line, sizeof line, f)) {
        unsigned k;
        if (sscanf(line, "ITEM-START %u", &k) == 1 && k < n) {
            *started = (int)k;
        } else if (sscanf(line, "ITEM-RESULT %u", &k) == 1 && k < n) {
            char *st = strchr(line + 12, ' ');
            char *tab = st ? strchr(st, '\t') : NULL;
            if (!st || !tab)
                continue;
            *tab = '\0';
            st++;
            char *secs = strchr(st, ' ');
            if (secs) {
                *secs++ = '\0';
                res[k].seconds = atof(secs);
            }
            res[k].status = !strcmp(st, "pass") ? R_PASS : !strcmp(st, "n/a") ? R_NA : R_FAIL;
            char *d = tab + 1;
            d[strcspn(d, "\n")] = '\0';
            snprintf(res[k].detail, sizeof res[k].detail, "%s", d);
            *started = -2 - (int)k; /* finished */
        }
    }
    fclose(f);
    return 1;
}

typedef struct cell {
    conf_status status;
    char detail[2048];
    double seconds;
} cell;

static void append(char *buf, size_t size, const char *fmt, ...)
{
    size_t used = strlen(buf);
    if (used + 1 >= size)
        return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf + used, size - used, fmt, ap);
    va_end(ap);
}

/* Groups item results into the table's cells. */
static void group_cells(const conf_item *items, const item_result *res, uint32_t n, cell *cells)
{
    for (size_t c = 0; c < CHECK_COUNT; c++) {
        cell *ce = &cells[c];
        memset(ce, 0, sizeof *ce);
        uint32_t total = 0, pass = 0, na = 0, fails = 0;
        for (uint32_t k = 0; k < n; k++) {
            if (strcmp(items[k].group, check_order[c]))
                continue;
            total++;
            ce->seconds += res[k].seconds;
            if (res[k].status == R_PASS)
                pass++;
            else if (res[k].status == R_NA)
                na++;
            else
                fails++;
        }
        int multi = !strcmp(check_order[c], "scenes") || !strcmp(check_order[c], "params");
        ce->status = total == 0 ? R_NA : fails ? R_FAIL : pass ? R_PASS : R_NA;
        if (total == 0) {
            snprintf(ce->detail, sizeof ce->detail, "nothing to check (no %s)", check_order[c]);
            continue;
        }
        if (!multi) {
            for (uint32_t k = 0; k < n; k++)
                if (!strcmp(items[k].group, check_order[c]))
                    snprintf(ce->detail, sizeof ce->detail, "%s", res[k].detail);
            continue;
        }
        append(ce->detail, sizeof ce->detail, "%u run, %u pass, %u n/a, %u fail", total, pass, na,
               fails);
        for (uint32_t k = 0; k < n; k++) {
            if (strcmp(items[k].group, check_order[c]) || res[k].status == R_PASS)
                continue;
            const char *name =
                strrchr(items[k].arg, '/') ? strrchr(items[k].arg, '/') + 1 : items[k].arg;
            if (res[k].status == R_FAIL || !strcmp(check_order[c], "scenes"))
                append(ce->detail, sizeof ce->detail, "; %s %s: %s", name,
                       status_name[res[k].status], res[k].detail);
        }
    }
}

static int run_method(const conf_opts *o, const gi_method *m, const char *tmpdir, cell *cells)
{
    static conf_item items[MAX_ITEMS];
    static item_result res[MAX_ITEMS];
    uint32_t n = build_items(m, items);
    for (uint32_t k = 0; k < n; k++) {
        res[k].status = R_FAIL;
        snprintf(res[k].detail, sizeof res[k].detail, "not run");
        res[k].seconds = 0;
    }
    char log[4200], size[32], timeout[32], from[32];
    snprintf(size, sizeof size, "%u", o->size);
    snprintf(timeout, sizeof timeout, "%g", o->item_timeout);
    uint32_t next = 0;
    while (next < n) {
        snprintf(log, sizeof log, "%s/%s-%u.log", tmpdir, m->id, next);
        snprintf(from, sizeof from, "%u", next);
        char *argv[] = {(char *)cli_self_exe(),
                        "conformance",
                        "--run-items",
                        "--method",
                        (char *)m->id,
                        "--size",
                        size,
                        "--item-timeout",
                        timeout,
                        "--from",
                        from,
                        NULL};
        cli_proc_result pr;
        /* The alarm in the child limits each item; this limit only guards against a child that
         * ignores it. */
        double limit = 60.0;
        for (uint32_t k = next; k < n; k++)
            limit += item_limit(m, &items[k], o->item_timeout);
        int started_ok = cli_run(argv, limit, log, log, &pr) == 0;
        int started = -1;
        parse_log(log, res, n, &started);
        if (!started_ok) {
            for (uint32_t k = next; k < n; k++)
                snprintf(res[k].detail, sizeof res[k].detail, "%s", pr.last_line);
            break;
        }
        if (pr.exit_code == 0 && !pr.signaled && !pr.timed_out && started <= -2 &&
            (uint32_t)(-2 - started) + 1 >= n)
            break; /* ran to the end */
        /* The child ended early: the item it was in (or, when it died
         * between items, the next one) fails with the child's last words. */
        char d[700];
        uint32_t at = started >= 0   ? (uint32_t)started
                      : started < -1 ? (uint32_t)(-1 - started)
                                     : next;
        if (pr.signaled && pr.signal == SIGALRM)
            snprintf(d, sizeof d, "timed out after %g s (the per-item limit)",
                     at < n ? item_limit(m, &items[at], o->item_timeout) : o->item_timeout);
        else
            cli_proc_describe(&pr, d, sizeof d);
        if (started == -1) { /* died before any item: nothing will run */
            for (uint32_t j = next; j < n; j++)
                snprintf(res[j].detail, sizeof res[j].detail, "%s", d);
            break;
        }
        uint32_t k = started >= 0 ? (uint32_t)started : (uint32_t)(-1 - started);
        if (k >= n)
            break;
        res[k].status = R_FAIL;
        snprintf(res[k].detail, sizeof res[k].detail, "%s", d);
        next = k + 1;
    }
    group_cells(items, res, n, cells);
    int failed = 0;
    for (size_t c = 0; c < CHECK_COUNT; c++)
        failed |= cells[c].status == R_FAIL;
    return failed;
}

static void print_table(const gi_method *const *ms, uint32_t count, cell (*cells)[CHECK_COUNT])
{
    printf("%-18s", "check");
    for (uint32_t i = 0; i < count; i++)
        printf(" %-8s", ms[i]->id);
    printf("\n");
    for (size_t c = 0; c < CHECK_COUNT; c++) {
        printf("%-18s", check_order[c]);
        for (uint32_t i = 0; i < count; i++)
            printf(" %-8s", status_name[cells[i][c].status]);
        printf("\n");
    }
    for (uint32_t i = 0; i < count; i++) {
        printf("\n%s (max_bounces %u, furnace bounce limit B = %u):\n", ms[i]->id,
               ms[i]->max_bounces, ms[i]->max_bounces + 1);
        for (size_t c = 0; c < CHECK_COUNT; c++)
            printf("  %-18s %-4s %5.1f s  %s\n", check_order[c], status_name[cells[i][c].status],
                   cells[i][c].seconds, cells[i][c].detail);
    }
}

static json_object *table_json(const gi_method *const *ms, uint32_t count,
                               cell (*cells)[CHECK_COUNT], int failed)
{
    json_object *root = json_object_new_object();
    json_object_object_add(root, "status", json_object_new_string(failed ? "fail" : "pass"));
    json_object *arr = json_object_new_array();
    for (uint32_t i = 0; i < count; i++) {
        json_object *mo = json_object_new_object();
        json_object_object_add(mo, "method", json_object_new_string(ms[i]->id));
        json_object_object_add(mo, "max_bounces", json_object_new_int((int32_t)ms[i]->max_bounces));
        json_object *checks = json_object_new_object();
        for (size_t c = 0; c < CHECK_COUNT; c++) {
            json_object *co = json_object_new_object();
            json_object_object_add(co, "status",
                                   json_object_new_string(status_name[cells[i][c].status]));
            json_object_object_add(co, "detail", json_object_new_string(cells[i][c].detail));
            json_object_object_add(co, "seconds", json_object_new_double(cells[i][c].seconds));
            json_object_object_add(checks, check_order[c], co);
        }
        json_object_object_add(mo, "checks", checks);
        json_object_array_add(arr, mo);
    }
    json_object_object_add(root, "methods", arr);
    return root;
}

int cmd_conformance(int argc, char **argv)
{
    conf_opts o = {NULL, 32, 60.0, 0};
    int child = 0;
    unsigned long from = 0;
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        unsigned long u;
        if (!strcmp(a, "--json")) {
            o.json = 1;
        } else if (!strcmp(a, "--run-items")) {
            child = 1;
        } else if (!strcmp(a, "--method") || !strcmp(a, "--size") || !strcmp(a, "--item-timeout") ||
                   !strcmp(a, "--from")) {
            if (!v)
                return cli_fail(EXIT_USAGE, "conformance: %s needs a value", a);
            i++;
            if (!strcmp(a, "--method")) {
                o.method = v;
            } else if (!strcmp(a, "--size")) {
                if (!cli_parse_uint(v, 32, 64, &u))
                    return cli_fail(EXIT_USAGE,
                                    "conformance: --size '%s' is not an integer in 32..64", v);
                o.size = (uint32_t)u;
            } else if (!strcmp(a, "--item-timeout")) {
                float t;
                if (!cli_parse_float(v, &t) || t < 1.0f)
                    return cli_fail(
                        EXIT_USAGE,
                        "conformance: --item-timeout '%s' is not a number of seconds >= 1", v);
                o.item_timeout = t;
            } else if (!cli_parse_uint(v, 0, MAX_ITEMS, &from)) {
                return cli_fail(EXIT_USAGE, "conformance: --from '%s' is not an item index", v);
            }
        } else {
            return cli_fail(EXIT_USAGE, "conformance: unknown argument '%s' (see gibench --help)",
                            a);
        }
    }
    if (child) {
        if (!o.method)
            return cli_fail(EXIT_USAGE, "conformance: --run-items needs --method");
        return run_items(&o, (uint32_t)from);
    }
    gi_plugins *reg = cli_load_plugins(0);
    if (!reg)
        return cli_fail(EXIT_RUN, "out of memory");
    const gi_method *ms[64];
    uint32_t count = 0;
    if (o.method) {
        const gi_method *m = gi_plugins_find(reg, o.method);
        if (!m) {
            char known[512] = "";
            for (uint32_t i = 0; i < reg->count; i++)
                append(known, sizeof known, "%s%s", i ? ", " : "", reg->items[i].method->id);
            gi_plugins_free(reg);
            return cli_fail(EXIT_USAGE, "conformance: no method '%s' (installed: %s)", o.method,
                            known[0] ? known : "none");
        }
        ms[count++] = m;
    } else {
        for (uint32_t i = 0; i < reg->count && count < 64; i++)
            ms[count++] = reg->items[i].method;
    }
    if (count == 0) {
        gi_plugins_free(reg);
        return cli_fail(EXIT_USAGE, "conformance: no method plugins found");
    }
    char tmpdir[] = "/tmp/gibench-conformance-XXXXXX";
    if (!mkdtemp(tmpdir)) {
        gi_plugins_free(reg);
        return cli_fail(EXIT_RUN, "conformance: cannot make a temporary directory");
    }
    cli_install_signal_handlers();
    cell(*cells)[CHECK_COUNT] = calloc(count, sizeof *cells);
    if (!cells) {
        gi_plugins_free(reg);
        return cli_fail(EXIT_RUN, "out of memory");
    }
    int failed = 0;
    for (uint32_t i = 0; i < count; i++) {
        double t0 = gi_now();
        if (!o.json)
            fprintf(stderr, "conformance: %s ...\n", ms[i]->id);
        failed |= run_method(&o, ms[i], tmpdir, cells[i]);
        if (!o.json)
            fprintf(stderr, "conformance: %s done in %.1f s\n", ms[i]->id, gi_now() - t0);
    }
    if (o.json) {
        json_object *j = table_json(ms, count, cells, failed);
        puts(json_object_to_json_string_ext(j, JSON_C_TO_STRING_PRETTY | JSON_C_TO_STRING_SPACED |
                                                   JSON_C_TO_STRING_NOSLASHESCAPE));
        json_object_put(j);
    } else {
        print_table(ms, count, cells);
    }
    /* the children's logs: kept only while something failed */
    DIR *d = opendir(tmpdir);
    if (d) {
        struct dirent *e;
        char p[4200];
        while ((e = readdir(d)))
            if (e->d_name[0] != '.' && !failed) {
                snprintf(p, sizeof p, "%s/%s", tmpdir, e->d_name);
                unlink(p);
            }
        closedir(d);
    }
    if (!failed)
        rmdir(tmpdir);
    else
        fprintf(stderr, "conformance: the children's logs are in %s\n", tmpdir);
    free(cells);
    gi_plugins_free(reg);
    return failed ? EXIT_RUN : EXIT_OK;
}
