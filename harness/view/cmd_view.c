/* gibench view: the interactive viewer (README.md "gibench view"). A GLFW
 * window with an OpenGL 4.5 core context, adopted by the core (gi_gpu_desc
 * .adopt_current), so that the methods render through the same plugin path
 * as `gibench render` and their image is shown without a copy; the
 * progressive reference runs on a worker thread (view_ref.h). --script
 * replays key and mouse events (view_script.c) for the tests. */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"
#include "view.h"

#include "gi/cache.h"
#include "gi/image.h"
#include "gi/log.h"
#include "gi/shader.h"
#include "gi/timer.h"
#include "gi/tonemap.h"
#include "gi/vecmath.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PI_F 3.14159265f

static const char display_vs[] = "out vec2 uv;\n"
                                 "void main() {\n"
                                 "    vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);\n"
                                 "    uv = p;\n"
                                 "    gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);\n"
                                 "}\n";
/* The display mapping of core/shaders/tonemap.glsl (exposure, clamp,
 * sRGB); in split view, right of the divider, the reference (`ref`, top
 * row first) or the method's relative luminance error against it,
 * |L - Lref| / (Lref + 0.01), on a log scale from 1e-3 (blue) to 1 (red). */
static const char display_fs[] =
    "in vec2 uv;\n"
    "out vec4 color;\n"
    "layout(binding = 0) uniform sampler2D img;\n"
    "layout(binding = 1) uniform sampler2D ref;\n"
    "uniform float scale;\n"
    "uniform int flip;\n"
    "uniform int split;\n"
    "uniform float divider;\n"
    "uniform float pixel;\n"
    "float enc(float x) {\n"
    "    x = x > 0.0 ? min(x, 1.0) : 0.0;\n"
    "    return x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1.0 / 2.4) - 0.055;\n"
    "}\n"
    "float lum(vec3 c) { return dot(c, vec3(0.2126, 0.7152, 0.0722)); }\n"
    "vec3 ramp(float t) {\n"
    "    t = clamp(t, 0.0, 1.0);\n"
    "    return clamp(vec3(1.5 - abs(4.0 * t - 3.0), 1.5 - abs(4.0 * t - 2.0), 1.5 - abs(4.0 * t - "
    "1.0)), 0.0, 1.0);\n"
    "}\n"
    "void main() {\n"
    "    vec2 t = flip != 0 ? vec2(uv.x, 1.0 - uv.y) : uv;\n"
    "    vec3 c = texture(img, t).rgb;\n"
    "    if (split != 0 && abs(uv.x - divider) < pixel) {\n"
    "        color = vec4(1.0);\n"
    "        return;\n"
    "    }\n"
    "    if (split != 0 && uv.x > divider) {\n"
    "        vec3 r = texture(ref, vec2(uv.x, 1.0 - uv.y)).rgb;\n"
    "        if (split == 2) {\n"
    "            float e = abs(lum(c) - lum(r)) / (lum(r) + 0.01);\n"
    "            color = vec4(ramp((log(max(e, 1e-4)) / log(10.0) + 3.0) / 3.0), 1.0);\n"
    "            return;\n"
    "        }\n"
    "        c = r;\n"
    "    }\n"
    "    c *= scale;\n"
    "    color = vec4(enc(c.r), enc(c.g), enc(c.b), 1.0);\n"
    "}\n";

static int build_display(viewer *v)
{
    gi_error err;
    v->display_prog = gi_program_build_text("view display", display_vs, display_fs, NULL, &err);
    if (!v->display_prog)
        return cli_fail(EXIT_RUN, "view: display shader: %s", err.text);
    glCreateVertexArrays(1, &v->display_vao);
    return EXIT_OK;
}

/* ---- camera ---- */

gi_vec3 view_eye(const viewer *v)
{
    float cp = cosf(v->pitch), sp = sinf(v->pitch);
    gi_vec3 dir = gi_v3(cp * sinf(v->yaw), sp, cp * cosf(v->yaw));
    return gi_v3_add(v->center, gi_v3_scale(dir, v->dist));
}

gi_camera_frame view_camera(const viewer *v)
{
    view_file f;
    memset(&f, 0, sizeof f);
    f.eye = view_eye(v);
    f.forward = gi_v3_normalize(gi_v3_sub(v->center, f.eye));
    f.up = gi_v3(0, 1, 0);
    f.yfov = v->yfov;
    f.znear = v->znear;
    f.zfar = v->zfar;
    return view_file_camera(&f);
}

/* The orbit camera placed as the scene's camera `index` (-1: the default view). */
void view_camera_from_scene(viewer *v, int index)
{
    gi_camera_frame cf = gi_scene_camera_at(v->scene, index, v->time);
    gi_vec3 f = gi_v3_normalize(cf.forward);
    gi_vec3 mid = gi_v3(0.5f * (v->gs->bounds[0] + v->gs->bounds[3]),
                        0.5f * (v->gs->bounds[1] + v->gs->bounds[4]),
                        0.5f * (v->gs->bounds[2] + v->gs->bounds[5]));
    float d = gi_v3_dot(gi_v3_sub(mid, cf.eye), f);
    if (!(d > 1e-3f))
        d = fmaxf(gi_v3_length(gi_v3_sub(mid, cf.eye)), 1.0f);
    v->dist = d;
    v->center = gi_v3_add(cf.eye, gi_v3_scale(f, d));
    v->pitch = asinf(fmaxf(-1.0f, fminf(1.0f, -f.y)));
    v->yaw = atan2f(-f.x, -f.z);
    v->yfov = cf.yfov;
    v->znear = cf.znear;
    v->zfar = cf.zfar;
    v->scene_camera = index;
    view_changed(v);
}

void view_changed(viewer *v)
{
    v->pitch = fmaxf(-1.55f, fminf(1.55f, v->pitch));
    v->dist = fmaxf(v->dist, 1e-3f);
    v->frame_index = 0;
    v->need_render = 1;
    v->need_display = 1;
    if (v->method_index < 0 || v->split) {
        gi_camera_frame cf = view_camera(v);
        view_ref_request(&v->ref, &cf, v->time, v->width, v->height, v->seed);
        v->ref_spp = 0;
        const float black[4] = {0, 0, 0, 1};
        glClearTexImage(v->ref_tex, 0, GL_RGBA, GL_FLOAT, black);
    }
}

