/* gibench conformance: the checks, one per item (docs/conformance.md): the furnace against its
 * closed form, every shipped scene, determinism, resize and a second prepare, updates against a
 * fresh instance, parameter values, refused settings and each light type. */
#include "conf.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The furnace: the image mean within 2 % of the closed form, and 90 % of
 * the pixels within 5 % (Monte Carlo methods are noisy per pixel; the
 * second bound catches errors that cancel in the mean). */
#define FURNACE_TOL 0.02
#define FURNACE_PIXEL_TOL 0.05
#define FURNACE_PIXEL_SHARE 0.90

conf_status conf_set(conf_result *r, conf_status s, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(r->detail, sizeof r->detail, fmt, ap);
    va_end(ap);
    r->status = s;
    return s;
}

static conf_status fail_why(conf_result *r, conf_session *S)
{
    return conf_set(r, R_FAIL, "%s", S->why);
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
static int pick_scene_from(conf_session *S, int one_object, char *path, size_t size, conf_scene *sc,
                           conf_result *r)
{
    static const char *const names[] = {"all.gltf",   "area_point.gltf",  "area.gltf",
                                        "point.gltf", "directional.gltf", "environment.gltf"};
    char why[256] = "";
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        if (one_object && i < 2)
            snprintf(path, size, "%s/one_object_%s", CONF_DATA, names[i]);
        else
            conf_path(path, size, names[i]);
        if (!conf_scene_open(S, path, 0.0f, sc)) {
            conf_set(r, R_FAIL, "%s", S->why);
            return 0;
        }
        if (cli_caps_cover(S->m, sc->scene, 0, why, sizeof why))
            return 1;
        conf_scene_free(sc);
    }
    conf_set(r, R_NA, "no test scene within the caps (%s)", why);
    return 0;
}

static int pick_scene(conf_session *S, char *path, size_t size, conf_scene *sc, conf_result *r)
{
    return pick_scene_from(S, 0, path, size, sc, r);
}

/* Closed emitting sphere seen from its centre: Le * sum_{k=0..B} rho^k with
 * B = max_bounces + 1, the bounce count of the reference `compare` pairs
 * the method with (the emitter itself is k = 0). */
static conf_status check_furnace(conf_session *S, const conf_opts *o, const char *arg,
                                 conf_result *r)
{
    char path[512];
    snprintf(path, sizeof path, "%s/furnace_%s.gltf", CONF_DATA, arg);
    return conf_check_furnace_file(S, o, path, atof(arg) / 100.0, r);
}

/* The furnace at parameters kv[0..n) (the defaults when n is 0). */
static conf_status furnace_at(conf_session *S, const conf_opts *o, const char *path, double rho,
                              const char *const *kv, uint32_t n, conf_result *r)
{
    char why[256];
    double Le = 1.0;
    conf_scene sc;
    if (!conf_scene_open(S, path, 0.0f, &sc))
        return fail_why(r, S);
    if (!cli_caps_cover(S->m, sc.scene, 0, why, sizeof why)) {
        conf_scene_free(&sc);
        return conf_set(r, R_NA, "%s", why);
    }
    uint32_t B = S->m->max_bounces + 1;
    double expect = 0.0;
    for (uint32_t k = 0; k <= B; k++)
        expect += Le * pow(rho, (double)k);
    gi_image *img =
        conf_instance_new(S, kv, n, &sc)
            ? conf_render_frames(S, &sc, 0.0f, o->size, o->size, frames_for(S->m, 4), 0, 0.0f, 1)
            : NULL;
    conf_scene_free(&sc);
    if (!img)
        return fail_why(r, S);
    if (!conf_sane(img, why, sizeof why)) {
        gi_image_free(img);
        return conf_set(r, R_FAIL, "%s", why);
    }
    size_t np = (size_t)img->width * img->height, within = 0;
    double worst = 0.0;
    for (size_t i = 0; i < np; i++) {
        double v = (img->rgba[4 * i] + img->rgba[4 * i + 1] + img->rgba[4 * i + 2]) / 3.0;
        double e = fabs(v / expect - 1.0);
        within += e <= FURNACE_PIXEL_TOL;
        worst = e > worst ? e : worst;
    }
    double mean = conf_measure(img).mean, dev = mean / expect - 1.0,
           frac = (double)within / (double)np;
    gi_image_free(img);
    int ok = fabs(dev) <= FURNACE_TOL && frac >= FURNACE_PIXEL_SHARE;
    return conf_set(
        r, ok ? R_PASS : R_FAIL,
        "rho %.1f, B = %u: mean %.4f, expected %.4f (%+.2f %%); %.1f %% of pixels within 5 "
        "%% (worst %.1f %%)",
        rho, B, mean, expect, 100.0 * dev, 100.0 * frac, 100.0 * worst);
}

