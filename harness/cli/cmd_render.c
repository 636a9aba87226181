/* gibench render: one method, one scene, one camera -> image + timings. */
#include "cli.h"

#include "debug_buffer.h"
#include "gi/cache.h"
#include "gi/image.h"
#include "gi/log.h"
#include "gi/passes.h"
#include "metrics.h"
#include "render_loop.h"
#include "view_file.h"

#include <math.h>
#include <stdio.h>
#include <sys/resource.h>
#include <stdlib.h>
#include <string.h>

#define MAX_PARAMS 64
#define MAX_OUTS 4
#define MAX_CURVE_REFS 4
#define MAX_CURVE_POINTS 64
#define MAX_BUFFERS 16

typedef struct render_opts {
    const char *scene, *method, *camera, *timings;
    const char *outs[MAX_OUTS];
    int out_count;
    const char *params[MAX_PARAMS];
    uint32_t param_count;
    uint32_t width, height, frames, warmup, seed;
    float time, animate_fps, exposure;
    int no_cache; /* --no-cache: precompute afresh and keep nothing (timing studies) */
    /* --curve-ref NAME=PATH: the image's error against PATH after frames
     * 1, 2, 4, 8, ... (every frame up to 16), in the timings as "curve" */
    const char *curve_name[MAX_CURVE_REFS], *curve_path[MAX_CURVE_REFS];
    int curve_ref_count;
    /* --view FILE: a saved view of gibench view (camera, time, method,
     * parameters, size, frames, seed, exposure); options given beside it win */
    const char *view_path;
    /* --frames-out PATTERN: every frame's linear image, PATTERN with one %d */
    const char *frames_out;
    /* --buffer NAME[,NAME...] (repeatable): the method's debug buffers
     * instead of the image (one: into each --out; several: each --out with
     * .NAME before its extension) */
    char buffers[MAX_BUFFERS][32];
    int buffer_count;
    int has_view;
    view_file view;
    int given_size, given_frames, given_seed, given_time, given_exposure;
} render_opts;

/* --view FILE: what the saved view says, except what the command line gives. */
static int apply_view(render_opts *o)
{
    char why[600];
    if (o->camera)
        return cli_fail(EXIT_USAGE, "render: --camera and --view both name a camera; give one");
    if (!view_file_read(o->view_path, &o->view, why, sizeof why))
        return cli_fail(EXIT_USAGE, "render: --view %s", why);
    o->has_view = 1;
    const view_file *v = &o->view;
    if (!o->method && !strcmp(v->method, "reference"))
        return cli_fail(EXIT_USAGE,
                        "render: the view %s shows the path-traced reference; give --method M (or "
                        "use gibench reference)",
                        o->view_path);
    if (!o->scene)
        o->scene = v->scene;
    if (!o->method) {
        o->method = v->method;
        /* the view's parameters belong to its method */
        if (o->param_count == 0)
            for (uint32_t i = 0; i < v->param_count; i++)
                o->params[o->param_count++] = v->params[i];
    }
    if (!o->given_size) {
        o->width = v->width;
        o->height = v->height;
    }
    if (!o->given_frames)
        o->frames = v->frames;
    if (!o->given_seed)
        o->seed = v->seed;
    if (!o->given_time)
        o->time = v->time;
    if (!o->given_exposure)
        o->exposure = v->exposure;
    return EXIT_OK;
}

/* Whether option `a` takes a value (every option but --no-cache does). */
static int takes_value(const char *a)
{
    return !strcmp(a, "--scene") || !strcmp(a, "--method") || !strcmp(a, "--camera") ||
           !strcmp(a, "--out") || !strcmp(a, "--size") || !strcmp(a, "--param") ||
           !strcmp(a, "--frames") || !strcmp(a, "--warmup") || !strcmp(a, "--time") ||
           !strcmp(a, "--animate") || !strcmp(a, "--seed") || !strcmp(a, "--exposure") ||
           !strcmp(a, "--timings") || !strcmp(a, "--curve-ref") || !strcmp(a, "--view") ||
           !strcmp(a, "--frames-out") || !strcmp(a, "--buffer");
}

/* --frames-out PATTERN: one %d for the frame index and an image file's extension. */
static int parse_frames_out(render_opts *o, const char *v)
{
    char probe[4096];
    if (!cli_frame_path(v, 0, probe, sizeof probe))
        return cli_fail(EXIT_USAGE,
                        "render: --frames-out '%s' needs exactly one %%d (or %%0Nd) for "
                        "the frame index "
                        "(%%%% for a percent sign)",
                        v);
    size_t pl = strlen(probe);
    if (pl < 5 || (strcmp(probe + pl - 4, ".exr") && strcmp(probe + pl - 4, ".pfm") &&
                   strcmp(probe + pl - 4, ".png")))
        return cli_fail(EXIT_USAGE, "render: --frames-out '%s' must end in .exr, .pfm or .png", v);
    o->frames_out = v;
    return EXIT_OK;
}

