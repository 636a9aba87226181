/* gibench view: the second method of the split (docs/commands.md "gibench
 * view", split mode 3): any installed method, rendered with the same view
 * as the first and shown right of the divider. It owns a view_slot (its
 * instance, parameters, host and target); to be created, rendered or told
 * of a change it is swapped into the viewer's fields, so that it goes
 * through exactly the code of the first method (view_method.c,
 * view_move.c), moves and animation included. */
#include "view.h"

#include "gi/timer.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <stdio.h>
#include <string.h>

#define SWAP(T, a, b)                                                                              \
    do {                                                                                           \
        T tmp_ = (a);                                                                              \
        (a) = (b);                                                                                 \
        (b) = tmp_;                                                                                \
    } while (0)

void view_slot_swap(viewer *v)
{
    view_slot *s = &v->second;
    SWAP(int, v->method_index, s->method_index);
    SWAP(const gi_method *, v->m, s->m);
    SWAP(void *, v->inst, s->inst);
    SWAP(gi_view, v->last_view, s->last_view);
    SWAP(gi_params *, v->params, s->params);
    SWAP(cli_host *, v->host, s->host);
    SWAP(int, v->host_ready, s->host_ready);
    char status[sizeof v->status];
    memcpy(status, v->status, sizeof status);
    memcpy(v->status, s->status, sizeof status);
    memcpy(s->status, status, sizeof status);
    SWAP(uint32_t, v->frame_index, s->frame_index);
    SWAP(int, v->stale, s->stale);
    SWAP(int, v->need_render, s->need_render);
    SWAP(GLuint, v->target_tex, s->target_tex);
    SWAP(GLuint, v->target_fbo, s->target_fbo);
    SWAP(gi_timer *, v->timer, s->timer);
    SWAP(uint32_t, v->timer_frames, s->timer_frames);
    SWAP(int, v->stage_count, s->stage_count);
    SWAP(double, v->frame_ms, s->frame_ms);
    SWAP(double, v->prepare_ms, s->prepare_ms);
    v->second_swapped = !v->second_swapped;
}

/* The second method's target, made on first use at the image's size (or
 * again after a resize). */
static void ensure_target(viewer *v)
{
    view_slot *s = &v->second;
    GLint w = 0, h = 0;
    if (s->target_tex) {
        glGetTextureLevelParameteriv(s->target_tex, 0, GL_TEXTURE_WIDTH, &w);
        glGetTextureLevelParameteriv(s->target_tex, 0, GL_TEXTURE_HEIGHT, &h);
        if ((uint32_t)w == v->width && (uint32_t)h == v->height)
            return;
        glDeleteTextures(1, &s->target_tex);
    } else {
        glCreateFramebuffers(1, &s->target_fbo);
    }
    glCreateTextures(GL_TEXTURE_2D, 1, &s->target_tex);
    glTextureStorage2D(s->target_tex, 1, GL_RGBA32F, (GLsizei)v->width, (GLsizei)v->height);
    glTextureParameteri(s->target_tex, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(s->target_tex, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glNamedFramebufferTexture(s->target_fbo, GL_COLOR_ATTACHMENT0, s->target_tex, 0);
    const float black[4] = {0, 0, 0, 1};
    glClearNamedFramebufferfv(s->target_fbo, GL_COLOR, 0, black);
    s->need_render = 1;
    s->frame_index = 0;
}

void view_second_unload(viewer *v)
{
    view_slot *s = &v->second;
    if (s->m || s->host_ready) {
        view_slot_swap(v);
        view_unload_method(v);
        view_slot_swap(v);
    }
    gi_timer_free(s->timer);
    s->timer = NULL;
    s->method_index = -1;
}

/* Creates and prepares method `index` as the second one (-1: none). The
 * first method's state (parameter selection, the split, what the
 * reference does) is kept. */
int view_second_select(viewer *v, int index)
{
    view_second_unload(v);
    if (index < 0) {
        if (v->split == 3)
            v->split = 0;
        view_reference_as_needed(v);
        return EXIT_OK;
    }
    v->second.host = &v->host_store[1];
    ensure_target(v);
    int first = v->method_index, sel = v->param_sel, need_display = v->need_display;
    view_slot_swap(v);
    /* view_select would treat the first method as the last one shown */
    int last = v->last_method;
    int rc = view_select(v, index);
    v->last_method = last;
    v->method_index = index;
    view_slot_swap(v);
    v->method_index = first;
    v->param_sel = sel;
    v->need_display = need_display | 1;
    v->second.need_render = 1;
    v->second.frame_index = 0;
    v->split = 3;
    view_reference_as_needed(v);
    if (rc != EXIT_OK)
        view_second_unload(v);
    return rc;
}

int view_second_wants_frame(const viewer *v)
{
    const view_slot *s = &v->second;
    if (v->split != 3 || s->method_index < 0 || !s->inst || s->stale)
        return 0;
    return s->need_render || ((s->m->caps & GI_CAP_PROGRESSIVE) && s->frame_index < 4096);
}

int view_second_render(viewer *v)
{
    ensure_target(v);
    /* the totals of the exit line and the stage times of the panels and
     * the overlay are the first method's */
    double sum = v->sum_frame_ms;
    uint64_t n = v->n_frames;
    char names[GI_TIMER_MAX_STAGES][GI_TIMER_NAME_MAX];
    double ms[GI_TIMER_MAX_STAGES];
    memcpy(names, v->stage_name, sizeof names);
    memcpy(ms, v->stage_ms, sizeof ms);
    view_slot_swap(v);
    v->need_render = 0;
    int rc = view_render_method(v);
    view_slot_swap(v);
    memcpy(v->stage_name, names, sizeof names);
    memcpy(v->stage_ms, ms, sizeof ms);
    v->sum_frame_ms = sum;
    v->n_frames = n;
    v->err_dirty = 1;
    return rc;
}

/* The animation's time changed (view_set_time): the second method's update(). */
int view_second_set_time(viewer *v)
{
    view_slot *s = &v->second;
    if (s->method_index < 0 || !s->inst)
        return EXIT_OK;
    gi_changes ch = {GI_CHANGED_TRANSFORMS | GI_CHANGED_LIGHTS |
                         (v->gs->deforming ? GI_CHANGED_VERTICES : 0u),
                     v->time, ~0ull};
    gi_result res = s->m->update(s->inst, v->gs, &ch);
    if (res != GI_OK)
        return cli_fail(EXIT_RUN, "view: %s: update failed (%s)", s->m->id, gi_result_name(res));
    s->need_render = 1;
    s->frame_index = 0;
    return EXIT_OK;
}

/* Nodes moved by hand: the second method told as the first is (view_tell_method). */
int view_second_tell(viewer *v, const unsigned char *moved)
{
    if (v->second.method_index < 0 || !v->second.inst)
        return EXIT_OK;
    int need_display = v->need_display;
    view_slot_swap(v);
    int rc = view_tell_method(v, moved);
    view_slot_swap(v);
    v->need_display = need_display | v->need_display;
    v->second.need_render = 1;
    v->second.frame_index = 0;
    return rc;
}

/* The view changed: the second method starts its accumulation again. */
void view_second_changed(viewer *v)
{
    v->second.need_render = 1;
    v->second.frame_index = 0;
}
