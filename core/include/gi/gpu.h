/* The GPU: a headless OpenGL 4.5 core context through EGL, and the scene
 * uploaded once (the vertices of morphing objects rewritten per frame).
 *
 * Use:
 *     gi_error err;
 *     gi_gpu *gpu = gi_gpu_create(NULL, &err);      // context is current
 *     gi_gpu_scene *gs = gi_gpu_scene_upload(gpu, scene, &err);
 *     gi_gpu_scene_set_time(gs, t);                 // refresh object transforms
 *     ... passes, plugins ...
 *     gi_gpu_scene_free(gs); gi_gpu_destroy(gpu);
 *
 * Device choice: an EGL device that is not software (EGL_EXT_platform_device,
 * e.g. NVIDIA) first, then Mesa's surfaceless platform (llvmpipe). The
 * environment variable GIBENCH_EGL (or gibench --egl-device) chooses:
 *   auto (or unset)  that order;
 *   device           a hardware EGL device only, no llvmpipe fallback;
 *   surfaceless      Mesa's surfaceless platform only (llvmpipe);
 *   <N>              EGL device number N (eglQueryDevicesEXT order), software too;
 *   <text>           the first EGL device whose GL_VENDOR, GL_RENDERER or EGL
 *                    vendor contains <text> (any case), e.g. "nvidia".
 * Only auto falls back to llvmpipe. If nothing gives a 4.5 core context the
 * error says what each attempt returned.
 * GL functions come from libepoxy; include <epoxy/gl.h>. The context is
 * current on the creating thread only.
 */
#ifndef GI_GPU_H
#define GI_GPU_H

#include <epoxy/gl.h>

#include "gi/common.h"
#include "gi/glsl_shared.h"
#include "gi/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct gi_gpu gi_gpu;

typedef struct gi_gpu_desc {
    int debug;            /* GL debug context + KHR_debug messages to the log */
    const char *platform; /* a GIBENCH_EGL value (above), or NULL = $GIBENCH_EGL */
    /* 1: make no context; use the OpenGL 4.5 core context current on this
     * thread (a window's, made by the caller, e.g. gibench view through
     * GLFW); gi_gpu_destroy then leaves it alone. platform is ignored. */
    int adopt_current;
} gi_gpu_desc;

gi_gpu *gi_gpu_create(const gi_gpu_desc *desc, gi_error *err);
void gi_gpu_destroy(gi_gpu *gpu);
/* GL_RENDERER, GL_VERSION, and how the context was made ("device",
 * "surfaceless", or "adopted" for a caller's context). */
const char *gi_gpu_renderer(const gi_gpu *gpu);
const char *gi_gpu_version(const gi_gpu *gpu);
const char *gi_gpu_platform(const gi_gpu *gpu);
/* GL_VENDOR, and which EGL device the context is on, in words:
 * "device 0 of 2 (NVIDIA Corporation)", "surfaceless (Mesa)". */
const char *gi_gpu_vendor(const gi_gpu *gpu);
const char *gi_gpu_device(const gi_gpu *gpu);
/* True on software rasterisers (llvmpipe, softpipe, swrast), where GL timer
 * queries are not trusted for compute work. */
int gi_gpu_is_software(const gi_gpu *gpu);
/* Checks glGetError; on error writes "what: GL_INVALID_..." into err. */
gi_result gi_gl_check(const char *what, gi_error *err);

/* The scene's binding points, the G-buffer's texture units and the first
 * points left to plugins are in gi/glsl_shared.h (shared with GLSL). */

/* std430 material record (64 bytes), see scene.glsl. */
typedef struct gi_gpu_material {
    float albedo[3];
    int32_t texture_layer; /* -1 none */
    float ks[3];
    float exponent;
    float emission[3];
    uint32_t flags; /* GI_MATERIAL_FLAG_MIRROR | GI_MATERIAL_FLAG_DOUBLE_SIDED */
} gi_gpu_material;

/* std430 punctual light record (64 bytes), world space at the current time. */
typedef struct gi_gpu_light {
    float position[3];
    uint32_t type; /* gi_light_type */
    float direction[3];
    float range;
    float intensity[3];
    float cos_inner;
    float cos_outer;
    float pad[3];
} gi_gpu_light;

/* std430 emitter record (16 bytes): an emissive triangle with its share of
 * the area-light power (for sampling by radiance distribution). */
typedef struct gi_gpu_emitter {
    uint32_t triangle;
    float area; /* world area at the current time */
    float cdf;  /* inclusive running sum of power, normalised to 1 at the end */
    float pdf;  /* probability of choosing this emitter */
} gi_gpu_emitter;

/* The emitter whose CDF interval holds u in [0, 1) (n >= 1 records):
 * the CPU twin of scene.glsl's gi_emitter_find, for plugins that read the
 * emitter table back (avg, cssm_hrc's direct=csm). */