/* --buffer NAME[,NAME...]: names are checked against the method later. */
static int parse_buffer(render_opts *o, const char *v)
{
    for (const char *p = v;; p++) {
        const char *end = strchr(p, ',');
        size_t n = end ? (size_t)(end - p) : strlen(p);
        if (n == 0 || n > 31)
            return cli_fail(EXIT_USAGE,
                            "render: --buffer '%s' is not NAME[,NAME...] (names of 1..31 "
                            "characters; gibench methods lists them)",
                            v);
        if (o->buffer_count == MAX_BUFFERS)
            return cli_fail(EXIT_USAGE, "render: at most %d --buffer names", MAX_BUFFERS);
        snprintf(o->buffers[o->buffer_count++], sizeof o->buffers[0], "%.*s", (int)n, p);
        if (!end)
            return EXIT_OK;
        p = end;
    }
}

/* --curve-ref NAME=PATH */
static int parse_curve_ref(render_opts *o, const char *v)
{
    const char *eq = strchr(v, '=');
    if (!eq || eq == v || !eq[1] || eq - v > 31)
        return cli_fail(EXIT_USAGE,
                        "render: --curve-ref '%s' is not NAME=IMAGE (a name of 1..31 characters)",
                        v);
    if (o->curve_ref_count == MAX_CURVE_REFS)
        return cli_fail(EXIT_USAGE, "render: at most %d --curve-ref", MAX_CURVE_REFS);
    o->curve_name[o->curve_ref_count] = v;
    o->curve_path[o->curve_ref_count++] = eq + 1;
    return EXIT_OK;
}

/* The options with a number: --frames, --warmup, --seed, --time, --animate, --exposure. */
static int parse_number_opt(render_opts *o, const char *a, const char *v)
{
    unsigned long u;
    if (!strcmp(a, "--frames")) {
        if (!cli_parse_uint(v, 1, 1000000, &u))
            return cli_fail(EXIT_USAGE, "render: --frames '%s' is not an integer in 1..1000000", v);
        o->frames = (uint32_t)u;
        o->given_frames = 1;
    } else if (!strcmp(a, "--warmup")) {
        if (!cli_parse_uint(v, 0, 1000, &u))
            return cli_fail(EXIT_USAGE, "render: --warmup '%s' is not an integer in 0..1000", v);
        o->warmup = (uint32_t)u;
    } else if (!strcmp(a, "--seed")) {
        if (!cli_parse_uint(v, 0, 0xFFFFFFFFul, &u))
            return cli_fail(EXIT_USAGE, "render: --seed '%s' is not a 32-bit unsigned integer", v);
        o->seed = (uint32_t)u;
        o->given_seed = 1;
    } else if (!strcmp(a, "--time")) {
        if (!cli_parse_float(v, &o->time) || o->time < 0)
            return cli_fail(EXIT_USAGE, "render: --time '%s' is not a non-negative number", v);
        o->given_time = 1;
    } else if (!strcmp(a, "--animate")) {
        if (!cli_parse_float(v, &o->animate_fps) || o->animate_fps <= 0)
            return cli_fail(EXIT_USAGE, "render: --animate '%s' is not a positive frame rate", v);
    } else if (!strcmp(a, "--exposure")) {
        if (!cli_parse_exposure(v, &o->exposure))
            return cli_fail(EXIT_USAGE,
                            "render: --exposure '%s' is not a number of stops in -64..64", v);
        o->given_exposure = 1;
    }
    return EXIT_OK;
}

