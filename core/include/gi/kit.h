/* The method kit: what every G-buffer method needs, written once.
 *
 * A plugin embeds a gi_kit in its instance and hands it each lifecycle call:
 *
 *     create():     gi_kit_init(&m->kit, host, gi_<id>_shaders)   (may fail: shader name clash)
 *     prepare(gs):  gi_kit_prepare(&m->kit, gs)
 *     update(gs,c): gi_kit_update(&m->kit, gs, c)
 *     render(v,t):  r = gi_kit_frame_begin(&m->kit, v, GI_KIT_GBUFFER | GI_KIT_ACCUMULATE);
 *                   r = gi_kit_render_gbuffer(&m->kit, v, "gbuffer");
 *                   glUseProgram(p); gi_kit_bind(&m->kit, p, v, t); ... dispatch ...
 *                   gi_kit_frame_end(&m->kit);
 *     destroy():    gi_kit_free(&m->kit)
 *     last_error(): gi_kit_last_error(&m->kit)
 *
 * Errors: `return gi_kit_fail(&m->kit, GI_ERR_GL, "what: %s", why);` keeps
 * the message for last_error(); gi_kit_fail_with passes a gi_error on.
 *
 * Progressive accumulation: the kit counts the frames in the running
 * average (gi_kit.frames, the shader's u_frame) and restarts it (0) on
 * any change of view (view_proj), size or scene (update() with any change
 * flag, prepare()), when the host starts a run (view->frame_index == 0),
 * and on every frame when accumulation is off. The shader side is
 * core/shaders/accumulate.glsl (gi_accumulate_store), bound at
 * GI_IMAGE_ACCUM / GI_IMAGE_TARGET by gi_kit_bind.
 *
 * Shaders: gbuffer_read.glsl (the G-buffer at named texture units,
 * gi_gbuffer_surface), view.glsl (u_eye, u_inv_view_proj, u_size, u_frame,
 * u_seed as gi_kit_bind sets them; gi_view_ray, gi_background),
 * accumulate.glsl. Binding points: gi/glsl_shared.h.
 *
 * Ownership: the kit owns its G-buffer, accumulation texture and scratch
 * textures; gi_kit_free releases them (and is safe on a zeroed kit). The
 * target belongs to the host, the scene to the core.
 */
#ifndef GI_KIT_H
#define GI_KIT_H

#include "gi/method.h"
#include "gi/passes.h"