/* A method that declares a furnace departure (gi_departure, docs/conformance.md "Declared
 * departures"): the paper's defaults are still rendered and their result reported, not gated,
 * under the label and reason; the check's status is the remedy's, held to the same bounds. A
 * default that fails to render at all still fails: a departure excuses an error, not a crash. */
conf_status conf_check_furnace_file(conf_session *S, const conf_opts *o, const char *path,
                                    double rho, conf_result *r)
{
    const gi_departure *dep = gi_method_departure(S->m, "furnace");
    conf_status s0 = furnace_at(S, o, path, rho, NULL, 0, r);
    if (!dep || s0 == R_NA)
        return s0;
    char buf[512], paper[1024];
    const char *kv[16];
    int n = gi_departure_remedy_args(dep, buf, sizeof buf, kv, 16);
    snprintf(paper, sizeof paper, "%s", r->detail);
    if (n <= 0)
        return conf_set(r, R_FAIL, "declared departure with an unusable remedy '%s'",
                        dep->remedy ? dep->remedy : "");
    conf_result rr = {R_FAIL, ""};
    conf_status s1 = furnace_at(S, o, path, rho, kv, (uint32_t)n, &rr);
    if (s0 == R_FAIL && strncmp(paper, "rho ", 4))
        s1 = R_FAIL; /* the defaults did not even render: not what the declaration covers */
    return conf_set(r, s1,
                    "declared departure: %s; paper default (reported, not gated) %s %s; remedy "
                    "%s: %s",
                    dep->reason, s0 == R_PASS ? "passes too:" : "fails:", paper, dep->remedy,
                    rr.detail);
}

static conf_status check_scene(conf_session *S, const conf_opts *o, const char *path,
                               conf_result *r)
{
    char why[256];
    conf_scene sc;
    if (!conf_scene_open(S, path, 0.0f, &sc))
        return fail_why(r, S);
    if (!cli_caps_cover(S->m, sc.scene, 0, why, sizeof why)) {
        conf_scene_free(&sc);
        return conf_set(r, R_NA, "%s", why);
    }
    gi_image *img = conf_fresh_render(S, &sc, o->size, 1, 1);
    conf_scene_free(&sc);
    if (!img)
        return fail_why(r, S);
    int ok = conf_sane(img, why, sizeof why);
    double mean = conf_measure(img).mean;
    gi_image_free(img);
    return ok ? conf_set(r, R_PASS, "finite, non-negative, mean %.4g", mean)
              : conf_set(r, R_FAIL, "%s", why);
}

static conf_status check_determinism(conf_session *S, const conf_opts *o, conf_result *r)
{
    char path[512];
    conf_scene sc;
    if (!pick_scene(S, path, sizeof path, &sc, r))
        return r->status;
    uint32_t frames = frames_for(S->m, 2);
    gi_image *a = conf_fresh_render(S, &sc, o->size, frames, 7);
    gi_image *b = a ? conf_fresh_render(S, &sc, o->size, frames, 7) : NULL;
    conf_scene_free(&sc);
    if (!a || !b) {
        gi_image_free(a);
        return fail_why(r, S);
    }
    size_t n = (size_t)a->width * a->height, differ = 0;
    for (size_t i = 0; i < n; i++)
        differ += memcmp(&a->rgba[4 * i], &b->rgba[4 * i], 3 * sizeof(float)) != 0;
    double d = conf_rel_diff(b, a);
    gi_image_free(a);
    gi_image_free(b);
    const char *base = strrchr(path, '/') + 1;
    if (differ)
        return conf_set(r, R_FAIL,
                        "%s, seed 7, two fresh instances: %zu of %zu pixels differ (mean relative "
                        "difference %.2g)",
                        base, differ, n, d);
    return conf_set(r, R_PASS, "%s, seed 7, two fresh instances, %u frame(s): bit-identical", base,
                    frames);
}