/* One option with its value. */
static int parse_opt(render_opts *o, const char *a, const char *v)
{
    if (!strcmp(a, "--scene"))
        o->scene = v;
    else if (!strcmp(a, "--method"))
        o->method = v;
    else if (!strcmp(a, "--camera"))
        o->camera = v;
    else if (!strcmp(a, "--timings"))
        o->timings = v;
    else if (!strcmp(a, "--view"))
        o->view_path = v;
    else if (!strcmp(a, "--frames-out"))
        return parse_frames_out(o, v);
    else if (!strcmp(a, "--curve-ref"))
        return parse_curve_ref(o, v);
    else if (!strcmp(a, "--buffer"))
        return parse_buffer(o, v);
    else if (!strcmp(a, "--out")) {
        if (cli_add_out("render", o->outs, &o->out_count, MAX_OUTS, v))
            return EXIT_USAGE;
    } else if (!strcmp(a, "--size")) {
        if (!cli_parse_size(v, &o->width, &o->height))
            return cli_fail(EXIT_USAGE, "render: --size '%s' is not WxH with " GI_IMAGE_SIZE_RULE,
                            v);
        o->given_size = 1;
    } else if (!strcmp(a, "--param")) {
        if (o->param_count == MAX_PARAMS)
            return cli_fail(EXIT_USAGE, "render: at most %d --param", MAX_PARAMS);
        o->params[o->param_count++] = v;
    } else {
        return parse_number_opt(o, a, v);
    }
    return EXIT_OK;
}

/* After the options: the saved view (--view, or --camera view:FILE.json)
 * and what is required. */
static int finish_opts(render_opts *o)
{
    if (o->view_path) {
        int rc = apply_view(o);
        if (rc != EXIT_OK)
            return rc;
    } else {
        /* --camera view:FILE.json: the saved view's camera and moved objects only */
        char why[600];
        int got = view_camera_read(o->camera, &o->view, why, sizeof why);
        if (got < 0)
            return cli_fail(EXIT_USAGE, "render: --camera %s", why);
        o->has_view = got;
    }
    if (!o->scene)
        return cli_fail(EXIT_USAGE, "render: --scene is required");
    if (!o->method)
        return cli_fail(EXIT_USAGE, "render: --method is required (see gibench methods)");
    if (o->out_count == 0)
        return cli_fail(EXIT_USAGE, "render: --out is required");
    if (o->warmup >= o->frames && o->frames > 1)
        return cli_fail(EXIT_USAGE, "render: --warmup %u leaves no timed frame of %u", o->warmup,
                        o->frames);
    return EXIT_OK;
}

static int parse_opts(int argc, char **argv, render_opts *o)
{
    memset(o, 0, sizeof *o);
    o->width = o->height = 256;
    o->frames = 1;
    o->seed = 1;
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--no-cache")) {
            o->no_cache = 1;
            continue;
        }
        if (takes_value(a)) {
            if (!v)
                return cli_fail(EXIT_USAGE, "render: %s needs a value", a);
            i++;
        } else {
            return cli_fail(EXIT_USAGE, "render: unknown argument '%s' (see gibench --help)", a);
        }
        int rc = parse_opt(o, a, v);
        if (rc != EXIT_OK)
            return rc;
    }
    return finish_opts(o);
}

/* The process's peak resident memory so far, in MiB: VmHWM of
 * /proc/self/status, the high-water mark of this program's own memory map.
 * (getrusage's ru_maxrss would do elsewhere, but on Linux it also keeps the
 * peak of the process image replaced by exec, here the study or compare
 * process that forked this render.) On llvmpipe the GPU's buffers and
 * textures are process memory and count; on a hardware GPU they do not. */
static double peak_rss_mib(void)
{
    FILE *f = fopen("/proc/self/status", "r");
    char line[256];
    double kib = NAN;
    while (f && fgets(line, sizeof line, f))
        if (!strncmp(line, "VmHWM:", 6)) {
            kib = strtod(line + 6, NULL);
            break;
        }
    if (f)
        fclose(f);
    if (!isfinite(kib)) {
        struct rusage ru;
        if (getrusage(RUSAGE_SELF, &ru) == 0)
            kib = (double)ru.ru_maxrss;
    }
    return kib / 1024.0;
}

typedef struct run_state {
    gi_scene *scene;
    gi_gpu *gpu;
    gi_gpu_scene *gs;
    gi_plugins *reg;
    gi_params *params;
    char *cache_dir;
    cli_host host;
    int host_ready;
    const gi_method *m;
    gi_timer *prep_timer, *render_timer;
    render_loop loop; /* the instance and its target (render_loop.h) */
    gi_camera_frame view_camera;
    gi_image *image;
    gi_image *curve_ref[MAX_CURVE_REFS];
    uint32_t curve_frame[MAX_CURVE_POINTS]; /* 1-based frame after which the error was taken */
    gi_metrics curve_m[MAX_CURVE_POINTS][MAX_CURVE_REFS];
    uint32_t curve_n;
    double rss_prepare_mib; /* peak resident memory once prepare() returned */
} run_state;