/* The reference runs while it is shown (alone or in split view) and idles otherwise. */
static void reference_as_needed(viewer *v)
{
    int need = v->method_index < 0 || v->split;
    if (need && !view_ref_running(&v->ref))
        view_changed(v);
    else if (!need)
        view_ref_pause(&v->ref);
}

/* ---- methods ---- */

static void unload_method(viewer *v)
{
    if (v->inst)
        v->m->destroy(v->inst);
    v->inst = NULL;
    if (v->host_ready)
        cli_host_free(&v->host);
    v->host_ready = 0;
    gi_params_free(v->params);
    v->params = NULL;
    v->m = NULL;
    v->status[0] = '\0';
    v->stale = 0;
}

void view_go_stale(viewer *v)
{
    v->stale = 1;
    const float black[4] = {0, 0, 0, 1};
    glClearNamedFramebufferfv(v->target_fbo, GL_COLOR, 0, black);
    v->need_display = 1;
}

/* Makes method `index` (into the registry; -1 the reference) the one shown:
 * create and prepare as `gibench render` does. EXIT_OK, or an exit code
 * after printing why (the previous method is gone either way). */
int view_select(viewer *v, int index)
{
    unload_method(v);
    v->method_index = index;
    v->frame_index = 0;
    v->need_render = v->need_display = 1;
    reference_as_needed(v);
    if (index < 0)
        return EXIT_OK;
    gi_error err;
    v->m = v->reg->items[index].method;
    const char *const *kv = NULL;
    uint32_t n = 0;
    if (!strcmp(v->m->id, v->kv_method)) {
        kv = (const char *const *)v->kv.params;
        n = v->kv.param_count;
    } else if (v->start_method && !strcmp(v->m->id, v->start_method)) {
        kv = v->opt_params;
        n = v->opt_param_count;
    }
    v->params = gi_params_parse(v->m->id, v->m->params, kv, n, &err);
    if (!v->params)
        return cli_fail(EXIT_USAGE, "%s", err.text);
    char why[256];
    if (!cli_caps_cover(v->m, v->scene, v->playing, why, sizeof why))
        snprintf(v->status, sizeof v->status, "%s", why);
    cli_host_init(&v->host, v->m->id, v->cache_dir, v->gs, gi_gpu_renderer(v->gpu),
                  gi_gpu_is_software(v->gpu));
    v->host_ready = 1;
    v->host_progress = v->host.host.progress; /* the terminal line, and a bar in the window */
    v->host.host.progress = view_overlay_progress;
    gi_timer_free(v->timer);
    v->timer = gi_timer_create(GI_TIMER_CPU_FINISH, 0);
    v->timer_frames = 0;
    v->stage_count = 0;
    gi_error cerr;
    gi_result res = gi_method_create(v->m, &v->host.host, v->params, &v->inst, &cerr);
    if (res != GI_OK)
        return cli_fail(EXIT_RUN, "view: %s: %s", v->m->id, cerr.text);
    char title[128];
    snprintf(title, sizeof title, "gibench view: preparing %s ...", v->m->id);
    glfwSetWindowTitle(v->win, title);
    /* objects or lights moved by hand: the method is prepared with the
     * scene as the file places it and told of the moves by update(), as
     * `gibench render --view` does it */
    int moved = view_moved_any(v);
    if (moved)
        view_nodes_swap(v, 1);
    double t0 = gi_now();
    res = v->m->prepare(v->inst, v->gs);
    cli_host_progress_end(&v->host);
    v->prepare_ms = 1e3 * (gi_now() - t0);
    if (moved) {
        view_nodes_swap(v, 0);
        view_changed(v);
    }
    if (res != GI_OK) {
        const char *msg = v->m->last_error(v->inst);
        return cli_fail(EXIT_RUN, "view: %s: prepare failed (%s)%s%s", v->m->id,
                        gi_result_name(res), msg && *msg ? ": " : "", msg ? msg : "");
    }
    if (v->time != v->prepared_time) {
        /* the scene moved since the upload: tell the method */
        gi_changes ch = {GI_CHANGED_TRANSFORMS | GI_CHANGED_LIGHTS |
                             (v->gs->deforming ? GI_CHANGED_VERTICES : 0u),
                         v->time, ~0ull};
        res = v->m->update(v->inst, v->gs, &ch);
        if (res != GI_OK)
            return cli_fail(EXIT_RUN, "view: %s: update failed (%s)", v->m->id,
                            gi_result_name(res));
    }
    if (moved && res == GI_OK)
        return view_tell_method(v, v->node_moved);
    return EXIT_OK;
}

/* The selected parameter one step up (dir 1) or down (-1): ints and floats
 * by a quarter (at least 1 for ints; a twentieth of the range from 0),
 * within their range; bools toggle; enums go round their choices. The
 * method is made again with the new values (create + prepare, as a
 * change of parameter needs a rebuild in general). */
static int step_param(viewer *v, int dir)
{
    if (!v->params || v->params->count == 0) {
        snprintf(v->status, sizeof v->status, "no parameter");
        return EXIT_OK;
    }
    uint32_t i = (uint32_t)v->param_sel % v->params->count;
    const gi_param_desc *d = &v->params->desc[i];
    double old = v->params->values[i], x = old;
    switch (d->type) {
    case GI_PARAM_INT:
        x = dir > 0 ? fmax(old + 1, round(old * 1.25)) : fmin(old - 1, round(old / 1.25));
        x = fmin(d->max, fmax(d->min, x));
        break;
    case GI_PARAM_FLOAT:
        x = old == 0 ? dir * (d->max - d->min) / 20 : dir > 0 ? old * 1.25 : old / 1.25;
        x = fmin(d->max, fmax(d->min, x));
        break;
    case GI_PARAM_BOOL:
        x = old != 0 ? 0 : 1;
        break;
    case GI_PARAM_ENUM: {
        int n = 1;
        for (const char *c = d->choices; c && *c; c++)
            n += *c == '|';
        x = (double)(((int)old + (dir > 0 ? 1 : n - 1)) % n);
        break;
    }
    }
    v->params->values[i] = x;
    char *s = gi_params_to_string(v->params);
    v->params->values[i] = old;
    if (!s || !view_file_set_params(&v->kv, s)) {
        free(s);
        return cli_fail(EXIT_RUN, "out of memory");
    }
    free(s);
    snprintf(v->kv_method, sizeof v->kv_method, "%s", v->m->id);
    int sel = v->param_sel;
    int rc = view_select(v, v->method_index);
    v->param_sel = sel;
    return rc;
}