static conf_status check_resize(conf_session *S, const conf_opts *o, conf_result *r)
{
    char path[512], why[256];
    conf_scene sc, sc2;
    if (!pick_scene(S, path, sizeof path, &sc, r))
        return r->status;
    uint32_t w2 = o->size + 16, h2 = o->size > 16 ? o->size - 8 : o->size,
             frames = frames_for(S->m, 2);
    gi_image *a = NULL, *b = NULL, *c = NULL;
    if (conf_instance_new(S, NULL, 0, &sc)) {
        a = conf_render_frames(S, &sc, 0.0f, o->size, o->size, frames, 0, 0.0f, 3);
        if (a)
            b = conf_render_frames(S, &sc, 0.0f, w2, h2, frames, 0, 0.0f, 3);
        if (b)
            c = conf_render_frames(S, &sc, 0.0f, o->size, o->size, frames, 0, 0.0f, 3);
    }
    if (!c) {
        conf_scene_free(&sc);
        gi_image_free(a);
        gi_image_free(b);
        return fail_why(r, S);
    }
    conf_status st = R_PASS;
    double back = conf_rel_diff(c, a);
    if (!conf_sane(b, why, sizeof why))
        st = conf_set(r, R_FAIL, "at %ux%u: %s", w2, h2, why);
    else if (conf_measure(a).mean > 0 && !(conf_measure(b).mean > 0))
        st = conf_set(r, R_FAIL, "black at %ux%u after %ux%u", w2, h2, o->size, o->size);
    else if (back > 0.01)
        st = conf_set(r, R_FAIL,
                      "back at %ux%u the image differs from the first by %.2g (mean relative)",
                      o->size, o->size, back);
    gi_image_free(a);
    gi_image_free(b);
    gi_image_free(c);
    if (st != R_PASS) {
        conf_scene_free(&sc);
        return st;
    }
    /* A second prepare, on another scene, against a fresh instance there. */
    char path2[512];
    conf_path(path2, sizeof path2, strstr(path, "/area.gltf") ? "area_point.gltf" : "area.gltf");
    if (!conf_scene_open(S, path2, 0.0f, &sc2)) {
        conf_scene_free(&sc);
        return fail_why(r, S);
    }
    if (!cli_caps_cover(S->m, sc2.scene, 0, why,
                        sizeof why)) { /* then prepare the same scene again */
        conf_scene_free(&sc2);
        conf_path(path2, sizeof path2, strrchr(path, '/') + 1);
        if (!conf_scene_open(S, path2, 0.0f, &sc2)) {
            conf_scene_free(&sc);
            return fail_why(r, S);
        }
    }
    gi_result res = S->m->prepare(S->inst, sc2.gs);
    gi_image *d = NULL, *e = NULL;
    if (res != GI_OK)
        conf_method_error(S, "second prepare", res);
    else
        d = conf_render_frames(S, &sc2, 0.0f, o->size, o->size, frames, 0, 0.0f, 3);
    if (d)
        e = conf_fresh_render(S, &sc2, o->size, frames, 3);
    conf_instance_free(S);
    conf_scene_free(&sc);
    conf_scene_free(&sc2);
    if (!e) {
        gi_image_free(d);
        return fail_why(r, S);
    }
    double again = conf_rel_diff(d, e);
    int ok = conf_sane(d, why, sizeof why);
    gi_image_free(d);
    gi_image_free(e);
    if (!ok)
        return conf_set(r, R_FAIL, "after a second prepare: %s", why);
    if (again > 0.01)
        return conf_set(
            r, R_FAIL,
            "after a second prepare (%s) the image differs from a fresh instance's by %.2g",
            strrchr(path2, '/') + 1, again);
    return conf_set(r, R_PASS,
                    "%ux%u -> %ux%u -> back (difference %.2g); second prepare on %s equals a fresh "
                    "instance (%.2g)",
                    o->size, o->size, w2, h2, back, strrchr(path2, '/') + 1, again);
}

/* An update between frames: the image after update() must be closer to a
 * fresh instance's image of the new state than the old image is (at most
 * a tenth of that distance: what the method did not take in shows), and
 * the new state must look different. */
static conf_status check_update(conf_session *S, const conf_opts *o, const char *which,
                                conf_result *r)
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
        return conf_set(r, R_NA, "%s does not claim %s", S->m->id, c);
    }
    conf_scene sc;
    if (!strcmp(which, "vertices"))
        snprintf(path, sizeof path, "%s/cornell_deform.gltf", CONF_SCENES);
    else if (scene_name)
        conf_path(path, sizeof path, scene_name);
    if (!strcmp(which, "camera")) {
        if (!pick_scene(S, path, sizeof path, &sc, r))
            return r->status;
    } else {
        if (!conf_scene_open(S, path, 0.0f, &sc))
            return fail_why(r, S);
        if (!cli_caps_cover(S->m, sc.scene, animated, why, sizeof why)) {
            conf_scene_free(&sc);
            return conf_set(r, R_NA, "%s", why);
        }
    }
    uint32_t frames = frames_for(S->m, 2);
    gi_image *a = NULL, *b = NULL, *c = NULL;
    if (conf_instance_new(S, NULL, 0, &sc)) {
        a = conf_render_frames(S, &sc, 0.0f, o->size, o->size, frames, 0, 0.0f, 5);
        /* frame_index goes on counting: the method must see the change itself */
        if (a && conf_update(S, &sc, flags, t1))
            b = conf_render_frames(S, &sc, t1, o->size, o->size, frames, frames, shift, 5);
    }
    if (b && conf_instance_new(S, NULL, 0, &sc)) /* the scene is at t1 now */
        c = conf_render_frames(S, &sc, t1, o->size, o->size, frames, 0, shift, 5);
    conf_instance_free(S);
    conf_scene_free(&sc);
    if (!c) {
        gi_image_free(a);
        gi_image_free(b);
        return fail_why(r, S);
    }
    double old_d = conf_rel_diff(a, c), new_d = conf_rel_diff(b, c);
    int ok = conf_sane(b, why, sizeof why);
    gi_image_free(a);
    gi_image_free(b);
    gi_image_free(c);
    const char *base = strrchr(path, '/') + 1;
    if (!ok)
        return conf_set(r, R_FAIL, "after update: %s", why);
    if (!(old_d > 0.01))
        return conf_set(r, R_FAIL,
                        "%s: the change does not show (difference %.2g); the check cannot judge",
                        base, old_d);
    if (!(new_d <= 0.1 * old_d))
        return conf_set(
            r, R_FAIL,
            "%s: after update() the image is %.3g from a fresh instance's of the new state "
            "(the old image: %.3g); "
            "limit a tenth",
            base, new_d, old_d);
    return conf_set(r, R_PASS, "%s: after update() %.3g from a fresh instance (the old image %.3g)",
                    base, new_d, old_d);
}

