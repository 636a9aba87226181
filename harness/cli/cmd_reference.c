/* gibench reference: the Embree path tracer (harness/reference/) from the
 * command line: progressive passes until --spp, --time or --target-se, then
 * the mean (+ a "variance" layer in EXR) and a stats file. */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"
#include "view_file.h"

#include "reference.h"

#include "gi/timer.h"
#include "gi/image.h"
#include "gi/log.h"
#include "gi/scene.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#define MAX_OUTS 4
#define DEFAULT_SPP 256

typedef struct ref_opts {
    const char *scene, *camera, *stats;
    const char *outs[MAX_OUTS];
    int out_count;
    uint32_t width, height, seed, threads;
    uint64_t spp;         /* 0 = no sample limit */
    double time_limit;    /* seconds; 0 = none */
    double target_se;     /* 0 = none */
    double target_relmse; /* 0 = none */
    int max_bounces;
    float scene_time, exposure;
    gi_ref_strategy strategy;
    int pixel_center;
    int robust_traversal;
} ref_opts;

static int is_exr(const char *path)
{
    const char *dot = strrchr(path, '.');
    return dot && !strcmp(dot, ".exr");
}

/* The options of how the image is rendered and written: --time-of-scene,
 * --exposure, --strategy, --pixel, --traversal. */
static int parse_render_opt(ref_opts *o, const char *a, const char *v)
{
    if (!strcmp(a, "--time-of-scene")) {
        if (!cli_parse_float(v, &o->scene_time) || o->scene_time < 0.0f)
            return cli_fail(EXIT_USAGE,
                            "reference: --time-of-scene '%s' is not a non-negative number", v);
    } else if (!strcmp(a, "--exposure")) {
        if (!cli_parse_exposure(v, &o->exposure))
            return cli_fail(EXIT_USAGE,
                            "reference: --exposure '%s' is not a number of stops in -64..64", v);
    } else if (!strcmp(a, "--strategy")) {
        int s = gi_ref_strategy_parse(v);
        if (s < 0)
            return cli_fail(EXIT_USAGE, "reference: --strategy '%s' is not mis, light or bsdf", v);
        o->strategy = (gi_ref_strategy)s;
    } else if (!strcmp(a, "--pixel")) {
        if (strcmp(v, "box") && strcmp(v, "center"))
            return cli_fail(EXIT_USAGE, "reference: --pixel '%s' is not box or center", v);
        o->pixel_center = !strcmp(v, "center");
    } else if (!strcmp(a, "--traversal")) {
        if (strcmp(v, "fast") && strcmp(v, "robust"))
            return cli_fail(EXIT_USAGE, "reference: --traversal '%s' is not fast or robust", v);
        o->robust_traversal = !strcmp(v, "robust");
    }
    return EXIT_OK;
}