/* Renders one frame of the method into the target (timed, with glFinish). */
static int render_method(viewer *v)
{
    gi_view view;
    gi_camera_frame cf = view_camera(v);
    gi_view_from_camera(&cf, v->width, v->height, v->time, &view);
    view.frame_index = v->frame_index;
    view.seed = v->seed;
    view.exposure = v->exposure;
    gi_target target = {v->target_tex, v->target_fbo, v->width, v->height};
    if (v->timer && v->timer_frames >= 1024) { /* the chart needs the last frame only */
        gi_timer_free(v->timer);
        v->timer = gi_timer_create(GI_TIMER_CPU_FINISH, 0);
        v->timer_frames = 0;
    }
    v->host.timer = v->timer;
    if (v->timer)
        gi_timer_frame_begin(v->timer);
    double t0 = gi_now();
    gi_result res = v->m->render(v->inst, &view, &target);
    glFinish();
    v->frame_ms = 1e3 * (gi_now() - t0);
    if (v->timer) {
        gi_timer_frame_end(v->timer);
        v->timer_frames++;
        gi_stage_stats st[GI_TIMER_MAX_STAGES];
        uint32_t n = gi_timer_stats(v->timer, st, GI_TIMER_MAX_STAGES);
        v->stage_count = 0;
        for (uint32_t i = 0; i < n; i++) {
            uint32_t count = 0;
            const double *ms = gi_timer_samples(v->timer, st[i].name, &count);
            if (!ms || !count)
                continue;
            snprintf(v->stage_name[v->stage_count], GI_TIMER_NAME_MAX, "%.*s",
                     GI_TIMER_NAME_MAX - 1, st[i].name);
            v->stage_ms[v->stage_count++] = ms[count - 1];
        }
    }
    v->host.timer = NULL;
    v->sum_frame_ms += v->frame_ms;
    v->n_frames++;
    if (res != GI_OK) {
        const char *msg = v->m->last_error(v->inst);
        return cli_fail(EXIT_RUN, "view: %s: render failed (%s)%s%s", v->m->id, gi_result_name(res),
                        msg && *msg ? ": " : "", msg ? msg : "");
    }
    gi_error err;
    if (gi_gl_check("after render", &err) != GI_OK)
        return cli_fail(EXIT_RUN, "view: %s: %s", v->m->id, err.text);
    v->frame_index++;
    v->need_display = 1;
    return EXIT_OK;
}

/* Advances the animation to time t and tells the method (update()). */
static int set_time(viewer *v, float t)
{
    v->time = t;
    gi_gpu_scene_set_time(v->gs, t);
    if (v->inst) {
        gi_changes ch = {GI_CHANGED_TRANSFORMS | GI_CHANGED_LIGHTS |
                             (v->gs->deforming ? GI_CHANGED_VERTICES : 0u),
                         t, ~0ull};
        gi_result res = v->m->update(v->inst, v->gs, &ch);
        if (res != GI_OK)
            return cli_fail(EXIT_RUN, "view: %s: update failed (%s)", v->m->id,
                            gi_result_name(res));
    }
    view_changed(v);
    return EXIT_OK;
}

/* ---- display ---- */

/* The window as shown (split view, divider and all) into a PNG: read back
 * from the back buffer before the swap. */
static void write_window(viewer *v, int fw, int fh)
{
    gi_image *img = fw > 0 && fh > 0 ? gi_image_create((uint32_t)fw, (uint32_t)fh) : NULL;
    unsigned char *px = malloc((size_t)fw * (size_t)(fh > 0 ? fh : 0) * 4);
    gi_error err;
    if (!img || !px) {
        v->exit_code = cli_fail(EXIT_RUN, "view: out of memory reading the window back");
    } else {
        glPixelStorei(GL_PACK_ALIGNMENT, 1);
        glReadBuffer(GL_BACK);
        glReadPixels(0, 0, fw, fh, GL_RGBA, GL_UNSIGNED_BYTE, px);
        for (int y = 0; y < fh; y++) /* bottom row first -> top row first; sRGB -> linear */
            for (int x = 0; x < fw; x++)
                for (int c = 0; c < 4; c++) {
                    float b = px[4 * ((size_t)(fh - 1 - y) * (size_t)fw + (size_t)x) + (size_t)c] /
                              255.0f;
                    img->rgba[4 * ((size_t)y * (size_t)fw + (size_t)x) + (size_t)c] =
                        c == 3 ? 1.0f : gi_srgb_decode(b);
                }
        if (gi_image_write(v->window_shot, img, NULL, &err) != GI_OK)
            v->exit_code = cli_fail(EXIT_RUN, "view: %s", err.text);
        else if (gi_log_get_level() >= GI_LOG_WARN)
            printf("view: window %s\n", v->window_shot);
    }
    free(px);
    gi_image_free(img);
}

