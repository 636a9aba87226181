/* gibench conformance, the child's side: a session on the GPU for one item
 * (docs/conformance.md): the scene loaded and uploaded, a fresh
 * instance of the method made and prepared as `gibench render` does it,
 * frames rendered into a target of the asked size and read back. */
#define _POSIX_C_SOURCE 200809L
#include "conf.h"

#include "gi/vecmath.h"

#include <stdio.h>
#include <string.h>

const char *const conf_status_name[] = {"pass", "fail", "n/a"};

void conf_scene_free(conf_scene *s)
{
    gi_gpu_scene_free(s->gs);
    gi_scene_free(s->scene);
    s->gs = NULL;
    s->scene = NULL;
}

int conf_scene_open(conf_session *S, const char *path, float t, conf_scene *out)
{
    gi_error err;
    memset(out, 0, sizeof *out);
    out->scene = gi_scene_load(path, &err);
    if (!out->scene) {
        snprintf(S->why, sizeof S->why, "%s", err.text);
        return 0;
    }
    out->gs = gi_gpu_scene_upload(S->gpu, out->scene, &err);
    if (!out->gs) {
        snprintf(S->why, sizeof S->why, "%s", err.text);
        conf_scene_free(out);
        return 0;
    }
    gi_gpu_scene_set_time(out->gs, t);
    return 1;
}

void conf_instance_free(conf_session *S)
{
    if (S->inst)
        S->m->destroy(S->inst);
    S->inst = NULL;
    gi_params_free(S->params);
    S->params = NULL;
    if (S->host_ready)
        cli_host_free(&S->host);
    S->host_ready = 0;
}

int conf_method_error(conf_session *S, const char *what, gi_result r)
{
    const char *msg = S->inst ? S->m->last_error(S->inst) : "";
    snprintf(S->why, sizeof S->why, "%s failed (%s)%s%s", what, gi_result_name(r),
             msg && *msg ? ": " : "", msg ? msg : "");
    return 0;
}

/* A new instance with parameters kv[0..n), prepared on scene sc. */
int conf_instance_new(conf_session *S, const char *const *kv, uint32_t n, const conf_scene *sc)
{
    gi_error err;
    conf_instance_free(S);
    S->params = gi_params_parse(S->m->id, S->m->params, kv, n, &err);
    if (!S->params) {
        snprintf(S->why, sizeof S->why, "%s", err.text);
        return 0;
    }
    /* No cache directory: precomputation runs afresh, nothing is kept. */
    cli_host_init(&S->host, S->m->id, NULL, sc->gs, gi_gpu_renderer(S->gpu),
                  gi_gpu_is_software(S->gpu));
    S->host.show_progress = 0;
    S->host_ready = 1;
    gi_error cerr;
    gi_result r = gi_method_create(S->m, &S->host.host, S->params, &S->inst, &cerr);
    if (r != GI_OK) {
        snprintf(S->why, sizeof S->why, "%s", cerr.text);
        return 0;
    }
    r = S->m->prepare(S->inst, sc->gs);
    if (r != GI_OK)
        return conf_method_error(S, "prepare", r);
    return 1;
}

static int target_size(conf_session *S, uint32_t w, uint32_t h)
{
    if (S->tex && S->w == w && S->h == h)
        return 1;
    if (S->fbo)
        glDeleteFramebuffers(1, &S->fbo);
    if (S->tex)
        glDeleteTextures(1, &S->tex);
    glCreateTextures(GL_TEXTURE_2D, 1, &S->tex);
    glTextureStorage2D(S->tex, 1, GL_RGBA32F, (GLsizei)w, (GLsizei)h);
    glCreateFramebuffers(1, &S->fbo);
    glNamedFramebufferTexture(S->fbo, GL_COLOR_ATTACHMENT0, S->tex, 0);
    S->w = w;
    S->h = h;
    return 1;
}

/* The view of the scene's first camera at time t; shift moves the eye
 * along the camera's right axis (the camera-change check). */
static void make_view(const gi_scene *s, float t, uint32_t w, uint32_t h, float shift,
                      uint32_t seed, gi_view *v)
{
    gi_camera_frame cf = gi_scene_camera_at(s, s->camera_count ? 0 : -1, t);
    if (shift != 0.0f) {
        gi_vec3 right =
            gi_v3(cf.world_from_camera[0], cf.world_from_camera[1], cf.world_from_camera[2]);
        cf.eye = gi_v3_add(cf.eye, gi_v3_scale(right, shift));
        cf.world_from_camera[12] = cf.eye.x;
        cf.world_from_camera[13] = cf.eye.y;
        cf.world_from_camera[14] = cf.eye.z;
    }
    gi_view_from_camera(&cf, w, h, t, v);
    v->seed = seed;
}

/* Renders `frames` frames (frame_index first, first + 1, ...) and reads the image back. */
gi_image *conf_render_frames(conf_session *S, const conf_scene *sc, float t, uint32_t w, uint32_t h,
                             uint32_t frames, uint32_t first, float shift, uint32_t seed)
{
    gi_error err;
    target_size(S, w, h);
    const float black[4] = {0, 0, 0, 1};
    glClearNamedFramebufferfv(S->fbo, GL_COLOR, 0, black);
    gi_target target = {S->tex, S->fbo, w, h};
    for (uint32_t f = 0; f < frames; f++) {
        gi_view v;
        make_view(sc->scene, t, w, h, shift, seed, &v);
        v.frame_index = first + f;
        gi_result r = S->m->render(S->inst, &v, &target);
        if (r != GI_OK) {
            conf_method_error(S, "render", r);
            return NULL;
        }
        if (gi_gl_check("after render", &err) != GI_OK) {
            snprintf(S->why, sizeof S->why, "%s", err.text);
            return NULL;
        }
    }
    gi_image *img = gi_gpu_read_texture(S->tex, w, h);
    if (!img)
        snprintf(S->why, sizeof S->why, "out of memory reading the image back");
    return img;
}

/* A fresh instance on sc, `frames` frames at t = 0 of size x size with
 * `seed`: the image, or NULL with the reason kept in S. */
gi_image *conf_fresh_render(conf_session *S, const conf_scene *sc, uint32_t size, uint32_t frames,
                            uint32_t seed)
{
    return conf_instance_new(S, NULL, 0, sc)
               ? conf_render_frames(S, sc, 0.0f, size, size, frames, 0, 0.0f, seed)
               : NULL;
}

int conf_update(conf_session *S, conf_scene *sc, uint32_t flags, float t)
{
    gi_gpu_scene_set_time(sc->gs, t);
    gi_changes ch = {flags, t, ~0ull};
    gi_result r = S->m->update(S->inst, sc->gs, &ch);
    return r == GI_OK ? 1 : conf_method_error(S, "update", r);
}
