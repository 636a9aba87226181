/* gibench conformance --held-out, the child's side (docs/conformance.md "The held-out family"):
 * one method on one scene of the family (or one furnace orientation). It renders the method at
 * its defaults, scores it and the trivial answers (black, the `direct` method) against the
 * bounce-matched reference, and raises every quality knob its parameter table marks three steps,
 * printing one line per check that the parent reads back. No code here knows any method: what is
 * checked comes from the descriptor (caps, max_bounces, parameter marks). */
#define _POSIX_C_SOURCE 200809L
#include "conf.h"

#include "metrics.h"
#include "reference.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* Samples per pixel of the reference: at 32^2 to 64^2 on scenes of a few dozen triangles this
 * takes about a second, and its own error (ref_noise below) stays well under the methods'. */
#define HO_REF_SPP 512u
/* A method must score at most this share of the better trivial answer's error. */
#define HO_TRIVIAL_SHARE 0.5

static void result_line(const char *check, conf_status s, double value, double limit,
                        const char *fmt, ...)
{
    char d[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(d, sizeof d, fmt, ap);
    va_end(ap);
    for (char *c = d; *c; c++)
        if (*c == '\n' || *c == '\t')
            *c = ' ';
    printf("HO-RESULT %s %s %.6g %.6g\t%s\n", check, conf_status_name[s], value, limit, d);
    fflush(stdout);
}

static void start_line(const char *check)
{
    printf("HO-START %s\n", check);
    fflush(stdout);
}

/* relMSE of x against ref, the metric `gibench diff` reports. */
static double relmse(const gi_image *x, const gi_image *ref)
{
    gi_metrics_opts mo = {0};
    mo.skip_flip = 1;
    gi_metrics m;
    gi_error err;
    return gi_metrics_compute(x, ref, &mo, &m, &err) == GI_OK ? m.relmse : INFINITY;
}

/* The relMSE the reference's own Monte Carlo error adds in expectation: the mean of its
 * variance over (ref + 0.01)^2, the denominator of relMSE. */
static double ref_noise(const gi_image *ref, const gi_image *var)
{
    size_t n = (size_t)ref->width * ref->height;
    double s = 0.0;
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++) {
            double r = ref->rgba[4 * i + c] + 0.01;
            s += var->rgba[4 * i + c] / (r * r);
        }
    return s / (3.0 * (double)n);
}

static void scene_stem(const char *file, char *out, size_t size)
{
    const char *b = strrchr(file, '/') ? strrchr(file, '/') + 1 : file;
    snprintf(out, size, "%s", b);
    char *dot = strrchr(out, '.');
    if (dot)
        *dot = '\0';
}

/* The reference of scene sc at bounce limit B (GI_REF_UNLIMITED for none) and its variance,
 * cached in DIR/refs/ so that every method of one run shares it. */
static int reference(const char *dir, const char *file, const gi_scene *s, int B, uint32_t size,
                     gi_image **mean, gi_image **var, char *why, size_t wsize)
{
    char stem[256], path[1400], tmp[1500];
    scene_stem(file, stem, sizeof stem);
    snprintf(path, sizeof path, "%s/refs", dir);
    mkdir(path, 0777);
    snprintf(path, sizeof path, "%s/refs/%s_B%d_%u.exr", dir, stem, B, size);
    gi_error err;
    if ((*mean = gi_image_read(path, &err)) && (*var = gi_image_read_layer(path, "variance", &err)))
        return 1;
    gi_image_free(*mean);
    gi_ref_desc d;
    gi_ref_desc_init(&d);
    d.scene = s;
    d.camera = s->camera_count ? 0 : -1;
    d.width = d.height = size;
    d.max_bounces = B;
    d.pixel_center = 1; /* as the methods' G-buffers sample: the comparison measures shading */
    gi_ref *r = NULL;
    if (gi_ref_create(&d, &r, &err) != GI_OK || gi_ref_render(r, HO_REF_SPP, &err) != GI_OK) {
        gi_ref_free(r);
        snprintf(why, wsize, "reference: %s", err.text);
        return 0;
    }
    *mean = gi_ref_mean_image(r);
    *var = gi_ref_variance_image(r);
    gi_ref_free(r);
    const gi_image *layers[1] = {*var};
    const char *names[1] = {"variance"};
    snprintf(tmp, sizeof tmp, "%s.%d.tmp.exr", path, (int)getpid());
    if (gi_image_write_exr_layers(tmp, *mean, layers, names, 1, &err) == GI_OK)
        rename(tmp, path);
    return 1;
}