static void display(viewer *v)
{
    double t0 = gi_now();
    int fw = 0, fh = 0;
    glfwGetFramebufferSize(v->win, &fw, &fh);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glViewport(0, 0, fw, fh);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_BLEND);
    glDisable(GL_CULL_FACE);
    glDisable(GL_SCISSOR_TEST);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glClearColor(0, 0, 0, 1);
    glClear(GL_COLOR_BUFFER_BIT);
    glUseProgram(v->display_prog);
    glUniform1f(glGetUniformLocation(v->display_prog, "scale"), exp2f(v->exposure));
    int ref = v->method_index < 0;
    glUniform1i(glGetUniformLocation(v->display_prog, "flip"), ref); /* images are top row first */
    glUniform1i(glGetUniformLocation(v->display_prog, "split"), ref ? 0 : v->split);
    glUniform1f(glGetUniformLocation(v->display_prog, "divider"), v->divider);
    glUniform1f(glGetUniformLocation(v->display_prog, "pixel"), fw > 0 ? 0.75f / (float)fw : 0.0f);
    glBindTextureUnit(0, ref ? v->ref_tex : v->target_tex);
    glBindTextureUnit(1, v->ref_tex);
    glBindSampler(0, 0);
    glBindSampler(1, 0);
    glBindVertexArray(v->display_vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glBindVertexArray(0);
    glUseProgram(0);
    view_overlay_draw(v, fw, fh);
    v->sum_overlay_ms += v->overlay_ms;
    if (v->window_shot) {
        write_window(v, fw, fh);
        v->window_shot = NULL;
    }
    glfwSwapBuffers(v->win);
    glFinish();
    v->display_ms = 1e3 * (gi_now() - t0);
    v->sum_display_ms += v->display_ms;
    v->n_displays++;
    v->need_display = 0;

    char title[768];
    if (ref)
        snprintf(title, sizeof title,
                 "gibench view | reference | %llu spp | EV %+.1f | t %.2f%s | ui %.1f ms",
                 (unsigned long long)v->ref_spp, (double)v->exposure, (double)v->time,
                 v->playing ? " playing" : "", v->display_ms);
    else
        snprintf(title, sizeof title,
                 "gibench view | %s%s | %.1f ms/frame | frame %u | EV %+.1f | t %.2f%s | ui %.1f "
                 "ms | %s%s%s",
                 v->m ? v->m->id : "-",
                 v->split == 1   ? " | reference right"
                 : v->split == 2 ? " | error right (log, 1e-3 blue .. 1 red)"
                                 : "",
                 v->frame_ms, v->frame_index, (double)v->exposure, (double)v->time,
                 v->playing ? " playing" : "", v->display_ms, gi_gpu_renderer(v->gpu),
                 v->status[0] ? " | " : "", v->status);
    if (!ref && v->params && v->params->count) {
        /* the parameter TAB selected, with its value */
        char *all = gi_params_to_string(v->params);
        uint32_t sel = (uint32_t)v->param_sel % v->params->count;
        const char *p = all;
        for (uint32_t k = 0; p && k < sel; k++) {
            p = strchr(p, ',');
            p = p ? p + 1 : NULL;
        }
        if (p) {
            size_t used = strlen(title);
            const char *end = strchr(p, ',');
            snprintf(title + used, sizeof title - used, " | param %.*s (TAB, PgUp/PgDn)",
                     (int)(end ? end - p : (long)strlen(p)), p);
        }
        free(all);
    }
    glfwSetWindowTitle(v->win, title);
}

/* Takes a fresh reference image into ref_tex. */
static void poll_reference(viewer *v)
{
    uint64_t spp = 0;
    gi_image *img = view_ref_take(&v->ref, 0, &spp);
    if (!img)
        return;
    glTextureSubImage2D(v->ref_tex, 0, 0, 0, (GLsizei)img->width, (GLsizei)img->height, GL_RGBA,
                        GL_FLOAT, img->rgba);
    gi_image_free(img);
    v->ref_spp = spp;
    v->need_display = 1;
}

/* ---- screenshots and saved views ---- */

void view_describe(const viewer *v, view_file *f)
{
    memset(f, 0, sizeof *f);
    snprintf(f->scene, sizeof f->scene, "%s", v->scene_path);
    snprintf(f->method, sizeof f->method, "%s", v->method_index < 0 ? "reference" : v->m->id);
    if (v->params) {
        char *s = gi_params_to_string(v->params);
        view_file_set_params(f, s);
        free(s);
    }
    f->width = v->width;
    f->height = v->height;
    f->frames = v->method_index < 0 ? (uint32_t)(v->ref_spp ? v->ref_spp : 1)
                                    : (v->frame_index ? v->frame_index : 1);
    f->seed = v->seed;
    f->time = v->time;
    f->exposure = v->exposure;
    gi_vec3 eye = view_eye(v);
    f->eye = eye;
    f->forward = gi_v3_normalize(gi_v3_sub(v->center, eye));
    f->up = gi_v3(0, 1, 0);
    f->yfov = v->yfov;
    f->znear = v->znear;
    f->zfar = v->zfar;
    view_describe_nodes(v, f);
}

int view_save(const viewer *v, const char *path)
{
    view_file f;
    view_describe(v, &f);
    char why[600];
    int ok = view_file_write(path, &f, why, sizeof why);
    view_file_free(&f);
    if (!ok)
        return cli_fail(EXIT_RUN, "view: %s", why);
    gi_log(GI_LOG_INFO, "view: saved the view to %s", path);
    return EXIT_OK;
}

/* PREFIX.exr (linear), PREFIX.png (exposure, sRGB) and PREFIX.json (the
 * view, which `gibench render --view` reproduces). */
int view_screenshot(viewer *v, const char *prefix)
{
    gi_image *img = NULL;
    if (v->method_index >= 0 && v->stale) {
        /* the method could not follow a change: its black target is not
         * an image of this view, and the view file would claim it is */
        gi_log(GI_LOG_WARN, "view: no screenshot %s: %s", prefix, v->status);
        return EXIT_OK;
    }
    if (v->method_index < 0) {
        uint64_t spp = 0;
        img = view_ref_take(&v->ref, 1, &spp);
        if (!img)
            return cli_fail(EXIT_RUN, "view: screenshot: the reference has no sample yet");
        v->ref_spp = spp;
    } else {
        img = gi_gpu_read_texture(v->target_tex, v->width, v->height);
        if (!img)
            return cli_fail(EXIT_RUN, "out of memory reading the image back");
        for (size_t i = 0; i < (size_t)v->width * v->height; i++)
            img->rgba[4 * i + 3] = 1.0f;
    }
    size_t n = strlen(prefix) + 8;
    char *path = malloc(n);
    if (!path) {
        gi_image_free(img);
        return cli_fail(EXIT_RUN, "out of memory");
    }
    gi_error err;
    gi_image_write_opts wo = {v->exposure};
    const char *ext[2] = {".exr", ".png"};
    int rc = EXIT_OK;
    for (int k = 0; k < 2 && rc == EXIT_OK; k++) {
        snprintf(path, n, "%s%s", prefix, ext[k]);
        if (gi_image_write(path, img, &wo, &err) != GI_OK)
            rc = cli_fail(EXIT_RUN, "view: %s", err.text);
    }
    gi_image_free(img);
    if (rc == EXIT_OK) {
        snprintf(path, n, "%s.json", prefix);
        rc = view_save(v, path);
    }
    if (rc == EXIT_OK)
        if (gi_log_get_level() >= GI_LOG_WARN)
            printf("view: screenshot %s.exr, .png, .json\n", prefix);
    free(path);
    return rc;
}