/* One option with its value. */
static int parse_opt(ref_opts *o, const char *a, const char *v)
{
    unsigned long u;
    float f;
    if (!strcmp(a, "--scene"))
        o->scene = v;
    else if (!strcmp(a, "--camera"))
        o->camera = v;
    else if (!strcmp(a, "--stats"))
        o->stats = v;
    else if (!strcmp(a, "--out")) {
        if (cli_add_out("reference", o->outs, &o->out_count, MAX_OUTS, v))
            return EXIT_USAGE;
    } else if (!strcmp(a, "--size")) {
        if (!cli_parse_size(v, &o->width, &o->height))
            return cli_fail(EXIT_USAGE,
                            "reference: --size '%s' is not WxH with " GI_IMAGE_SIZE_RULE, v);
    } else if (!strcmp(a, "--spp")) {
        if (!cli_parse_uint(v, 1, 0xFFFFFFFFul, &u))
            return cli_fail(EXIT_USAGE, "reference: --spp '%s' is not an integer in 1..4294967295",
                            v);
        o->spp = u;
    } else if (!strcmp(a, "--time")) {
        if (!cli_parse_float(v, &f) || !(f > 0.0f))
            return cli_fail(EXIT_USAGE,
                            "reference: --time '%s' is not a positive number of seconds", v);
        o->time_limit = f;
    } else if (!strcmp(a, "--target-se")) {
        if (!cli_parse_float(v, &f) || !(f > 0.0f))
            return cli_fail(EXIT_USAGE, "reference: --target-se '%s' is not a positive number", v);
        o->target_se = f;
    } else if (!strcmp(a, "--target-relmse")) {
        if (!cli_parse_float(v, &f) || !(f > 0.0f))
            return cli_fail(EXIT_USAGE, "reference: --target-relmse '%s' is not a positive number",
                            v);
        o->target_relmse = f;
    } else if (!strcmp(a, "--max-bounces")) {
        if (!strcmp(v, "inf") || !strcmp(v, "unlimited") || !strcmp(v, "-1"))
            o->max_bounces = GI_REF_UNLIMITED;
        else if (cli_parse_uint(v, 0, 1000000, &u))
            o->max_bounces = (int)u;
        else
            return cli_fail(EXIT_USAGE, "reference: --max-bounces '%s' is not 0..1000000 or 'inf'",
                            v);
    } else if (!strcmp(a, "--seed")) {
        if (!cli_parse_uint(v, 0, 0xFFFFFFFFul, &u))
            return cli_fail(EXIT_USAGE, "reference: --seed '%s' is not a 32-bit unsigned integer",
                            v);
        o->seed = (uint32_t)u;
    } else if (!strcmp(a, "--threads")) {
        if (!cli_parse_uint(v, 0, 1024, &u))
            return cli_fail(EXIT_USAGE, "reference: --threads '%s' is not an integer in 0..1024",
                            v);
        o->threads = (uint32_t)u;
    } else {
        return parse_render_opt(o, a, v);
    }
    return EXIT_OK;
}

static int parse_opts(int argc, char **argv, ref_opts *o)
{
    static const char *valued[] = {
        "--scene",     "--camera",       "--size",     "--spp",      "--time",
        "--target-se", "--max-bounces",  "--seed",     "--threads",  "--time-of-scene",
        "--out",       "--stats",        "--exposure", "--strategy", "--pixel",
        "--traversal", "--target-relmse"};
    memset(o, 0, sizeof *o);
    o->width = o->height = 256;
    o->seed = 1;
    o->max_bounces = GI_REF_UNLIMITED;
    o->strategy = GI_REF_STRATEGY_MIS;
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i];
        int known = 0;
        for (size_t k = 0; k < sizeof valued / sizeof valued[0]; k++)
            known |= !strcmp(a, valued[k]);
        if (!known)
            return cli_fail(EXIT_USAGE, "reference: unknown argument '%s' (see gibench --help)", a);
        const char *v = i + 1 < argc ? argv[++i] : NULL;
        if (!v)
            return cli_fail(EXIT_USAGE, "reference: %s needs a value", a);
        int rc = parse_opt(o, a, v);
        if (rc != EXIT_OK)
            return rc;
    }
    if (!o->scene)
        return cli_fail(EXIT_USAGE, "reference: --scene is required");
    if (o->out_count == 0)
        return cli_fail(EXIT_USAGE, "reference: --out is required");
    if (o->spp == 0 && o->time_limit == 0.0 && o->target_se == 0.0 && o->target_relmse == 0.0)
        o->spp = DEFAULT_SPP;
    return EXIT_OK;
}

/* ---- progress -------------------------------------------------------- */

typedef struct progress {
    int on;
} progress;