/* The method's image with parameters kv[0..n) and view seed `seed`. */
static gi_image *render_with(conf_session *S, const conf_scene *sc, const char *const *kv,
                             uint32_t n, uint32_t size, uint32_t seed)
{
    uint32_t frames = (S->m->caps & GI_CAP_PROGRESSIVE) ? 4 : 1;
    if (!conf_instance_new(S, kv, n, sc))
        return NULL;
    gi_image *img = conf_render_frames(S, sc, 0.0f, size, size, frames, 0, 0.0f, seed);
    if (img && !conf_sane(img, S->why, sizeof S->why)) {
        gi_image_free(img);
        return NULL;
    }
    return img;
}

/* relMSE of the method against ref; INFINITY with the reason in S->why when it fails. */
static double score(conf_session *S, const conf_scene *sc, const char *const *kv, uint32_t n,
                    uint32_t size, uint32_t seed, const gi_image *ref)
{
    gi_image *img = render_with(S, sc, kv, n, size, seed);
    if (!img)
        return INFINITY;
    double e = relmse(img, ref);
    gi_image_free(img);
    return e;
}

/* The `direct` method's image of the scene, cached beside the references. */
static gi_image *direct_image(conf_session *S, const char *dir, const char *file,
                              const conf_scene *sc, uint32_t size)
{
    char stem[256], path[1400];
    scene_stem(file, stem, sizeof stem);
    snprintf(path, sizeof path, "%s/refs/%s_direct_%u.exr", dir, stem, size);
    gi_error err;
    gi_image *img = gi_image_read(path, &err);
    if (img)
        return img;
    gi_plugins *reg = cli_load_plugins(1);
    const gi_method *dm = reg ? gi_plugins_find(reg, "direct") : NULL;
    if (!dm) {
        snprintf(S->why, sizeof S->why, "the trivial answer needs the `direct` method plugin");
        gi_plugins_free(reg);
        return NULL;
    }
    conf_session D;
    memset(&D, 0, sizeof D);
    D.m = dm;
    D.gpu = S->gpu;
    img = render_with(&D, sc, NULL, 0, size, 1);
    if (!img)
        snprintf(S->why, sizeof S->why, "direct: %.900s", D.why);
    conf_instance_free(&D);
    if (D.fbo)
        glDeleteFramebuffers(1, &D.fbo);
    if (D.tex)
        glDeleteTextures(1, &D.tex);
    gi_plugins_free(reg);
    if (img && gi_image_write(path, img, NULL, &err) != GI_OK)
        fprintf(stderr, "conformance: warning: %s\n", err.text);
    return img;
}

/* The settings a scene is scored at: the defaults, or the remedy of a declared held_out
 * departure (gi_departure; docs/conformance.md "Declared departures"). */
typedef struct ho_base {
    const gi_departure *dep; /* NULL: the defaults */
    char buf[512];
    const char *kv[16];
    uint32_t n;
} ho_base;