static void cleanup(run_state *r)
{
    render_loop_free(&r->loop);
    gi_timer_free(r->prep_timer);
    gi_timer_free(r->render_timer);
    gi_gpu_scene_free(r->gs);
    gi_gpu_destroy(r->gpu);
    gi_scene_free(r->scene);
    gi_params_free(r->params);
    gi_plugins_free(r->reg);
    gi_image_free(r->image);
    for (int i = 0; i < MAX_CURVE_REFS; i++)
        gi_image_free(r->curve_ref[i]);
    if (r->host_ready)
        cli_host_free(&r->host);
    free(r->cache_dir);
}

/* Reports a failure of the render loop with its one-line message: bad
 * usage for invalid arguments and what the method cannot do. */
static int loop_fail(run_state *r, gi_result res, const gi_error *err)
{
    if (r->host_ready)
        cli_host_progress_end(&r->host);
    return cli_fail(res == GI_ERR_INVALID_ARGUMENT || res == GI_ERR_UNSUPPORTED ? EXIT_USAGE
                                                                                : EXIT_RUN,
                    "%s", err->text);
}

/* Whether the error is recorded after 1-based frame k of n: every frame of
 * short runs, else 1, 2, 4, 8, ... and the last. */
static int curve_frame_wanted(uint32_t k, uint32_t n)
{
    return n <= 16 || (k & (k - 1)) == 0 || k == n;
}

/* The convergence curve: per recorded frame, the time to that image (the
 * sum of the frame times so far; a warm-up frame, whose time is not kept,
 * is charged the median of the timed frames) and the error against each
 * --curve-ref. */
static json_object *curve_json(const run_state *r, const render_opts *o)
{
    uint32_t n_ms = 0;
    const double *ms = gi_timer_samples(r->render_timer, "frame", &n_ms);
    gi_stage_stats st[GI_TIMER_MAX_STAGES + 1];
    uint32_t ns = gi_timer_stats(r->render_timer, st, GI_TIMER_MAX_STAGES + 1);
    double median = NAN;
    for (uint32_t i = 0; i < ns; i++)
        if (!strcmp(st[i].name, "frame"))
            median = st[i].median_ms;
    json_object *arr = json_object_new_array();
    double total = 0;
    uint32_t next = 0;
    for (uint32_t k = 1; k <= o->frames && next < r->curve_n; k++) {
        uint32_t timed = k > o->warmup ? k - o->warmup - 1 : UINT32_MAX;
        total += timed < n_ms && ms ? ms[timed] : median;
        if (r->curve_frame[next] != k)
            continue;
        json_object *p = json_object_new_object();
        json_object_object_add(p, "frame", json_object_new_int((int32_t)k));
        json_object_object_add(p, "time_ms", json_object_new_double(total));
        for (int c = 0; c < o->curve_ref_count; c++) {
            const gi_metrics *m = &r->curve_m[next][c];
            json_object *mj = json_object_new_object();
            json_object_object_add(mj, "relmse", json_object_new_double(m->relmse));
            json_object_object_add(mj, "rmse", json_object_new_double(m->rmse));
            json_object_object_add(mj, "mae", json_object_new_double(m->mae));
            json_object_object_add(mj, "mean_lum_diff_pct",
                                   json_object_new_double(m->mean_lum_diff_pct));
            char name[32];
            snprintf(name, sizeof name, "%.*s",
                     (int)(strchr(o->curve_name[c], '=') - o->curve_name[c]), o->curve_name[c]);
            json_object_object_add(p, name, mj);
        }
        json_object_array_add(arr, p);
        next++;
    }
    return arr;
}

/* Reads the image back after 1-based frame k and records its error
 * against every --curve-ref (outside the timed frame). */
static int record_curve_point(run_state *r, const render_opts *o, uint32_t k)
{
    if (o->curve_ref_count == 0 || !curve_frame_wanted(k, o->frames) ||
        r->curve_n == MAX_CURVE_POINTS)
        return EXIT_OK;
    gi_image *img = gi_gpu_read_texture(r->loop.target_tex, o->width, o->height);
    if (!img)
        return cli_fail(EXIT_RUN, "out of memory reading the image back");
    gi_metrics_opts mo = {o->exposure, 0, 1, 0};
    for (int c = 0; c < o->curve_ref_count; c++) {
        gi_error err;
        if (gi_metrics_compute(img, r->curve_ref[c], &mo, &r->curve_m[r->curve_n][c], &err) !=
            GI_OK) {
            gi_image_free(img);
            return cli_fail(EXIT_RUN, "render: error against %s: %s", o->curve_path[c], err.text);
        }
    }
    gi_image_free(img);
    r->curve_frame[r->curve_n++] = k;
    return EXIT_OK;
}