/* The next free DIR/gibench_view_NNNN (keys P and V). */
static void next_name(viewer *v, char *out, size_t size)
{
    for (;;) {
        snprintf(out, size, "%s/gibench_view_%04u", v->shot_dir, v->shot_counter++);
        char probe[4200];
        snprintf(probe, sizeof probe, "%s.json", out);
        FILE *f = fopen(probe, "rb");
        if (!f)
            return;
        fclose(f);
    }
}

/* ---- input ---- */

static int method_count(const viewer *v)
{
    return (int)v->reg->count;
}

int view_key(viewer *v, int key, int mods)
{
    float step = 0.05f * v->dist;
    gi_vec3 eye = view_eye(v);
    gi_vec3 fwd = gi_v3_normalize(gi_v3_sub(v->center, eye));
    gi_vec3 right = gi_v3_normalize(gi_v3_cross(fwd, gi_v3(0, 1, 0)));
    v->need_display = 1;
    switch (key) {
    case GLFW_KEY_ESCAPE:
        v->quit = 1;
        return EXIT_OK;
    case GLFW_KEY_M:
    case GLFW_KEY_N: {
        /* through every plugin, then the reference, and round */
        int n = method_count(v) + 1, cur = v->method_index < 0 ? n - 1 : v->method_index;
        int back = key == GLFW_KEY_N || (mods & GLFW_MOD_SHIFT);
        int next = (cur + (back ? n - 1 : 1)) % n;
        v->param_sel = 0;
        return view_select(v, next == n - 1 ? -1 : next);
    }
    case GLFW_KEY_R:
        if (v->method_index < 0)
            return view_select(v, v->last_method < 0 ? 0 : v->last_method);
        v->last_method = v->method_index;
        return view_select(v, -1);
    case GLFW_KEY_TAB:
        v->param_sel =
            v->params && v->params->count ? (v->param_sel + 1) % (int)v->params->count : 0;
        return EXIT_OK;
    case GLFW_KEY_PAGE_UP:
    case GLFW_KEY_PAGE_DOWN:
        return v->method_index >= 0 ? step_param(v, key == GLFW_KEY_PAGE_UP ? 1 : -1) : EXIT_OK;
    case GLFW_KEY_X:
        v->split = (v->split + 1) % 3;
        reference_as_needed(v);
        return EXIT_OK;
    case GLFW_KEY_SPACE:
        v->playing = !v->playing;
        v->last_tick = gi_now();
        return EXIT_OK;
    case GLFW_KEY_PERIOD:
        return set_time(v, v->time + 1.0f / 30.0f);
    case GLFW_KEY_COMMA:
        return set_time(v, fmaxf(0.0f, v->time - 1.0f / 30.0f));
    case GLFW_KEY_EQUAL:
    case GLFW_KEY_RIGHT_BRACKET:
        v->exposure = fminf(64.0f, v->exposure + 0.5f);
        return EXIT_OK;
    case GLFW_KEY_MINUS:
    case GLFW_KEY_LEFT_BRACKET:
        v->exposure = fmaxf(-64.0f, v->exposure - 0.5f);
        return EXIT_OK;
    case GLFW_KEY_L:
        return view_light_select(v);
    case GLFW_KEY_O:
        v->show_overlay = !v->show_overlay;
        return EXIT_OK;
    case GLFW_KEY_C:
        view_camera_from_scene(
            v, v->scene->camera_count ? (v->scene_camera + 1) % (int)v->scene->camera_count : -1);
        return EXIT_OK;
    case GLFW_KEY_W:
    case GLFW_KEY_S:
        if (mods & GLFW_MOD_SHIFT)
            return view_light_move(v, gi_v3_scale(fwd, key == GLFW_KEY_W ? 1.0f : -1.0f));
        v->center = gi_v3_add(v->center, gi_v3_scale(fwd, key == GLFW_KEY_W ? step : -step));
        break;
    case GLFW_KEY_A:
    case GLFW_KEY_D:
        if (mods & GLFW_MOD_SHIFT)
            return view_light_move(v, gi_v3_scale(right, key == GLFW_KEY_D ? 1.0f : -1.0f));
        v->center = gi_v3_add(v->center, gi_v3_scale(right, key == GLFW_KEY_D ? step : -step));
        break;
    case GLFW_KEY_Q:
    case GLFW_KEY_E:
        if (mods & GLFW_MOD_SHIFT)
            return view_light_move(v, gi_v3(0, key == GLFW_KEY_E ? 1.0f : -1.0f, 0));
        v->center = gi_v3_add(v->center, gi_v3(0, key == GLFW_KEY_E ? step : -step, 0));
        break;
    case GLFW_KEY_LEFT:
    case GLFW_KEY_RIGHT:
        v->yaw += key == GLFW_KEY_LEFT ? -0.1f : 0.1f;
        break;
    case GLFW_KEY_UP:
    case GLFW_KEY_DOWN:
        v->pitch += key == GLFW_KEY_UP ? 0.1f : -0.1f;
        break;
    case GLFW_KEY_P: {
        char name[4096];
        next_name(v, name, sizeof name);
        return view_screenshot(v, name);
    }
    case GLFW_KEY_V: {
        char name[4096], path[4200];
        next_name(v, name, sizeof name);
        snprintf(path, sizeof path, "%s.json", name);
        return view_save(v, path);
    }
    default:
        return EXIT_OK;
    }
    view_changed(v);
    return EXIT_OK;
}