/* Check (a): relMSE <= 1/2 of the better of black and `direct` (direct itself exempt). */
static void check_trivial(conf_session *S, const char *dir, const char *file, const conf_scene *sc,
                          uint32_t size, const gi_image *ref, double e, const char *note)
{
    gi_image *black = gi_image_create(ref->width, ref->height);
    if (!black) {
        result_line("trivial", R_FAIL, e, NAN, "out of memory");
        return;
    }
    for (size_t i = 0; i < (size_t)ref->width * ref->height; i++)
        black->rgba[4 * i + 3] = 1.0f;
    double eb = relmse(black, ref);
    gi_image_free(black);
    gi_image *dimg = direct_image(S, dir, file, sc, size);
    if (!dimg) {
        result_line("trivial", R_FAIL, e, NAN, "set-up failed: %s", S->why);
        return;
    }
    double ed = relmse(dimg, ref);
    gi_image_free(dimg);
    double limit = HO_TRIVIAL_SHARE * fmin(eb, ed);
    if (!strcmp(S->m->id, "direct")) {
        result_line("trivial", R_NA, e, limit,
                    "direct is the trivial answer itself (exempt): relMSE %.4g, black %.4g", e, eb);
        return;
    }
    result_line("trivial", e <= limit ? R_PASS : R_FAIL, e, limit,
                "%srelMSE %.4g, limit %.4g = 1/2 of min(black %.4g, direct %.4g)", note, e, limit,
                eb, ed);
}

/* Check (b): every marked quality knob raised three steps from its default must not raise the
 * error by more than tol, the noise (from seed repeats and the reference's variance). */
static void check_knob(conf_session *S, const conf_scene *sc, uint32_t size, const gi_image *ref,
                       const ho_base *base, const gi_param_desc *d, double e0, double tol)
{
    char check[96], kv[128], text[512] = "";
    snprintf(check, sizeof check, "converge:%s", d->name);
    start_line(check);
    gi_param_quality q;
    if (gi_param_quality_of(d, &q) != 1) {
        result_line(check, R_FAIL, NAN, NAN, "malformed quality mark '%s'", d->choices);
        return;
    }
    if (q.dir == 0) { /* the method says it does not converge in this knob, and why */
        result_line(check, R_NA, NAN, NAN, "does not converge in %s: %s", d->name, q.reason);
        return;
    }
    double worst = e0, prev = d->def;
    int used =
        snprintf(text, sizeof text, "%s%s%s%s %g: %.4g", base->dep ? "at the remedy " : "",
                 base->dep ? base->dep->remedy : "", base->dep ? ", " : "", d->name, d->def, e0);
    for (int k = 1; k <= 3; k++) {
        double v = gi_param_quality_step(d, d->def, k);
        if (v == prev)
            break; /* clamped at the range's end */
        prev = v;
        if (d->type == GI_PARAM_INT)
            snprintf(kv, sizeof kv, "%s=%lld", d->name, (long long)v);
        else
            snprintf(kv, sizeof kv, "%s=%.9g", d->name, v);
        const char *args[17];
        uint32_t na = 0;
        for (uint32_t i = 0; i < base->n; i++) /* the knob's value replaces the remedy's */
            if (strncmp(base->kv[i], d->name, strlen(d->name)) ||
                base->kv[i][strlen(d->name)] != '=')
                args[na++] = base->kv[i];
        args[na++] = kv;
        double e = score(S, sc, args, na, size, 1, ref);
        if (!isfinite(e)) {
            result_line(check, R_FAIL, e, e0 + tol, "%s: %s", kv, S->why);
            return;
        }
        worst = fmax(worst, e);
        if (used > 0 && (size_t)used < sizeof text)
            used += snprintf(text + used, sizeof text - (size_t)used, ", %g: %.4g", v, e);
    }
    result_line(check, worst <= e0 + tol ? R_PASS : R_FAIL, worst, e0 + tol,
                "relMSE %s; the worst may exceed the default's by the noise %.3g", text, tol);
}