/* --frames-out: frame f (from 0) read back and written as linear radiance
 * (alpha 1), outside the timed frame. */
static int write_frame(run_state *r, const render_opts *o, uint32_t f)
{
    if (!o->frames_out)
        return EXIT_OK;
    char path[4096];
    if (!cli_frame_path(o->frames_out, f, path, sizeof path))
        return cli_fail(EXIT_USAGE, "render: --frames-out '%s': bad pattern", o->frames_out);
    gi_image *img = gi_gpu_read_texture(r->loop.target_tex, o->width, o->height);
    if (!img)
        return cli_fail(EXIT_RUN, "out of memory reading frame %u back", f);
    for (size_t i = 0; i < (size_t)o->width * o->height; i++)
        img->rgba[4 * i + 3] = 1.0f;
    gi_image_write_opts wo = {o->exposure};
    gi_error err;
    gi_result res = gi_image_write(path, img, &wo, &err);
    gi_image_free(img);
    if (res != GI_OK)
        return cli_fail(EXIT_RUN, "render: frame %u: %s", f, err.text);
    return EXIT_OK;
}

static json_object *timings_json(const run_state *r, const render_opts *o)
{
    json_object *j = json_object_new_object();
    char *pstr = gi_params_to_string(r->params);
    json_object_object_add(j, "method", json_object_new_string(r->m->id));
    json_object_object_add(j, "method_version", json_object_new_string(r->m->version));
    json_object_object_add(j, "params", json_object_new_string(pstr ? pstr : ""));
    free(pstr);
    json_object_object_add(j, "scene", json_object_new_string(o->scene));
    json_object_object_add(j, "camera",
                           json_object_new_string(o->camera     ? o->camera
                                                  : o->has_view ? o->view_path
                                                                : "#0"));
    json_object_object_add(j, "width", json_object_new_int((int32_t)o->width));
    json_object_object_add(j, "height", json_object_new_int((int32_t)o->height));
    json_object_object_add(j, "frames", json_object_new_int((int32_t)o->frames));
    json_object_object_add(j, "warmup", json_object_new_int((int32_t)o->warmup));
    json_object_object_add(j, "seed", json_object_new_int64(o->seed));
    json_object_object_add(j, "time", json_object_new_double(o->time));
    json_object_object_add(j, "animate_fps", json_object_new_double(o->animate_fps));
    json_object_object_add(j, "cache", json_object_new_boolean(r->cache_dir != NULL));
    json_object_object_add(j, "gl_renderer", json_object_new_string(gi_gpu_renderer(r->gpu)));
    json_object_object_add(j, "gl_version", json_object_new_string(gi_gpu_version(r->gpu)));
    json_object_object_add(j, "egl_platform", json_object_new_string(gi_gpu_platform(r->gpu)));
    json_object_object_add(j, "gl_vendor", json_object_new_string(gi_gpu_vendor(r->gpu)));
    json_object_object_add(j, "egl_device", json_object_new_string(gi_gpu_device(r->gpu)));
    json_object_object_add(
        j, "timer", json_object_new_string(gi_timer_mode_name(gi_timer_get_mode(r->render_timer))));
    json_object_object_add(j, "prepare", cli_timer_json(r->prep_timer));
    json_object_object_add(j, "render", cli_timer_json(r->render_timer));
    json_object_object_add(j, "stats", json_object_get(r->host.stats));
    double mean[4];
    gi_image_mean(r->image, mean);
    json_object *mj = json_object_new_array();
    for (int c = 0; c < 3; c++)
        json_object_array_add(mj, json_object_new_double(mean[c]));
    json_object_object_add(j, "mean_rgb", mj);
    json_object_object_add(j, "nonfinite_pixels",
                           json_object_new_int64((int64_t)gi_image_count_nonfinite(r->image)));
    /* peak resident memory (MiB): after prepare(), and of the whole run */
    json_object_object_add(j, "peak_rss_prepare_mib", json_object_new_double(r->rss_prepare_mib));
    json_object_object_add(j, "peak_rss_mib", json_object_new_double(peak_rss_mib()));
    if (o->curve_ref_count)
        json_object_object_add(j, "curve", curve_json(r, o));
    return j;
}

