/* gibench view: the interactive viewer (docs/commands.md "gibench view"). A GLFW
 * window with an OpenGL 4.5 core context, adopted by the core (gi_gpu_desc
 * .adopt_current), so that the methods render through the same plugin path
 * as `gibench render` and their image is shown without a copy; the
 * progressive reference runs on a worker thread (view_ref.h). --script
 * replays key and mouse events (view_script.c) for the tests.
 *
 * This file holds the options, the setup and the main loop; the camera,
 * the method shown, the display, screenshots and input are in view_*.c
 * (view.h). */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"
#include "view.h"
#include "view_panels.h"

#include "gi/cache.h"
#include "gi/log.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void on_glfw_error(int code, const char *msg)
{
    gi_log(GI_LOG_DEBUG, "GLFW error %d: %s", code, msg);
}

static int parse_opts(int argc, char **argv, viewer *v)
{
    v->width = 512;
    v->height = 512;
    v->seed = 1;
    v->shot_dir = ".";
    v->show_panels = -1; /* on, but off under --script unless --panels on */
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i];
        const char *val = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--scene") || !strcmp(a, "--method") || !strcmp(a, "--size") ||
            !strcmp(a, "--script") || !strcmp(a, "--screenshot-dir") || !strcmp(a, "--param") ||
            !strcmp(a, "--camera") || !strcmp(a, "--exposure") || !strcmp(a, "--time") ||
            !strcmp(a, "--seed") || !strcmp(a, "--panels")) {
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
        else if (!strcmp(a, "--panels")) {
            if (strcmp(val, "on") && strcmp(val, "off"))
                return cli_fail(EXIT_USAGE, "view: --panels '%s' is not on or off", val);
            v->show_panels = !strcmp(val, "on");
        } else if (!strcmp(a, "--size")) {
            if (!cli_parse_size(val, &v->width, &v->height))
                return cli_fail(EXIT_USAGE, "view: --size '%s' is not WxH with " GI_IMAGE_SIZE_RULE,
                                val);
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
    if (v->show_panels < 0)
        v->show_panels = v->script_path ? 0 : 1;
    return EXIT_OK;
}

/* The plugins, and the method to start with in *start (-1: the reference);
 * its --param values are checked before a window opens. */
static int find_start_method(viewer *v, int *start)
{
    gi_error err;
    v->reg = cli_load_plugins(1);
    if (!v->reg)
        return cli_fail(EXIT_RUN, "out of memory");
    if (v->reg->count == 0)
        return cli_fail(EXIT_RUN, "view: no method plugin found (see gibench methods)");
    *start = 0;
    if (v->start_method) {
        *start = -1;
        for (uint32_t i = 0; i < v->reg->count; i++)
            if (!strcmp(v->reg->items[i].method->id, v->start_method))
                *start = (int)i;
        if (*start < 0 && strcmp(v->start_method, "reference"))
            return cli_fail(EXIT_USAGE,
                            "view: no method '%s' (see gibench methods; or 'reference')",
                            v->start_method);
        /* parameters are checked before a window opens */
        if (*start >= 0) {
            const gi_method *m = v->reg->items[*start].method;
            gi_params *p =
                gi_params_parse(m->id, m->params, v->opt_params, v->opt_param_count, &err);
            if (!p)
                return cli_fail(EXIT_USAGE, "%s", err.text);
            gi_params_free(p);
        }
    }
    return EXIT_OK;
}

/* The script, the scene and the camera to start from (*camera), the cache
 * directory and the state for moving nodes: all that needs no window. */
static int load_inputs(viewer *v, int *camera)
{
    gi_error err;
    if (v->script_path) {
        v->script = fopen(v->script_path, "r");
        if (!v->script)
            return cli_fail(EXIT_USAGE, "view: cannot read the script %s", v->script_path);
    }
    v->scene = gi_scene_load(v->scene_path, &err);
    if (!v->scene)
        return cli_fail(EXIT_USAGE, "%s", err.text);
    *camera = v->scene->camera_count ? 0 : -1;
    if (v->camera_name) {
        *camera = gi_scene_find_camera(v->scene, v->camera_name);
        if (*camera < 0)
            return cli_fail(EXIT_USAGE,
                            "view: %s has no camera '%s' (%u cameras; use a name or #k)",
                            v->scene_path, v->camera_name, v->scene->camera_count);
    }
    v->cache_dir = gi_cache_dir(&err); /* optional, as for render */
    if (!v->cache_dir)
        fprintf(stderr, "gibench: warning: %s; rendering without the cache\n", err.text);
    if (!view_move_init(v))
        return cli_fail(EXIT_RUN, "out of memory");
    return EXIT_OK;
}

/* The window with its OpenGL 4.5 core context made current, and the input
 * callbacks. */
static int open_window(viewer *v)
{
    glfwSetErrorCallback(on_glfw_error);
    if (!glfwInit())
        return cli_fail(
            EXIT_RUN, "view: GLFW cannot start (no display? run it under xvfb-run or set DISPLAY)");
    v->glfw_ready = 1;
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    /* the panels go right of the image, which keeps the size asked for */
    int pw = v->show_panels ? VIEW_PANEL_W : 0;
    v->win = glfwCreateWindow((int)v->width + pw, (int)v->height, "gibench view", NULL, NULL);
    if (!v->win)
        return cli_fail(EXIT_RUN, "view: no window with an OpenGL 4.5 core context (GLFW)");
    glfwMakeContextCurrent(v->win);
    view_pin_gl_driver();
    glfwSwapInterval(v->script ? 0 : 1);
    view_input_listen(v);
    glfwGetWindowSize(v->win, &v->win_w, &v->win_h);
    view_region_update(v);
    return EXIT_OK;
}

/* The core on the window's context, and the scene uploaded at --time. */
static int upload_scene(viewer *v)
{
    gi_error err;
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
    return EXIT_OK;
}

/* The method's target and the reference's texture (black), the display
 * shader, the overlay and the reference's worker thread. */
static int make_display(viewer *v)
{
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
    int rc = view_build_display(v);
    if (rc != EXIT_OK)
        return rc;
    view_buffer_upload(v);
    if (!view_overlay_init(v))
        return cli_fail(EXIT_RUN, "view: the overlay's shader or buffers could not be made");
    v->show_overlay = 1;
    /* Dear ImGui starts with the first panels shown (view_panels_draw) */
    if (v->show_panels && !view_panels_init(v))
        return cli_fail(EXIT_RUN, "view: Dear ImGui could not start on the window's context");
    if (!view_ref_start(&v->ref, v->scene))
        return cli_fail(EXIT_RUN, "view: cannot start the reference's worker thread");
    return EXIT_OK;
}

/* Everything up to the first method shown. EXIT_OK, or an exit code after
 * printing why (teardown frees what was made). */
static int setup(viewer *v)
{
    int start = 0, camera = -1;
    int rc = find_start_method(v, &start);
    if (rc == EXIT_OK)
        rc = load_inputs(v, &camera);
    if (rc == EXIT_OK)
        rc = open_window(v);
    if (rc == EXIT_OK)
        rc = upload_scene(v);
    if (rc == EXIT_OK)
        rc = make_display(v);
    if (rc != EXIT_OK)
        return rc;
    v->method_index = -2; /* none yet */
    v->host = &v->host_store[0];
    v->second.method_index = -1;
    v->zoom = 1.0f;
    v->cursor_px = v->cursor_py = -1;
    v->relmse = NAN;
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

/* The image's size in framebuffer pixels: the window less the panels. */
static void view_image_size(viewer *v, int *w, int *h)
{
    int ww = 0, wh = 0;
    glfwGetFramebufferSize(v->win, w, h);
    glfwGetWindowSize(v->win, &ww, &wh);
    view_region_update(v);
    if (v->show_panels)
        *w -= ww > 0 ? (int)lround((double)VIEW_PANEL_W * *w / ww) : VIEW_PANEL_W;
}

int view_toggle_panels(viewer *v)
{
    int ww = 0, wh = 0;
    glfwGetWindowSize(v->win, &ww, &wh);
    v->show_panels = !v->show_panels;
    glfwSetWindowSize(v->win, ww + (v->show_panels ? VIEW_PANEL_W : -VIEW_PANEL_W), wh);
    view_region_update(v);
    view_reference_as_needed(v);
    v->need_display = 1;
    return EXIT_OK;
}

static void teardown(viewer *v)
{
    view_ref_stop(&v->ref);
    if (v->host)
        view_second_unload(v);
    view_unload_method(v);
    gi_image_free(v->ref_img);
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
        GLuint more[3] = {v->second.target_tex, v->buf_tex, v->second.target_fbo};
        glDeleteTextures(2, more);
        glDeleteFramebuffers(1, &more[2]);
        view_panels_free(v);
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
        view_image_size(v, &fw, &fh);
        if (fw > 0 && fh > 0 && ((uint32_t)fw != v->width || (uint32_t)fh != v->height) &&
            gi_image_size_ok((unsigned)fw, (unsigned)fh))
            resize_targets(v, (uint32_t)fw, (uint32_t)fh);
        if (v->playing) {
            double now = gi_now();
            float dt = (float)(now - v->last_tick);
            v->last_tick = now;
            if (v->script)
                dt = 1.0f /
                     30.0f; /* a scripted run steps the animation by frames, not by the clock */
            int rc = view_set_time(v, v->time + dt);
            if (rc != EXIT_OK)
                return rc;
        }
        if (wants_frame(v)) {
            v->need_render = 0;
            int rc = view_render_method(v);
            if (rc != EXIT_OK)
                return rc;
            v->frames_since_event++;
            if (v->source == VIEW_SRC_BUFFER)
                view_buffer_upload(v); /* the buffer of this frame */
        }
        if (view_second_wants_frame(v)) {
            int rc = view_second_render(v);
            if (rc != EXIT_OK)
                return rc;
        }
        if (v->method_index < 0 || v->stale)
            v->need_render = 0; /* the worker renders, or the method shows nothing; the change went
                                   with view_changed */
        if (view_needs_reference(v)) {
            view_poll_reference(v);
            char err[GI_ERROR_MAX];
            view_ref_error(&v->ref, err, sizeof err);
            if (err[0])
                return cli_fail(EXIT_RUN, "view: reference: %s", err);
        }
        if (v->need_display)
            view_display(v);
        view_panels_apply(v);
        if (v->exit_code != EXIT_OK)
            return v->exit_code;
        if (v->script) {
            glfwPollEvents();
            int rc = view_script_step(v);
            if (rc != EXIT_OK)
                return rc;
        } else if (v->playing || wants_frame(v) || view_second_wants_frame(v) ||
                   v->dragging_divider) {
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