/* se: the latest --target-se statistic, measured at se_spp samples. */
static void progress_show(const progress *p, const ref_opts *o, uint64_t spp, double se,
                          uint64_t se_spp, double elapsed)
{
    if (!p->on)
        return;
    double frac = 0.0;
    if (o->spp)
        frac = fmax(frac, (double)spp / (double)o->spp);
    if (o->time_limit > 0.0)
        frac = fmax(frac, elapsed / o->time_limit);
    if (o->target_se > 0.0 && isfinite(se) && se > 0.0) /* SE ~ 1/sqrt(spp) */
        frac =
            fmax(frac, (double)spp / ((double)se_spp * (se / o->target_se) * (se / o->target_se)));
    frac = fmin(frac, 1.0);
    char bar[31];
    int filled = (int)(frac * 30.0);
    for (int i = 0; i < 30; i++)
        bar[i] = i < filled ? '#' : '.';
    bar[30] = '\0';
    char el[32], eta[32] = "?";
    cli_format_duration(elapsed, el, sizeof el);
    if (frac > 0)
        cli_format_duration(elapsed * (1.0 - frac) / frac, eta, sizeof eta);
    fprintf(stderr, "\rreference [%s] %3d%%  %llu spp  %s elapsed, ETA %s  SE %.4g\033[K", bar,
            (int)(frac * 100.0), (unsigned long long)spp, el, eta, se);
    fflush(stderr);
}

static void progress_end(const progress *p)
{
    if (p->on)
        fputc('\n', stderr);
}

/* ---- run --------------------------------------------------------------- */

typedef struct run_state {
    gi_scene *scene;
    gi_ref *ref;
    gi_image *mean, *var;
} run_state;

static json_object *stats_json(const run_state *r, const ref_opts *o, int camera, double wall,
                               const char *stop)
{
    gi_ref_stats st;
    gi_ref_get_stats(r->ref, &st);
    json_object *j = json_object_new_object();
    json_object_object_add(j, "renderer", json_object_new_string(gi_ref_renderer(r->ref)));
    json_object_object_add(j, "scene", json_object_new_string(o->scene));
    char cam[32];
    snprintf(cam, sizeof cam, camera < 0 ? "default" : "#%d", camera);
    json_object_object_add(j, "camera", json_object_new_string(o->camera ? o->camera : cam));
    json_object_object_add(j, "width", json_object_new_int((int32_t)o->width));
    json_object_object_add(j, "height", json_object_new_int((int32_t)o->height));
    json_object_object_add(j, "time_of_scene", json_object_new_double(o->scene_time));
    json_object_object_add(j, "spp", json_object_new_int64((int64_t)st.spp));
    json_object_object_add(j, "seed", json_object_new_int64(o->seed));
    json_object_object_add(j, "max_bounces",
                           json_object_new_int(o->max_bounces)); /* -1 = unlimited */
    json_object_object_add(j, "strategy",
                           json_object_new_string(gi_ref_strategy_name(o->strategy)));
    json_object_object_add(j, "pixel", json_object_new_string(o->pixel_center ? "center" : "box"));
    json_object_object_add(j, "traversal",
                           json_object_new_string(o->robust_traversal ? "robust" : "fast"));
    json_object_object_add(j, "threads", json_object_new_int((int32_t)st.threads));
    json_object_object_add(j, "stop", json_object_new_string(stop));
    json_object_object_add(j, "wall_seconds", json_object_new_double(wall));
    json_object_object_add(j, "build_seconds", json_object_new_double(st.build_seconds));
    json_object_object_add(j, "render_seconds", json_object_new_double(st.render_seconds));
    json_object_object_add(j, "render_cpu_seconds", json_object_new_double(st.render_cpu_seconds));
    json_object_object_add(j, "rays", json_object_new_int64((int64_t)st.rays));
    json_object_object_add(j, "mrays_per_second",
                           json_object_new_double(st.render_seconds > 0
                                                      ? 1e-6 * (double)st.rays / st.render_seconds
                                                      : 0.0));
    json_object_object_add(j, "nonfinite_samples", json_object_new_int64((int64_t)st.nonfinite));
    /* Mean over pixels of the standard error of the mean luminance, absolute
     * and relative (the --target-se statistic, docs/commands.md "gibench reference"). */
    size_t n = (size_t)o->width * o->height;
    double se_sum = 0.0;
    for (size_t i = 0; i < n; i++)
        se_sum += sqrt((double)r->var->rgba[4 * i + 3]);
    json_object_object_add(j, "mean_se", json_object_new_double(se_sum / (double)n));
    double rel = gi_ref_mean_rel_se(r->ref);
    json_object_object_add(j, "mean_rel_se", isfinite(rel) ? json_object_new_double(rel) : NULL);
    double rm = gi_ref_mean_relmse(r->ref);
    json_object_object_add(j, "relmse_estimate", isfinite(rm) ? json_object_new_double(rm) : NULL);
    double mean[4];
    gi_image_mean(r->mean, mean);
    json_object *mj = json_object_new_array();
    for (int c = 0; c < 3; c++)
        json_object_array_add(mj, json_object_new_double(mean[c]));
    json_object_object_add(j, "mean_rgb", mj);
    return j;
}