static conf_status check_param(conf_session *S, const conf_opts *o, const char *kv, conf_result *r)
{
    char path[512], why[256];
    conf_scene sc;
    if (!pick_scene_from(S, 1, path, sizeof path, &sc, r))
        return r->status;
    const char *list[1] = {kv};
    gi_image *img = NULL;
    if (conf_instance_new(S, list, 1, &sc))
        img = conf_render_frames(S, &sc, 0.0f, o->size, o->size, frames_for(S->m, 2), 0, 0.0f, 1);
    conf_instance_free(S);
    conf_scene_free(&sc);
    if (!img)
        return fail_why(r, S);
    int ok = conf_sane(img, why, sizeof why);
    gi_image_free(img);
    return ok ? conf_set(r, R_PASS, "%s on %s", kv, strrchr(path, '/') + 1)
              : conf_set(r, R_FAIL, "%s: %s", kv, why);
}

/* The host refuses what the table does not allow; checked on the method's
 * own table: an unknown name, and each parameter just outside its range or
 * with a choice it does not have. */
static conf_status check_unknown(conf_session *S, conf_result *r)
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
        return conf_set(r, R_FAIL, "%u of %u bad settings accepted, e.g. %s", accepted, n, first);
    return conf_set(r, R_PASS,
                    "%u bad settings refused (unknown name, out of range, no such choice)", n);
}

/* A scene lit only by one light type must come out non-black and brighter
 * than the same scene without that light. */
static conf_status check_light(conf_session *S, const conf_opts *o, const char *kind,
                               conf_result *r)
{
    char path[512], dark[512], why[256];
    snprintf(path, sizeof path, "%s/%s.gltf", CONF_DATA, kind);
    conf_path(dark, sizeof dark, "dark.gltf");
    conf_scene sc, sd;
    if (!conf_scene_open(S, path, 0.0f, &sc))
        return fail_why(r, S);
    if (!cli_caps_cover(S->m, sc.scene, 0, why, sizeof why)) {
        conf_scene_free(&sc);
        return conf_set(r, R_NA, "%s", why);
    }
    if (!conf_scene_open(S, dark, 0.0f, &sd)) {
        conf_scene_free(&sc);
        return fail_why(r, S);
    }
    uint32_t frames = frames_for(S->m, 2);
    gi_image *lit = conf_fresh_render(S, &sc, o->size, frames, 1);
    gi_image *unlit = lit ? conf_fresh_render(S, &sd, o->size, frames, 1) : NULL;
    conf_instance_free(S);
    conf_scene_free(&sc);
    conf_scene_free(&sd);
    if (!unlit) {
        gi_image_free(lit);
        return fail_why(r, S);
    }
    int ok = conf_sane(lit, why, sizeof why);
    double ml = conf_measure(lit).mean, md = conf_measure(unlit).mean;
    gi_image_free(lit);
    gi_image_free(unlit);
    if (!ok)
        return conf_set(r, R_FAIL, "%s", why);
    if (!(ml > 1e-3) || !(ml > 2.0 * md + 1e-4))
        return conf_set(
            r, R_FAIL,
            "claims %s light but the scene lit only by it has mean %.3g (without it %.3g)", kind,
            ml, md);
    return conf_set(r, R_PASS, "mean %.4g lit, %.3g without the light", ml, md);
}

conf_status conf_run_item(conf_session *S, const conf_opts *o, const conf_item *it, conf_result *r)
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
    return conf_set(r, R_FAIL, "unknown check %s", it->group);
}
