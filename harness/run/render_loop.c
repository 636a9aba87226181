/* The render loop of gibench render and the Python API (render_loop.h). */
#include "render_loop.h"

#include "debug_buffer.h"
#include "gi/log.h"
#include "gi/passes.h"
#include "gi/plugin.h"

#include <stdlib.h>

void render_loop_target(render_loop *r)
{
    glCreateTextures(GL_TEXTURE_2D, 1, &r->target_tex);
    glTextureStorage2D(r->target_tex, 1, GL_RGBA32F, (GLsizei)r->width, (GLsizei)r->height);
    glCreateFramebuffers(1, &r->target_fbo);
    glNamedFramebufferTexture(r->target_fbo, GL_COLOR_ATTACHMENT0, r->target_tex, 0);
    const float black[4] = {0, 0, 0, 1};
    glClearNamedFramebufferfv(r->target_fbo, GL_COLOR, 0, black);
}

gi_result render_loop_method_error(const render_loop *r, const char *what, gi_result res,
                                   gi_error *err)
{
    const char *msg = r->m->last_error(r->inst);
    return gi_error_set(err, res, "%s: %s failed (%s)%s%s", r->m->id, what, gi_result_name(res),
                        msg && *msg ? ": " : "", msg ? msg : "");
}

gi_result render_loop_prepare(render_loop *r, const gi_params *params, gi_error *err)
{
    gi_error cerr;
    gi_result res = gi_method_create(r->m, &r->host->host, params, &r->inst, &cerr);
    if (res != GI_OK)
        return gi_error_set(err, res, "%s: %s", r->m->id, cerr.text);
    r->host->timer = r->prep_timer;
    /* -v: the moment precomputation starts (the cancellation test waits for it) */
    gi_log(GI_LOG_INFO, "%s: prepare begins", r->m->id);
    gi_timer_frame_begin(r->prep_timer);
    res = r->m->prepare(r->inst, r->gs);
    gi_timer_frame_end(r->prep_timer);
    cli_host_progress_end(r->host);
    if (res != GI_OK)
        return render_loop_method_error(r, "prepare", res, err);
    return GI_OK;
}

/* What a step of the scene's animation changes, for update(): transforms
 * when an object is animated (or deforms: its vertices follow the time),
 * lights when a punctual light or an emissive object moves, the camera when
 * the view's camera node is animated, vertices when morph targets deform.
 * A method that rebuilds on a flag is charged only for what moves. */
static gi_changes animation_changes(const gi_scene *s, const gi_gpu_scene *gs, int camera)
{
    gi_changes ch = {0u, 0.0f, 0ull};
    for (uint32_t k = 0; k < s->object_count; k++)
        if (s->objects[k].animated || s->objects[k].morph_track.count) {
            ch.flags |= GI_CHANGED_TRANSFORMS;
            ch.moved_objects |= k < 64 ? 1ull << k : 0ull;
        }
    if (s->object_count > 64 && (ch.flags & GI_CHANGED_TRANSFORMS))
        ch.moved_objects = ~0ull;
    if (gs->deforming)
        ch.flags |= GI_CHANGED_TRANSFORMS | GI_CHANGED_VERTICES;
    if (gi_scene_lights_animated(s))
        ch.flags |= GI_CHANGED_LIGHTS;
    if (gi_scene_camera_animated(s, camera))
        ch.flags |= GI_CHANGED_CAMERA;
    return ch;
}

gi_result render_loop_update(render_loop *r, float t, uint32_t flags, gi_error *err)
{
    gi_gpu_scene_set_time(r->gs, t);
    gi_changes ch = animation_changes(r->scene, r->gs, r->fixed_camera ? -1 : r->camera);
    ch.flags |= flags;
    ch.time = t;
    gi_result res = r->m->update(r->inst, r->gs, &ch);
    if (res != GI_OK)
        return render_loop_method_error(r, "update", res, err);
    return GI_OK;
}

gi_result render_loop_frame(render_loop *r, uint32_t f, gi_error *err)
{
    gi_target target = {r->target_tex, r->target_fbo, r->width, r->height};
    float t = r->time + (r->animate_fps > 0 ? (float)f / r->animate_fps : 0.0f);
    gi_result res;
    r->host->timer = r->render_timer;
    /* A frame of an animation is update() and render(): what an
     * interactive program pays per frame (a method that rebuilds data
     * in update() is charged for it; its stages count in the frame). */
    gi_timer_frame_begin(r->render_timer);
    if (f > 0 && r->animate_fps > 0) {
        res = render_loop_update(r, t, 0, err);
        if (res != GI_OK) {
            gi_timer_frame_end(r->render_timer);
            return res;
        }
    }
    gi_camera_frame cf =
        r->fixed_camera ? *r->fixed_camera : gi_scene_camera_at(r->scene, r->camera, t);
    gi_view view;
    gi_view_from_camera(&cf, r->width, r->height, t, &view);
    view.frame_index = r->animate_fps > 0 ? 0 : f;
    view.seed = r->seed;
    view.exposure = r->exposure;
    r->view = view;
    res = r->m->render(r->inst, &view, &target);
    gi_timer_frame_end(r->render_timer);
    if (res != GI_OK)
        return render_loop_method_error(r, "render", res, err);
    gi_error gerr;
    if ((res = gi_gl_check("after render", &gerr)) != GI_OK)
        return gi_error_set(err, res, "%s: %s", r->m->id, gerr.text);
    return GI_OK;
}

gi_image *render_loop_image(const render_loop *r)
{
    gi_image *img = gi_gpu_read_texture(r->target_tex, r->width, r->height);
    if (img)
        for (size_t i = 0; i < (size_t)r->width * r->height; i++)
            img->rgba[4 * i + 3] = 1.0f;
    return img;
}

gi_image *render_loop_buffer(const render_loop *r, const char *name, gi_error *err)
{
    return debug_buffer_fetch(r->m, r->inst, &r->view, name, err);
}

void render_loop_free(render_loop *r)
{
    if (r->inst)
        r->m->destroy(r->inst);
    r->inst = NULL;
    if (r->target_fbo)
        glDeleteFramebuffers(1, &r->target_fbo);
    if (r->target_tex)
        glDeleteTextures(1, &r->target_tex);
    r->target_fbo = r->target_tex = 0;
}