static void run_scene(conf_session *S, const conf_opts *o, const char *dir, const char *file)
{
    char path[1400], why[256];
    snprintf(path, sizeof path, "%s/%s", dir, file);
    conf_scene sc;
    start_line("trivial");
    if (!conf_scene_open(S, path, 0.0f, &sc)) {
        result_line("trivial", R_FAIL, NAN, NAN, "%s", S->why);
        return;
    }
    if (!cli_caps_cover(S->m, sc.scene, 0, why, sizeof why)) {
        result_line("trivial", R_NA, NAN, NAN, "%s", why);
        conf_scene_free(&sc);
        return;
    }
    int B = S->m->max_bounces >= 64 ? GI_REF_UNLIMITED : (int)S->m->max_bounces + 1;
    gi_image *ref = NULL, *var = NULL;
    if (!reference(dir, file, sc.scene, B, o->size, &ref, &var, S->why, sizeof S->why)) {
        result_line("trivial", R_FAIL, NAN, NAN, "set-up failed: %s", S->why);
        conf_scene_free(&sc);
        return;
    }
    ho_base base = {gi_method_departure(S->m, "held_out"), "", {NULL}, 0};
    char note[900] = "";
    if (base.dep) { /* scored with the remedy; the paper's defaults reported beside it */
        int n = gi_departure_remedy_args(base.dep, base.buf, sizeof base.buf, base.kv, 16);
        base.n = n > 0 ? (uint32_t)n : 0;
        double e0 = score(S, &sc, NULL, 0, o->size, 1, ref);
        snprintf(note, sizeof note,
                 "declared departure: %s; paper default (reported, not gated) relMSE %.4g; remedy "
                 "%s: ",
                 base.dep->reason, e0, base.dep->remedy);
    }
    double e1 = score(S, &sc, base.kv, base.n, o->size, 1, ref);
    if (!isfinite(e1)) {
        result_line("trivial", R_FAIL, e1, NAN, "%s%s", note, S->why);
    } else {
        check_trivial(S, dir, file, &sc, o->size, ref, e1, note);
        int marked = 0;
        for (const gi_param_desc *d = S->m->params; d && d->name; d++)
            marked += gi_param_quality_of(d, NULL) != 0;
        if (marked && !o->no_converge) {
            /* the noise: a second seed of the method, plus the reference's own */
            double e2 = score(S, &sc, base.kv, base.n, o->size, 2, ref);
            double tol = 2.0 * fabs(e1 - (isfinite(e2) ? e2 : e1)) + ref_noise(ref, var);
            for (const gi_param_desc *d = S->m->params; d && d->name; d++)
                if (gi_param_quality_of(d, NULL) != 0)
                    check_knob(S, &sc, o->size, ref, &base, d, e1, tol);
        }
    }
    gi_image_free(ref);
    gi_image_free(var);
    conf_scene_free(&sc);
}

int conf_held_out_item(const conf_opts *o, const char *dir, const char *file)
{
    gi_plugins *reg = cli_load_plugins(1);
    const gi_method *m = reg ? gi_plugins_find(reg, o->method) : NULL;
    if (!m) {
        gi_plugins_free(reg);
        return cli_fail(EXIT_USAGE, "conformance: no method '%s'", o->method);
    }
    conf_session S;
    memset(&S, 0, sizeof S);
    S.m = m;
    gi_error err;
    const char *check = !strcmp(file, "furnace_in") ? "furnace_in" : "furnace_out";
    if (!(S.gpu = gi_gpu_create(NULL, &err))) {
        start_line(check);
        result_line(check, R_FAIL, NAN, NAN, "%s", err.text);
    } else if (!strcmp(file, "furnace_in") || !strcmp(file, "furnace_out")) {
        /* both orientations of the closed sphere: wound inward single-sided, and wound outward
         * double-sided (back faces lit with reversed normals; tests/data/truth) */
        char path[512];
        if (check[8] == 'i')
            snprintf(path, sizeof path, "%s/furnace_050.gltf", CONF_DATA);
        else
            snprintf(path, sizeof path, "%s/sphere_out_ds.gltf", CONF_TRUTH);
        start_line(check);
        conf_result r = {R_FAIL, ""};
        conf_check_furnace_file(&S, o, path, 0.5, &r);
        result_line(check, r.status, NAN, NAN, "%s", r.detail);
    } else {
        run_scene(&S, o, dir, file);
    }
    conf_instance_free(&S);
    if (S.fbo)
        glDeleteFramebuffers(1, &S.fbo);
    if (S.tex)
        glDeleteTextures(1, &S.tex);
    if (S.gpu)
        gi_gpu_destroy(S.gpu);
    gi_plugins_free(reg);
    return EXIT_OK;
}