#ifdef __cplusplus
extern "C" {
#endif

#define GI_KIT_SCRATCH_MAX 8

/* What gi_kit_frame_begin keeps sized to the view. */
enum {
    GI_KIT_GBUFFER = 1u << 0,    /* a G-buffer (gi_kit.gbuffer) */
    GI_KIT_ACCUMULATE = 1u << 1, /* an RGBA32F running average (gi_kit.accum) */
    GI_KIT_NO_AVERAGE =
        1u << 2, /* restart the average every frame (an "accumulate off" parameter) */
};

typedef struct gi_kit_scratch {
    GLuint texture;
    GLenum format;
    uint32_t width, height;
} gi_kit_scratch;

typedef struct gi_kit {
    const gi_host *host;
    const gi_gpu_scene *scene; /* set by prepare and update */
    gi_gbuffer *gbuffer;       /* with GI_KIT_GBUFFER: view-sized */
    GLuint accum;              /* with GI_KIT_ACCUMULATE: view-sized RGBA32F */
    uint32_t width, height;    /* size of the last frame */
    uint32_t frames;           /* frames already in the running average (u_frame) */
    float last_view_proj[16];
    gi_kit_scratch scratch[GI_KIT_SCRATCH_MAX];
    gi_error error;
} gi_kit;

/* Zeroes the kit, keeps `host` and registers the plugin's shader table
 * (may be NULL). Fails, with the reason in the kit's error and the host's
 * log, when a shader of the table is named like a core shader. */
gi_result gi_kit_init(gi_kit *k, const gi_host *host, const gi_shader_source *shaders);
/* Remembers the scene and restarts accumulation. */
void gi_kit_prepare(gi_kit *k, const gi_gpu_scene *gs);
/* Remembers the scene; restarts accumulation when changes->flags != 0. */
void gi_kit_update(gi_kit *k, const gi_gpu_scene *gs, const gi_changes *changes);
/* Sizes what `what` asks for to the view (re-made on a change of size),
 * applies the restart rules above. */
gi_result gi_kit_frame_begin(gi_kit *k, const gi_view *v, unsigned what);
/* Renders the kit's G-buffer for the view, inside stage `stage` when it is
 * not NULL. */
gi_result gi_kit_render_gbuffer(gi_kit *k, const gi_view *v, const char *stage);
/* With `program` in use: binds the scene, the G-buffer (when there is one)
 * at GI_TEX_GBUFFER_*, the accumulation and the target images (when
 * there are, target may be NULL) and sets view.glsl's uniforms. */
void gi_kit_bind(const gi_kit *k, GLuint program, const gi_view *v, const gi_target *t);
/* Counts the frame into the running average. */
void gi_kit_frame_end(gi_kit *k);
/* Scratch texture `slot` (< GI_KIT_SCRATCH_MAX) of `format` and size,
 * re-made when either changed (contents then undefined); 0 on a bad slot. */
GLuint gi_kit_scratch_texture(gi_kit *k, unsigned slot, GLenum format, uint32_t width,
                              uint32_t height);
/* For a method's debug buffers (gi_method.debug_buffer, ABI 1.3): with
 * `program` in use and bound by gi_kit_bind, sends the shader's
 * gi_accumulate_store to scratch texture `slot` (RGBA32F, width x height)
 * instead of the accumulation and the target, as a first frame (u_frame 0),
 * so that the next render() makes what it would have made. Returns the
 * texture, 0 on a bad slot. */
GLuint gi_kit_debug_target(gi_kit *k, GLuint program, unsigned slot, uint32_t width,
                           uint32_t height);
void gi_kit_free(gi_kit *k);

/* Keeps "fmt ..." as the error and returns r. */
gi_result gi_kit_fail(gi_kit *k, gi_result r, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
/* Keeps err's text as the error and returns r. */
gi_result gi_kit_fail_with(gi_kit *k, gi_result r, const gi_error *err);
const char *gi_kit_last_error(const gi_kit *k);

/* The data layout this build sees (gi_method.layout; method.h "Data
 * layout"). Bump GI_LAYOUT_REVISION on a same-size change of one of them. */
#define GI_LAYOUT_REVISION 1u
#define GI_ABI_LAYOUT                                                                              \
    {                                                                                              \
        GI_LAYOUT_REVISION, sizeof(gi_host), sizeof(gi_view), sizeof(gi_target),                   \
            sizeof(gi_changes), sizeof(gi_gpu_scene), sizeof(gi_gpu_material),                     \
            sizeof(gi_gpu_light), sizeof(gi_gpu_emitter), sizeof(gi_scene), sizeof(gi_object),     \
            sizeof(gi_material), sizeof(gi_light), sizeof(gi_camera), sizeof(gi_vertex),           \
            sizeof(gi_param_desc), sizeof(gi_gbuffer), sizeof(gi_depth_view),                      \
            sizeof(gi_depth_desc), sizeof(gi_depth_atlas_desc), sizeof(gi_kit)                     \
    }

/* The descriptor and the exported entry point of a plugin whose lifecycle
 * functions are named <prefix>_create, _prepare, _update, _render,
 * _destroy and _last_error; the identity, caps and parameter table follow
 * as designated initialisers:
 *
 *     GI_METHOD_EXPORT(csm, .id = "csm", .title = "Coherent Shadow Maps", .citation = "...",
 *                      .version = "0.2", .caps = GI_CAP_DIRECT | ..., .max_bounces = 0,
 *                      .params = csm_params);
 *
 * It fills struct_size, abi_version and layout, and defines
 * gi_method_entry (NULL for a host of another ABI major). */
#define GI_METHOD_EXPORT(prefix, ...)                                                              \
    static const gi_method prefix##_method = {.struct_size = sizeof(gi_method),                    \
                                              .abi_version = GI_ABI_VERSION,                       \
                                              .create = prefix##_create,                           \
                                              .prepare = prefix##_prepare,                         \
                                              .update = prefix##_update,                           \
                                              .render = prefix##_render,                           \
                                              .destroy = prefix##_destroy,                         \
                                              .last_error = prefix##_last_error,                   \
                                              .layout = GI_ABI_LAYOUT,                             \
                                              __VA_ARGS__};                                        \
    GI_EXPORT const gi_method *gi_method_entry(uint32_t host_abi_version)                          \
    {                                                                                              \
        return GI_ABI_VERSION_MAJOR(host_abi_version) == GI_ABI_MAJOR ? &prefix##_method : NULL;   \
    }                                                                                              \
    /* the declaration again, so that the macro's use ends with a semicolon */                     \
    GI_EXPORT const gi_method *gi_method_entry(uint32_t host_abi_version)

/* GI_OK when `plugin` (a descriptor's layout) equals the core's; else
 * GI_ERR_UNSUPPORTED and "built against <struct> of N bytes, this gibench
 * has M" (or the revisions) in err. */
gi_result gi_abi_layout_check(const gi_abi_layout *plugin, gi_error *err);

/* A compute dispatch covering width x height with 8 x 8 work groups
 * (the kit's shaders' local size), then a barrier for images, texture
 * fetches and buffers written by it. */
void gi_kit_dispatch_8x8(uint32_t width, uint32_t height);

#ifdef __cplusplus
}
#endif
#endif