static inline uint32_t gi_emitter_find_cpu(const gi_gpu_emitter *em, uint32_t n, float u)
{
    uint32_t lo = 0, hi = n - 1;
    while (lo < hi) {
        uint32_t mid = (lo + hi) / 2;
        if (em[mid].cdf > u)
            hi = mid;
        else
            lo = mid + 1;
    }
    return lo;
}

/* The scene on the GPU. All handles are owned by the core; plugins read
 * them and must not delete them. Vertex attributes of `vao`: 0 position
 * (vec3), 1 object (uint), 2 normal (vec3), 3 material (uint), 4 uv (vec2),
 * interleaved as gi_vertex; `ibo` holds the triangle indices. */
typedef struct gi_gpu_scene {
    gi_gpu *gpu;
    const gi_scene *scene;
    GLuint vao, vbo, ibo;
    GLuint ssbo_materials, ssbo_lights, ssbo_emitters;
    GLuint ubo_objects; /* GI_MAX_OBJECTS x {mat4 world_from_local; mat4 normal matrix} */
    GLuint ubo_info;    /* scene counts, light powers, time, bounds (GiSceneInfo) */
    GLuint tex_env, tex_env_cond, tex_env_marg; /* 0 when no environment */
    GLuint tex_albedo; /* 2D array, 1 x 1 x 1 white when the scene has no texture */
    uint32_t triangle_count, vertex_count, light_count, emitter_count;
    float emitter_power; /* total area-light power (sum of area x luminance x pi) */
    float time;          /* time the transforms were last set for */
    float world_from_local[GI_MAX_OBJECTS][16]; /* CPU copy of the UBO */
    float bounds[6];                            /* world bounds at `time` */
    int deforming; /* the scene has morph targets: set_time rewrites their vertices */
} gi_gpu_scene;

gi_gpu_scene *gi_gpu_scene_upload(gi_gpu *gpu, const gi_scene *scene, gi_error *err);
void gi_gpu_scene_free(gi_gpu_scene *gs);
/* Recomputes object transforms, light frames and emitter areas at time t
 * and refreshes the UBO/SSBOs; for objects with morph targets it also
 * writes their vertices at t (gi_scene_object_vertices) into `vbo` (which
 * is also the GI_SSBO_VERTICES buffer). Cheap for rigid scenes; call once
 * per frame of an animation. */
void gi_gpu_scene_set_time(gi_gpu_scene *gs, float t);
/* Overwrites vertices first_vertex .. first_vertex + count - 1 of the
 * vertex buffer (object-local, gi_vertex layout): deformation driven by
 * the caller (procedural or simulated) rather than by glTF morph targets.
 * A vertex must keep its object and material, and be finite; a range past
 * the scene is an error. The caller keeps its CPU copy (scene->vertices,
 * gi_rt_refresh) and the objects' local_bounds in step, tells methods
 * through gi_changes (GI_CHANGED_VERTICES), and must not also have morph
 * targets on those objects (set_time would overwrite them). */
gi_result gi_gpu_scene_update_vertices(gi_gpu_scene *gs, uint32_t first_vertex, uint32_t count,
                                       const gi_vertex *v, gi_error *err);
/* Binds every scene resource to its fixed binding point. */
void gi_gpu_scene_bind(const gi_gpu_scene *gs);
/* Draws all triangles (or only object `object` when >= 0) with the scene
 * VAO; the caller has a program bound. `instances` > 1 draws instanced. */
void gi_gpu_scene_draw(const gi_gpu_scene *gs, int object, GLsizei instances);
/* Draws `ranges` runs of the scene's own index buffer in one call
 * (glMultiDrawElements): run k is counts[k] indices from byte offset
 * offsets[k]; the caller has a program bound. */
void gi_gpu_scene_draw_ranges(const gi_gpu_scene *gs, const GLsizei *counts,
                              const void *const *offsets, GLsizei ranges);
/* Draws `index_count` indices of another element buffer `ibo` (indices into
 * the scene's vertices, e.g. gi/algo/simplify.h's lower-detail copy) with
 * the scene's VAO and vertex attributes, then gives the VAO its own
 * element buffer back; the caller has a program bound. */
void gi_gpu_scene_draw_indices(const gi_gpu_scene *gs, GLuint ibo, uint32_t index_count,
                               GLsizei instances);

/* A new width x height 2D texture of `format` (one level, contents
 * undefined) with nearest filtering and clamp-to-edge wrapping: the render
 * targets, image outputs and lookup tables of the passes and plugins. */
GLuint gi_gpu_texture_2d(GLenum format, uint32_t width, uint32_t height);

/* Reads an RGBA32F texture (level 0) into a new image, top row first. */
struct gi_image *gi_gpu_read_texture(GLuint tex, uint32_t width, uint32_t height);

#ifdef __cplusplus
}
#endif
#endif