/* The camera: a saved view's (--camera view:FILE.json: its camera, its
 * moved objects and lights placed; *has_view and *view_cf), the scene's
 * camera of --camera, or -1 when the scene has none. */
static int find_camera(run_state *r, const ref_opts *o, int *camera, int *has_view,
                       gi_camera_frame *view_cf)
{
    *camera = 0;
    view_file view;
    char why[600];
    *has_view = view_camera_read(o->camera, &view, why, sizeof why);
    if (*has_view < 0)
        return cli_fail(EXIT_USAGE, "reference: --camera %s", why);
    if (*has_view) {
        int ok = view_file_check_nodes(&view, r->scene, why, sizeof why);
        if (ok)
            view_file_apply_nodes(&view, r->scene);
        *view_cf = view_file_camera(&view);
        view_file_free(&view);
        if (!ok)
            return cli_fail(EXIT_USAGE, "reference: --camera %s: %s", o->camera, why);
    } else if (o->camera) {
        *camera = gi_scene_find_camera(r->scene, o->camera);
        if (*camera < 0)
            return cli_fail(EXIT_USAGE,
                            "reference: %s has no camera '%s' (%u cameras; use a name or #k)",
                            o->scene, o->camera, r->scene->camera_count);
    } else if (r->scene->camera_count == 0) {
        *camera = -1;
    }
    return EXIT_OK;
}

/* The path tracer of the options; view_cf: a saved view's camera, or NULL. */
static int create_tracer(run_state *r, const ref_opts *o, int camera,
                         const gi_camera_frame *view_cf)
{
    gi_error err;
    gi_ref_desc d;
    gi_ref_desc_init(&d);
    d.scene = r->scene;
    d.camera = camera;
    if (view_cf)
        d.camera_frame = view_cf;
    d.time = o->scene_time;
    d.width = o->width;
    d.height = o->height;
    d.seed = o->seed;
    d.max_bounces = o->max_bounces;
    d.threads = o->threads;
    d.strategy = o->strategy;
    d.pixel_center = o->pixel_center;
    d.robust_traversal = o->robust_traversal;
    gi_result res = gi_ref_create(&d, &r->ref, &err);
    if (res != GI_OK)
        return cli_fail(res == GI_ERR_INVALID_ARGUMENT ? EXIT_USAGE : EXIT_RUN, "%s", err.text);
    return EXIT_OK;
}

/* The progress line after a pass; a pending interrupt cancels. */
typedef struct pass_state {
    progress bar;
    const ref_opts *o;
    double every, last_line; /* GIBENCH_PROGRESS_EVERY: a plain line every `every` s */
} pass_state;

/* A plain progress line for a caller that reads the log (gibench study). */
static void progress_line(pass_state *ps, uint64_t spp, double elapsed)
{
    fprintf(stderr, "reference: %llu/%llu spp, %.1f s\n", (unsigned long long)spp,
            (unsigned long long)ps->o->spp, elapsed);
    ps->last_line = elapsed;
}

static int after_pass(void *user, uint64_t spp, double se, uint64_t se_spp, double elapsed)
{
    pass_state *ps = user;
    if (cli_interrupted)
        return 1;
    if (ps->bar.on)
        progress_show(&ps->bar, ps->o, spp, se, se_spp, elapsed);
    if (ps->every > 0.0 && elapsed - ps->last_line >= ps->every)
        progress_line(ps, spp, elapsed);
    return 0;
}

/* Progressive passes until --spp, --time, --target-se or --target-relmse says stop; *stop
 * names which. */
