/* The render loop of one method instance: create and prepare it, render
 * frame after frame into a target texture, read the image back. Shared by
 * gibench render (harness/cli/cmd_render.c) and the Python API
 * (harness/api/), so that both make the same image bit for bit. */
#ifndef GIBENCH_RENDER_LOOP_H
#define GIBENCH_RENDER_LOOP_H

#include "cli.h"
#include "gi/image.h"

typedef struct render_loop {
    /* given by the caller */
    const gi_method *m;
    const gi_scene *scene;
    gi_gpu_scene *gs;
    cli_host *host;         /* initialised for this method and scene upload */
    gi_timer *prep_timer;   /* prepare(), one frame */
    gi_timer *render_timer; /* every frame, update() and render() */
    uint32_t width, height, seed;
    float time, animate_fps, exposure;
    int camera;                          /* scene camera index; -1 for none */
    const gi_camera_frame *fixed_camera; /* a saved view's camera, or NULL */
    /* owned by the loop (render_loop_free releases them) */
    void *inst;
    GLuint target_tex, target_fbo;
    gi_view view; /* the view of the last frame rendered (render_loop_buffer's) */
} render_loop;

/* The render target (RGBA32F, cleared to black). */
void render_loop_target(render_loop *r);
/* The method created with `params` and prepared under prep_timer. On
 * failure the CLI's one-line message ("csm: prepare failed (...)...") in
 * err; the result says usage (GI_ERR_INVALID_ARGUMENT, GI_ERR_UNSUPPORTED)
 * or a failure while running. */
gi_result render_loop_prepare(render_loop *r, const gi_params *params, gi_error *err);
/* The scene moved to time t (its animation: transforms, lights, camera,
 * deformation) and the method told by update() of what that changes, and
 * of `flags` besides (GI_CHANGED_CAMERA for another camera). */
gi_result render_loop_update(render_loop *r, float t, uint32_t flags, gi_error *err);
/* Frame f (from 0), timed: update() for a step of an animation (animate_fps
 * > 0), then render(), then a GL error check. */
gi_result render_loop_frame(render_loop *r, uint32_t f, gi_error *err);
/* The target read back with alpha 1; NULL when out of memory. */
gi_image *render_loop_image(const render_loop *r);
/* Debug buffer `name` of the instance after the last frame
 * (debug_buffer_fetch of debug_buffer.h with that frame's view). */
gi_image *render_loop_buffer(const render_loop *r, const char *name, gi_error *err);
/* "M: WHAT failed (RESULT): MESSAGE" of the method's last_error. */
gi_result render_loop_method_error(const render_loop *r, const char *what, gi_result res,
                                   gi_error *err);
/* Destroys the instance and the target. */
void render_loop_free(render_loop *r);

#endif