void view_button(viewer *v, int button, int press, double x, double y, int mods)
{
    if (!press && v->drag_object) {
        v->drag_object = 0;
        return;
    }
    if (press && button == GLFW_MOUSE_BUTTON_LEFT && (mods & (GLFW_MOD_SHIFT | GLFW_MOD_CONTROL))) {
        /* Shift: move the selected light (key L), or else the object under
         * the mouse, in the view plane; Ctrl: rotate the object */
        int rc = v->sel_light >= 0 && !(mods & GLFW_MOD_CONTROL)
                     ? view_light_pick(v, x, y)
                     : view_pick(v, x, y, (mods & GLFW_MOD_CONTROL) ? 2 : 1);
        if (rc != EXIT_OK && v->script)
            v->exit_code = rc;
        v->mx = x;
        v->my = y;
        v->need_display = 1;
        return;
    }
    int ww = 0, wh = 0;
    glfwGetWindowSize(v->win, &ww, &wh);
    if (press && button == GLFW_MOUSE_BUTTON_LEFT && v->split && v->method_index >= 0 && ww > 0 &&
        fabs(x - v->divider * ww) <= 6.0) {
        v->dragging_divider = 1;
        return;
    }
    if (!press && v->dragging_divider) {
        v->dragging_divider = 0;
        return;
    }
    if (press) {
        v->drag_button = button;
        v->mx = x;
        v->my = y;
    } else if (button == v->drag_button) {
        v->drag_button = -1;
    }
}

void view_cursor(viewer *v, double x, double y)
{
    double dx = x - v->mx, dy = y - v->my;
    v->mx = x;
    v->my = y;
    if (v->drag_object) {
        if (dx == 0 && dy == 0)
            return;
        int rc = view_drag_to(v, x, y);
        if (rc != EXIT_OK)
            v->exit_code = rc;
        return;
    }
    if (v->dragging_divider) {
        int ww = 0, wh = 0;
        glfwGetWindowSize(v->win, &ww, &wh);
        v->divider = ww > 0 ? fminf(1.0f, fmaxf(0.0f, (float)(x / ww))) : 0.5f;
        v->need_display = 1;
        return;
    }
    if (v->drag_button < 0 || (dx == 0 && dy == 0))
        return;
    if (v->drag_button == GLFW_MOUSE_BUTTON_LEFT) { /* orbit */
        v->yaw -= (float)dx * 0.01f;
        v->pitch += (float)dy * 0.01f;
    } else if (v->drag_button == GLFW_MOUSE_BUTTON_RIGHT) { /* dolly */
        v->dist *= expf((float)dy * 0.01f);
    } else { /* pan */
        gi_vec3 eye = view_eye(v);
        gi_vec3 fwd = gi_v3_normalize(gi_v3_sub(v->center, eye));
        gi_vec3 right = gi_v3_normalize(gi_v3_cross(fwd, gi_v3(0, 1, 0)));
        gi_vec3 up = gi_v3_cross(right, fwd);
        float s = 2.0f * v->dist * tanf(0.5f * v->yfov) / (float)v->height;
        v->center = gi_v3_add(v->center, gi_v3_add(gi_v3_scale(right, -(float)dx * s),
                                                   gi_v3_scale(up, (float)dy * s)));
    }
    view_changed(v);
}

void view_scroll(viewer *v, double dy)
{
    v->dist *= expf(-(float)dy * 0.1f);
    view_changed(v);
}

static viewer *from(GLFWwindow *w)
{
    return glfwGetWindowUserPointer(w);
}

static void on_key(GLFWwindow *w, int key, int scancode, int action, int mods)
{
    (void)scancode;
    viewer *v = from(w);
    if (action == GLFW_RELEASE || v->script)
        return; /* a scripted run takes its events from the script only */
    int rc = view_key(v, key, mods);
    if (rc != EXIT_OK && v->exit_code == EXIT_OK)
        v->status_error = 1; /* interactive: keep running; the message was printed */
}

static void on_button(GLFWwindow *w, int button, int action, int mods)
{
    viewer *v = from(w);
    if (v->script)
        return;
    double x, y;
    glfwGetCursorPos(w, &x, &y);
    view_button(v, button, action == GLFW_PRESS, x, y, mods);
}

static void on_cursor(GLFWwindow *w, double x, double y)
{
    viewer *v = from(w);
    if (!v->script)
        view_cursor(v, x, y);
}

static void on_scroll(GLFWwindow *w, double dx, double dy)
{
    (void)dx;
    viewer *v = from(w);
    if (!v->script)
        view_scroll(v, dy);
}

static void on_size(GLFWwindow *w, int width, int height)
{
    viewer *v = from(w);
    v->win_w = width;
    v->win_h = height;
    v->need_display = 1;
}

static void on_refresh(GLFWwindow *w)
{
    from(w)->need_display = 1;
}

static void on_glfw_error(int code, const char *msg)
{
    gi_log(GI_LOG_DEBUG, "GLFW error %d: %s", code, msg);
}

/* ---- options and main loop ---- */

static int parse_opts(int argc, char **argv, viewer *v)
{
    v->width = 512;
    v->height = 512;
    v->seed = 1;
    v->shot_dir = ".";
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i];
        const char *val = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--scene") || !strcmp(a, "--method") || !strcmp(a, "--size") ||
            !strcmp(a, "--script") || !strcmp(a, "--screenshot-dir") || !strcmp(a, "--param") ||
            !strcmp(a, "--camera") || !strcmp(a, "--exposure") || !strcmp(a, "--time") ||
            !strcmp(a, "--seed")) {
            if (!val)
                return cli_fail(EXIT_USAGE, "view: %s needs a value", a);
            i++;
        } else {
            return cli_fail(EXIT_USAGE, "view: unknown argument '%s' (see gibench help view)", a);
        }
        unsigned long u;
        if (!strcmp(a, "--scene"))
            v->scene_path = val;
        else if (!strcmp(a, "--method"))
            v->start_method = val;
        else if (!strcmp(a, "--script"))
            v->script_path = val;
        else if (!strcmp(a, "--screenshot-dir"))
            v->shot_dir = val;
        else if (!strcmp(a, "--camera"))
            v->camera_name = val;
        else if (!strcmp(a, "--size")) {
            if (!cli_parse_size(val, &v->width, &v->height))
                return cli_fail(EXIT_USAGE, "view: --size '%s' is not WxH with 1..16384 each", val);
        } else if (!strcmp(a, "--param")) {
            if (v->opt_param_count == VIEW_FILE_MAX_PARAMS)
                return cli_fail(EXIT_USAGE, "view: at most %d --param", VIEW_FILE_MAX_PARAMS);
            v->opt_params[v->opt_param_count++] = val;
        } else if (!strcmp(a, "--exposure")) {
            if (!cli_parse_exposure(val, &v->exposure))
                return cli_fail(EXIT_USAGE,
                                "view: --exposure '%s' is not a number of stops in -64..64", val);
        } else if (!strcmp(a, "--time")) {
            if (!cli_parse_float(val, &v->time) || v->time < 0)
                return cli_fail(EXIT_USAGE, "view: --time '%s' is not a non-negative number", val);
        } else if (!strcmp(a, "--seed")) {
            if (!cli_parse_uint(val, 0, 0xFFFFFFFFul, &u))
                return cli_fail(EXIT_USAGE, "view: --seed '%s' is not a 32-bit unsigned integer",
                                val);
            v->seed = (uint32_t)u;
        }
    }
    if (!v->scene_path)
        return cli_fail(EXIT_USAGE, "view: --scene is required");
    return EXIT_OK;
}