/* One line at the end (unless -q): the method, frames, frame time and files. */
static void print_summary(const run_state *r, const render_opts *o)
{
    if (gi_log_get_level() < GI_LOG_WARN)
        return;
    gi_stage_stats st[GI_TIMER_MAX_STAGES + 1];
    uint32_t n = gi_timer_stats(r->render_timer, st, GI_TIMER_MAX_STAGES + 1);
    double median = NAN, prep = NAN;
    for (uint32_t i = 0; i < n; i++)
        if (!strcmp(st[i].name, "frame"))
            median = st[i].median_ms;
    n = gi_timer_stats(r->prep_timer, st, GI_TIMER_MAX_STAGES + 1);
    for (uint32_t i = 0; i < n; i++)
        if (!strcmp(st[i].name, "frame"))
            prep = st[i].median_ms;
    char files[1024] = "";
    for (int i = 0; i < o->out_count; i++) {
        size_t used = strlen(files);
        snprintf(files + used, sizeof files - used, "%s%s", i ? ", " : "", o->outs[i]);
    }
    printf("render: %s, %ux%u, %u frame%s (%u warm-up), median %.3g ms/frame, prepare %.3g ms "
           "(%s); wrote %s%s%s\n",
           r->m->id, o->width, o->height, o->frames, o->frames == 1 ? "" : "s", o->warmup, median,
           prep, gi_gpu_renderer(r->gpu), files, o->timings ? ", " : "",
           o->timings ? o->timings : "");
}

/* The method of --method among the installed ones. */
static int find_method(run_state *r, const render_opts *o)
{
    r->reg = cli_load_plugins(1);
    if (!r->reg)
        return cli_fail(EXIT_RUN, "out of memory");
    r->m = gi_plugins_find(r->reg, o->method);
    if (!r->m) {
        char known[512] = "";
        for (uint32_t i = 0; i < r->reg->count; i++) {
            size_t used = strlen(known);
            snprintf(known + used, sizeof known - used, "%s%s", i ? ", " : "",
                     r->reg->items[i].method->id);
        }
        return cli_fail(EXIT_USAGE, "render: no method '%s' (installed: %s)", o->method,
                        known[0] ? known : "none");
    }
    for (int i = 0; i < o->buffer_count; i++) {
        gi_error err;
        if (debug_buffer_check(r->m, o->buffers[i], &err) != GI_OK)
            return cli_fail(EXIT_USAGE, "render: %s", err.text);
    }
    return EXIT_OK;
}

/* The method's parameters and the scene, with what a saved view moves
 * marked as moving; warns when the method's caps leave part of the scene
 * out. *moves: the view moves objects or lights. */
static int load_scene(run_state *r, const render_opts *o, int *moves)
{
    gi_error err;
    r->params = gi_params_parse(r->m->id, r->m->params, o->params, o->param_count, &err);
    if (!r->params)
        return cli_fail(EXIT_USAGE, "%s", err.text);
    r->scene = gi_scene_load(o->scene, &err);
    if (!r->scene)
        return cli_fail(EXIT_USAGE, "%s", err.text);
    /* A study marks such a cell n/a; a single render runs it but says what
     * the image leaves out. */
    char why[256];
    *moves = o->has_view && o->view.node_count > 0;
    if (*moves) {
        /* a saved view with objects or lights moved: the method is prepared
         * with the scene as the file places it, those objects marked as
         * moving, then told of the move by update(), as gibench view did */
        char nwhy[600];
        if (!view_file_check_nodes(&o->view, r->scene, nwhy, sizeof nwhy))
            return cli_fail(EXIT_USAGE, "render: --view %s: %s", o->view_path, nwhy);
        for (uint32_t i = 0; i < o->view.node_count; i++)
            view_scene_mark_moving(r->scene, o->view.nodes[i].node);
    }
    if (!cli_caps_cover(r->m, r->scene, o->animate_fps > 0 || *moves, why, sizeof why))
        gi_log(GI_LOG_WARN,
               "render: %s in %s: the image leaves that out (a study marks this cell n/a)", why,
               o->scene);
    return EXIT_OK;
}

/* References of the convergence curve: read before anything is timed. */
static int read_curve_refs(run_state *r, const render_opts *o)
{
    gi_error err;
    for (int c = 0; c < o->curve_ref_count; c++) {
        r->curve_ref[c] = gi_image_read(o->curve_path[c], &err);
        if (!r->curve_ref[c])
            return cli_fail(EXIT_USAGE, "render: --curve-ref: %s", err.text);
        if (r->curve_ref[c]->width != o->width || r->curve_ref[c]->height != o->height)
            return cli_fail(EXIT_USAGE, "render: --curve-ref %s is %ux%u, the render %ux%u",
                            o->curve_path[c], r->curve_ref[c]->width, r->curve_ref[c]->height,
                            o->width, o->height);
    }
    return EXIT_OK;
}

