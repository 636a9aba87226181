/* gibench view: the method shown (docs/commands.md "gibench view"): created and
 * prepared as `gibench render` does it, made again when a parameter key
 * changes a value, one frame rendered and timed per call, and told of the
 * animation's time through update(). */
#include "view.h"

#include "gi/timer.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void view_unload_method(viewer *v)
{
    if (v->inst)
        v->m->destroy(v->inst);
    v->inst = NULL;
    if (v->host_ready)
        cli_host_free(v->host);
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
    view_unload_method(v);
    v->method_index = index;
    v->frame_index = 0;
    v->need_render = v->need_display = 1;
    view_reference_as_needed(v);
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
    cli_host_init(v->host, v->m->id, v->cache_dir, v->gs, gi_gpu_renderer(v->gpu),
                  gi_gpu_is_software(v->gpu));
    v->host_ready = 1;
    v->host_progress = v->host->host.progress; /* the terminal line, and a bar in the window */
    v->host->host.progress = view_overlay_progress;
    view_overlay_progress_owner(v);
    gi_timer_free(v->timer);
    v->timer = gi_timer_create(GI_TIMER_CPU_FINISH, 0);
    v->timer_frames = 0;
    v->stage_count = 0;
    gi_error cerr;
    gi_result res = gi_method_create(v->m, &v->host->host, v->params, &v->inst, &cerr);
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
    cli_host_progress_end(v->host);
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
int view_step_param(viewer *v, int dir)
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
    return view_remake(v, s);
}

int view_remake(viewer *v, char *params)
{
    if (!params || !view_file_set_params(&v->kv, params)) {
        free(params);
        return cli_fail(EXIT_RUN, "out of memory");
    }
    free(params);
    snprintf(v->kv_method, sizeof v->kv_method, "%s", v->m->id);
    int sel = v->param_sel;
    int rc = view_select(v, v->method_index);
    v->param_sel = sel;
    return rc;
}

/* Renders one frame of the method into the target (timed, with glFinish). */
int view_render_method(viewer *v)
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
    v->host->timer = v->timer;
    if (v->timer)
        gi_timer_frame_begin(v->timer);
    double t0 = gi_now();
    gi_result res = v->m->render(v->inst, &view, &target);
    glFinish();
    v->last_view = view;
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
    v->host->timer = NULL;
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
    v->err_dirty = 1;
    if (!v->second_swapped)
        v->frame_hist[v->frame_hist_n++ % VIEW_FRAME_HISTORY] = v->frame_ms;
    return EXIT_OK;
}

/* Advances the animation to time t and tells the method (update()). */
int view_set_time(viewer *v, float t)
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
    return view_second_set_time(v);
}