static int setup(viewer *v)
{
    gi_error err;
    v->reg = cli_load_plugins(1);
    if (!v->reg)
        return cli_fail(EXIT_RUN, "out of memory");
    if (v->reg->count == 0)
        return cli_fail(EXIT_RUN, "view: no method plugin found (see gibench methods)");
    int start = 0;
    if (v->start_method) {
        start = -1;
        for (uint32_t i = 0; i < v->reg->count; i++)
            if (!strcmp(v->reg->items[i].method->id, v->start_method))
                start = (int)i;
        if (start < 0 && strcmp(v->start_method, "reference"))
            return cli_fail(EXIT_USAGE,
                            "view: no method '%s' (see gibench methods; or 'reference')",
                            v->start_method);
        /* parameters are checked before a window opens */
        if (start >= 0) {
            const gi_method *m = v->reg->items[start].method;
            gi_params *p =
                gi_params_parse(m->id, m->params, v->opt_params, v->opt_param_count, &err);
            if (!p)
                return cli_fail(EXIT_USAGE, "%s", err.text);
            gi_params_free(p);
        }
    }
    if (v->script_path) {
        v->script = fopen(v->script_path, "r");
        if (!v->script)
            return cli_fail(EXIT_USAGE, "view: cannot read the script %s", v->script_path);
    }
    v->scene = gi_scene_load(v->scene_path, &err);
    if (!v->scene)
        return cli_fail(EXIT_USAGE, "%s", err.text);
    int camera = v->scene->camera_count ? 0 : -1;
    if (v->camera_name) {
        camera = gi_scene_find_camera(v->scene, v->camera_name);
        if (camera < 0)
            return cli_fail(EXIT_USAGE,
                            "view: %s has no camera '%s' (%u cameras; use a name or #k)",
                            v->scene_path, v->camera_name, v->scene->camera_count);
    }
    v->cache_dir = gi_cache_dir(&err);
    if (!v->cache_dir)
        return cli_fail(EXIT_RUN, "%s", err.text);
    if (!view_move_init(v))
        return cli_fail(EXIT_RUN, "out of memory");

    glfwSetErrorCallback(on_glfw_error);
    if (!glfwInit())
        return cli_fail(
            EXIT_RUN, "view: GLFW cannot start (no display? run it under xvfb-run or set DISPLAY)");
    v->glfw_ready = 1;
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    v->win = glfwCreateWindow((int)v->width, (int)v->height, "gibench view", NULL, NULL);
    if (!v->win)
        return cli_fail(EXIT_RUN, "view: no window with an OpenGL 4.5 core context (GLFW)");
    glfwMakeContextCurrent(v->win);
    view_pin_gl_driver();
    glfwSwapInterval(v->script ? 0 : 1);
    glfwSetWindowUserPointer(v->win, v);
    glfwSetKeyCallback(v->win, on_key);
    glfwSetMouseButtonCallback(v->win, on_button);
    glfwSetCursorPosCallback(v->win, on_cursor);
    glfwSetScrollCallback(v->win, on_scroll);
    glfwSetWindowRefreshCallback(v->win, on_refresh);
    glfwSetWindowSizeCallback(v->win, on_size);
    glfwGetWindowSize(v->win, &v->win_w, &v->win_h);

    gi_gpu_desc gd = {0};
    gd.adopt_current = 1;
    v->gpu = gi_gpu_create(&gd, &err);
    if (!v->gpu)
        return cli_fail(EXIT_RUN, "view: %s", err.text);
    v->gs = gi_gpu_scene_upload(v->gpu, v->scene, &err);
    if (!v->gs)
        return cli_fail(EXIT_RUN, "%s", err.text);
    gi_gpu_scene_set_time(v->gs, v->time);
    v->prepared_time = v->time;

    glCreateTextures(GL_TEXTURE_2D, 1, &v->target_tex);
    glTextureStorage2D(v->target_tex, 1, GL_RGBA32F, (GLsizei)v->width, (GLsizei)v->height);
    glTextureParameteri(v->target_tex, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(v->target_tex, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glCreateFramebuffers(1, &v->target_fbo);
    glNamedFramebufferTexture(v->target_fbo, GL_COLOR_ATTACHMENT0, v->target_tex, 0);
    const float black[4] = {0, 0, 0, 1};
    glClearNamedFramebufferfv(v->target_fbo, GL_COLOR, 0, black);
    glCreateTextures(GL_TEXTURE_2D, 1, &v->ref_tex);
    glTextureStorage2D(v->ref_tex, 1, GL_RGBA32F, (GLsizei)v->width, (GLsizei)v->height);
    glTextureParameteri(v->ref_tex, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(v->ref_tex, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glClearTexImage(v->ref_tex, 0, GL_RGBA, GL_FLOAT, black);
    int rc = build_display(v);
    if (rc != EXIT_OK)
        return rc;
    if (!view_overlay_init(v))
        return cli_fail(EXIT_RUN, "view: the overlay's shader or buffers could not be made");
    v->show_overlay = 1;
    if (!view_ref_start(&v->ref, v->scene))
        return cli_fail(EXIT_RUN, "view: cannot start the reference's worker thread");

    v->method_index = -2; /* none yet */
    v->divider = 0.5f;
    v->drag_button = -1;
    v->last_method = start >= 0 ? start : 0;
    view_camera_from_scene(v, camera);
    return view_select(v, start);
}

/* The method's target and the reference's texture at w x h: the window
 * was resized, and the image is rendered again at its new size. */
static void resize_targets(viewer *v, uint32_t w, uint32_t h)
{
    v->width = w;
    v->height = h;
    glDeleteTextures(1, &v->target_tex);
    glDeleteTextures(1, &v->ref_tex);
    GLuint *tex[2] = {&v->target_tex, &v->ref_tex};
    const float black[4] = {0, 0, 0, 1};
    for (int i = 0; i < 2; i++) {
        glCreateTextures(GL_TEXTURE_2D, 1, tex[i]);
        glTextureStorage2D(*tex[i], 1, GL_RGBA32F, (GLsizei)w, (GLsizei)h);
        glTextureParameteri(*tex[i], GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTextureParameteri(*tex[i], GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        glClearTexImage(*tex[i], 0, GL_RGBA, GL_FLOAT, black);
    }
    glNamedFramebufferTexture(v->target_fbo, GL_COLOR_ATTACHMENT0, v->target_tex, 0);
    if (gi_log_get_level() >= GI_LOG_WARN)
        printf("view: resized to %ux%u\n", w, h);
    view_changed(v);
}

static void teardown(viewer *v)
{
    view_ref_stop(&v->ref);
    unload_method(v);
    view_move_free(v);
    gi_timer_free(v->timer);
    if (v->win) {
        if (v->display_prog)
            glDeleteProgram(v->display_prog);
        if (v->display_vao)
            glDeleteVertexArrays(1, &v->display_vao);
        if (v->target_fbo)
            glDeleteFramebuffers(1, &v->target_fbo);
        if (v->target_tex)
            glDeleteTextures(1, &v->target_tex);
        if (v->ref_tex)
            glDeleteTextures(1, &v->ref_tex);
        view_overlay_free(v);
        gi_gpu_scene_free(v->gs);
        gi_gpu_destroy(v->gpu);
        glfwDestroyWindow(v->win);
    }
    if (v->glfw_ready)
        glfwTerminate();
    gi_scene_free(v->scene);
    gi_plugins_free(v->reg);
    free(v->cache_dir);
    free(v->window_shot_buf);
    view_file_free(&v->kv);
    if (v->script)
        fclose(v->script);
}

/* Whether the method shown needs another frame now: something changed, or
 * it is progressive and still accumulating (up to 4096 frames). */
static int wants_frame(const viewer *v)
{
    if (v->method_index < 0 || !v->inst || v->stale)
        return 0;
    if (v->need_render)
        return 1;
    return (v->m->caps & GI_CAP_PROGRESSIVE) && v->frame_index < 4096;
}

static int loop(viewer *v)
{
    while (!v->quit && !glfwWindowShouldClose(v->win) && !cli_interrupted) {
        int fw = 0, fh = 0;
        glfwGetFramebufferSize(v->win, &fw, &fh);
        if (fw > 0 && fh > 0 && ((uint32_t)fw != v->width || (uint32_t)fh != v->height) &&
            fw <= 16384 && fh <= 16384)
            resize_targets(v, (uint32_t)fw, (uint32_t)fh);
        if (v->playing) {
            double now = gi_now();
            float dt = (float)(now - v->last_tick);
            v->last_tick = now;
            if (v->script)
                dt = 1.0f /
                     30.0f; /* a scripted run steps the animation by frames, not by the clock */
            int rc = set_time(v, v->time + dt);
            if (rc != EXIT_OK)
                return rc;
        }
        if (wants_frame(v)) {
            v->need_render = 0;
            int rc = render_method(v);
            if (rc != EXIT_OK)
                return rc;
            v->frames_since_event++;
        }
        if (v->method_index < 0 || v->stale)
            v->need_render = 0; /* the worker renders, or the method shows nothing; the change went
                                   with view_changed */
        if (v->method_index < 0 || v->split) {
            poll_reference(v);
            char err[GI_ERROR_MAX];
            view_ref_error(&v->ref, err, sizeof err);
            if (err[0])
                return cli_fail(EXIT_RUN, "view: reference: %s", err);
        }
        if (v->need_display)
            display(v);
        if (v->exit_code != EXIT_OK)
            return v->exit_code;
        if (v->script) {
            glfwPollEvents();
            int rc = view_script_step(v);
            if (rc != EXIT_OK)
                return rc;
        } else if (v->playing || wants_frame(v) || v->dragging_divider) {
            glfwPollEvents();
        } else {
            glfwWaitEventsTimeout(v->method_index < 0 ? 0.05 : 0.25);
        }
    }
    return cli_interrupted ? cli_fail(EXIT_RUN, "view: interrupted") : EXIT_OK;
}

int cmd_view(int argc, char **argv)
{
    viewer *v = calloc(1, sizeof *v);
    if (!v)
        return cli_fail(EXIT_RUN, "out of memory");
    int rc = parse_opts(argc, argv, v);
    if (rc == EXIT_OK) {
        cli_install_signal_handlers();
        rc = setup(v);
        if (rc == EXIT_OK)
            rc = loop(v);
        if (rc == EXIT_OK && gi_log_get_level() >= GI_LOG_WARN && v->gpu)
            printf("view: %llu method frames, mean %.3g ms; %llu redraws, mean %.3g ms of the "
                   "viewer's own "
                   "(tone map, overlay, swap), of which the overlay %.3g ms; %s\n",
                   (unsigned long long)v->n_frames,
                   v->n_frames ? v->sum_frame_ms / (double)v->n_frames : 0.0,
                   (unsigned long long)v->n_displays,
                   v->n_displays ? v->sum_display_ms / (double)v->n_displays : 0.0,
                   v->n_displays ? v->sum_overlay_ms / (double)v->n_displays : 0.0,
                   gi_gpu_renderer(v->gpu));
    }
    teardown(v);
    free(v);
    return rc;
}