static int render_passes(run_state *r, const ref_opts *o, const char **stop)
{
    gi_error err;
    pass_state ps = {{isatty(STDERR_FILENO) && gi_log_get_level() >= GI_LOG_WARN}, o, 0.0, 0.0};
    /* a caller that reads the log (gibench study) asks for a plain line
     * every S seconds instead of the terminal's bar */
    const char *every_env = getenv("GIBENCH_PROGRESS_EVERY");
    ps.every = every_env && !ps.bar.on ? atof(every_env) : 0.0;
    const double t_render = gi_now();
    gi_ref_until u = {o->spp, o->time_limit, o->target_se, o->target_relmse};
    gi_result res = gi_ref_progressive(r->ref, &u, after_pass, &ps, stop, &err);
    progress_end(&ps.bar);
    if (res == GI_OK && ps.every > 0.0)
        progress_line(&ps, gi_ref_spp(r->ref), gi_now() - t_render);
    if (res == GI_ERR_CANCELLED)
        return cli_fail(EXIT_RUN, "reference: interrupted after %llu spp; no image written",
                        (unsigned long long)gi_ref_spp(r->ref));
    if (res != GI_OK)
        return cli_fail(EXIT_RUN, "%s", err.text);
    return EXIT_OK;
}

/* The mean into every --out (EXR with a "variance" layer). */
static int write_images(run_state *r, const ref_opts *o)
{
    gi_error err;
    gi_result res;
    r->mean = gi_ref_mean_image(r->ref);
    r->var = gi_ref_variance_image(r->ref);
    if (!r->mean || !r->var)
        return cli_fail(EXIT_RUN, "out of memory reading the image");
    for (int i = 0; i < o->out_count; i++) {
        if (is_exr(o->outs[i])) {
            const gi_image *layers[1] = {r->var};
            const char *names[1] = {"variance"};
            res = gi_image_write_exr_layers(o->outs[i], r->mean, layers, names, 1, &err);
        } else {
            gi_image_write_opts wo = {o->exposure};
            res = gi_image_write(o->outs[i], r->mean, &wo, &err);
        }
        if (res != GI_OK)
            return cli_fail(EXIT_RUN, "%s", err.text);
    }
    return EXIT_OK;
}

static int run(run_state *r, const ref_opts *o)
{
    double t_start = gi_now();
    gi_error err;
    r->scene = gi_scene_load(o->scene, &err);
    if (!r->scene)
        return cli_fail(EXIT_USAGE, "%s", err.text);
    int camera, has_view;
    gi_camera_frame view_cf;
    const char *stop = NULL;
    int rc = find_camera(r, o, &camera, &has_view, &view_cf);
    if (rc == EXIT_OK)
        rc = create_tracer(r, o, camera, has_view ? &view_cf : NULL);
    if (rc == EXIT_OK)
        rc = render_passes(r, o, &stop);
    if (rc == EXIT_OK)
        rc = write_images(r, o);
    if (rc != EXIT_OK)
        return rc;
    gi_ref_stats st;
    gi_ref_get_stats(r->ref, &st);
    if (st.nonfinite)
        gi_log(GI_LOG_WARN, "reference: %llu NaN/Inf samples were discarded",
               (unsigned long long)st.nonfinite);
    gi_log(GI_LOG_INFO, "reference: %llu spp in %.2f s (%s), %.2f Mrays/s, mean relative SE %.4g",
           (unsigned long long)st.spp, st.render_seconds, stop,
           st.render_seconds > 0 ? 1e-6 * (double)st.rays / st.render_seconds : 0.0,
           gi_ref_mean_rel_se(r->ref));
    return o->stats ? cli_save_json(o->stats, stats_json(r, o, camera, gi_now() - t_start, stop))
                    : EXIT_OK;
}

int cmd_reference(int argc, char **argv)
{
    ref_opts o;
    int rc = parse_opts(argc, argv, &o);
    if (rc != EXIT_OK)
        return rc;
    cli_install_signal_handlers();
    run_state r;
    memset(&r, 0, sizeof r);
    rc = run(&r, &o);
    gi_image_free(r.mean);
    gi_image_free(r.var);
    gi_ref_free(r.ref);
    gi_scene_free(r.scene);
    return rc;
}