/* The scene camera of --camera (a saved view has its own); -1 when the
 * scene has none. */
static int find_camera(const run_state *r, const render_opts *o, int *camera)
{
    *camera = 0;
    if (o->camera && !o->has_view) {
        *camera = gi_scene_find_camera(r->scene, o->camera);
        if (*camera < 0)
            return cli_fail(EXIT_USAGE,
                            "render: %s has no camera '%s' (%u cameras; use a name or #k)",
                            o->scene, o->camera, r->scene->camera_count);
    } else if (r->scene->camera_count == 0) {
        *camera = -1;
    }
    return EXIT_OK;
}

/* The cache, the GL context with the scene uploaded, the timers, the host
 * services and the render target (cleared to black). */
static int setup_gpu(run_state *r, const render_opts *o, int camera)
{
    gi_error err;
    /* The cache only saves time: with no usable directory (HOME unset or
     * read-only, as on many batch nodes) the method precomputes afresh, as
     * with --no-cache, after one warning. */
    if (!o->no_cache) {
        r->cache_dir = gi_cache_dir(&err);
        if (!r->cache_dir)
            fprintf(stderr, "gibench: warning: %s; rendering without the cache\n", err.text);
    }
    r->gpu = gi_gpu_create(NULL, &err);
    if (!r->gpu)
        return cli_fail(EXIT_RUN, "%s", err.text);
    r->gs = gi_gpu_scene_upload(r->gpu, r->scene, &err);
    if (!r->gs)
        return cli_fail(EXIT_RUN, "%s", err.text);
    gi_gpu_scene_set_time(r->gs, o->time);

    gi_timer_mode mode = gi_timer_mode_for(gi_gpu_is_software(r->gpu));
    r->prep_timer = gi_timer_create(mode, 0);
    r->render_timer = gi_timer_create(mode, o->warmup);
    cli_host_init(&r->host, r->m->id, r->cache_dir, r->gs, gi_gpu_renderer(r->gpu),
                  gi_gpu_is_software(r->gpu));
    r->host_ready = 1;

    render_loop *l = &r->loop;
    l->m = r->m;
    l->scene = r->scene;
    l->gs = r->gs;
    l->host = &r->host;
    l->prep_timer = r->prep_timer;
    l->render_timer = r->render_timer;
    l->width = o->width;
    l->height = o->height;
    l->seed = o->seed;
    l->time = o->time;
    l->animate_fps = o->animate_fps;
    l->exposure = o->exposure;
    l->camera = camera;
    if (o->has_view) {
        r->view_camera = view_file_camera(&o->view);
        l->fixed_camera = &r->view_camera;
    }
    render_loop_target(l);
    return EXIT_OK;
}

/* The method created and prepared (the prepare timer), then told of what
 * a saved view moves. */
static int create_and_prepare(run_state *r, const render_opts *o, int moves)
{
    gi_error err;
    gi_result res = render_loop_prepare(&r->loop, r->params, &err);
    if (res != GI_OK)
        return loop_fail(r, res, &err);
    if (moves) {
        unsigned char *moved = calloc(r->scene->node_count, 1);
        if (!moved)
            return cli_fail(EXIT_RUN, "out of memory");
        for (uint32_t i = 0; i < o->view.node_count; i++)
            moved[o->view.nodes[i].node] = 1;
        gi_changes ch = {0, o->time, 0};
        view_scene_changes(r->scene, moved, &ch.flags, &ch.moved_objects);
        free(moved);
        view_file_apply_nodes(&o->view, r->scene);
        gi_gpu_scene_set_time(r->gs, o->time);
        res = r->m->update(r->loop.inst, r->gs, &ch);
        if (res != GI_OK) {
            render_loop_method_error(&r->loop, "update", res, &err);
            return loop_fail(r, res, &err);
        }
    }
    return EXIT_OK;
}

/* Every frame (the render timer), with the convergence curve's points and
 * --frames-out taken between them, under a progress line. */
static int render_frames(run_state *r, const render_opts *o)
{
    cli_progress bar;
    char label[64];
    snprintf(label, sizeof label, "render %s", r->m->id);
    cli_progress_start(&bar, label);
    for (uint32_t f = 0; f < o->frames; f++) {
        if (f > 0 && o->frames > 1)
            cli_progress_show(&bar, (double)f / o->frames, f, o->frames, "frames");
        if (cli_interrupted) {
            cli_progress_end(&bar);
            return cli_fail(EXIT_RUN, "render: interrupted after %u of %u frames; no image written",
                            f, o->frames);
        }
        gi_error err;
        gi_result res = render_loop_frame(&r->loop, f, &err);
        if (res != GI_OK) {
            cli_progress_end(&bar);
            return loop_fail(r, res, &err);
        }
        int rc = record_curve_point(r, o, f + 1);
        if (rc == EXIT_OK)
            rc = write_frame(r, o, f);
        if (rc != EXIT_OK) {
            cli_progress_end(&bar);
            return rc;
        }
    }
    if (o->frames > 1)
        cli_progress_show(&bar, 1.0, o->frames, o->frames, "frames");
    cli_progress_end(&bar);
    return EXIT_OK;
}

/* --buffer with several names: --out PATH with ".NAME" before its extension. */
static void buffer_path(const char *out, const char *name, char *path, size_t size)
{
    const char *dot = strrchr(out, '.');
    snprintf(path, size, "%.*s.%s%s", (int)(dot - out), out, name, dot);
}

/* --buffer: every buffer fetched first (nothing is written when one
 * fails), then written into the --out files. */
static int write_buffers(run_state *r, const render_opts *o)
{
    gi_image *img[MAX_BUFFERS] = {0};
    gi_error err;
    int rc = EXIT_OK;
    for (int b = 0; b < o->buffer_count && rc == EXIT_OK; b++)
        if (!(img[b] = render_loop_buffer(&r->loop, o->buffers[b], &err)))
            rc = cli_fail(EXIT_RUN, "render: %s", err.text);
    gi_image_write_opts wo = {o->exposure};
    for (int b = 0; b < o->buffer_count && rc == EXIT_OK; b++)
        for (int i = 0; i < o->out_count && rc == EXIT_OK; i++) {
            char path[4096];
            if (o->buffer_count == 1)
                snprintf(path, sizeof path, "%s", o->outs[i]);
            else
                buffer_path(o->outs[i], o->buffers[b], path, sizeof path);
            if (gi_image_write(path, img[b], &wo, &err) != GI_OK)
                rc = cli_fail(EXIT_RUN, "%s", err.text);
        }
    for (int b = 0; b < o->buffer_count; b++)
        gi_image_free(img[b]);
    return rc;
}

/* The last image (alpha 1) into every --out (or, with --buffer, the
 * buffers), the timings file and the summary line. */
static int write_results(run_state *r, const render_opts *o)
{
    gi_error err;
    r->image = render_loop_image(&r->loop);
    if (!r->image)
        return cli_fail(EXIT_RUN, "out of memory reading the image back");
    gi_image_write_opts wo = {o->exposure};
    if (o->buffer_count) {
        int brc = write_buffers(r, o);
        if (brc != EXIT_OK)
            return brc;
    }
    for (int i = 0; i < o->out_count && !o->buffer_count; i++)
        if (gi_image_write(o->outs[i], r->image, &wo, &err) != GI_OK)
            return cli_fail(EXIT_RUN, "%s", err.text);
    uint64_t bad = gi_image_count_nonfinite(r->image);
    if (bad)
        gi_log(GI_LOG_WARN, "%s: %llu pixels are NaN or Inf", r->m->id, (unsigned long long)bad);
    int rc = o->timings ? cli_save_json(o->timings, timings_json(r, o)) : EXIT_OK;
    if (rc == EXIT_OK)
        print_summary(r, o);
    return rc;
}

static int run(run_state *r, const render_opts *o)
{
    int moves = 0, camera = 0;
    int rc = find_method(r, o);
    if (rc == EXIT_OK)
        rc = load_scene(r, o, &moves);
    if (rc == EXIT_OK)
        rc = read_curve_refs(r, o);
    if (rc == EXIT_OK)
        rc = find_camera(r, o, &camera);
    if (rc == EXIT_OK)
        rc = setup_gpu(r, o, camera);
    if (rc == EXIT_OK)
        rc = create_and_prepare(r, o, moves);
    if (rc != EXIT_OK)
        return rc;
    r->rss_prepare_mib = peak_rss_mib();
    rc = render_frames(r, o);
    if (rc == EXIT_OK)
        rc = write_results(r, o);
    return rc;
}

int cmd_render(int argc, char **argv)
{
    render_opts o;
    int rc = parse_opts(argc, argv, &o);
    if (rc != EXIT_OK) {
        view_file_free(&o.view);
        return rc;
    }
    cli_install_signal_handlers();
    run_state r;
    memset(&r, 0, sizeof r);
    rc = run(&r, &o);
    cleanup(&r);
    view_file_free(&o.view);
    return rc;
}
