/* The plugin ABI: one method (one paper) per shared library.
 *
 * A plugin exports exactly one symbol,
 *     GI_EXPORT const gi_method *gi_method_entry(uint32_t host_abi_version);
 * returning a pointer to static data, or NULL when the host's major version
 * differs from the one the plugin was built for. The entry touches no GL.
 *
 * The host calls, in this order and on the thread that owns the GL context:
 *     create(host, params, &inst)       once; no scene yet; GL is current
 *     prepare(inst, gs)                 once per scene (precomputation; may
 *                                       read/write host->cache_dir)
 *     { update(inst, gs, changes) }     between frames when something moved
 *     render(inst, view, target)        once per frame
 *     { debug_buffer(inst, name, view, &img) }  optional, after a render()
 *                                       of the same view (ABI 1.3)
 *     destroy(inst)                     always, also after a failed call
 * After any call returns an error the host reads last_error(inst) (never
 * NULL; "" when there is nothing to say) and then calls destroy(inst). When
 * create() fails there is no instance: the plugin reports through host->log.
 *
 * Growth: gi_method and gi_host only ever grow at their end. Each carries
 * its struct_size; a reader checks that a field lies inside struct_size
 * before touching it (GI_HAS_FIELD). A change that reorders or removes a
 * field bumps GI_ABI_MAJOR; a change that appends bumps GI_ABI_MINOR.
 *
 * Data layout: a plugin also reads structs the host fills (gi_view,
 * gi_gpu_scene, gi_scene and its arrays, gi_gbuffer, ...) and embeds the
 * core's gi_kit. Their sizes as the plugin's build saw them travel in
 * gi_method.layout (GI_ABI_LAYOUT); the loader refuses a plugin whose
 * sizes or GI_LAYOUT_REVISION differ from its own, naming the first
 * struct that differs. Whoever changes one of these structs without
 * changing its size (a reorder, a type of the same width) bumps
 * GI_LAYOUT_REVISION by hand.
 *
 * Ownership: plugins own and free every GL object they create; they read
 * the scene's GPU buffers (gi_gpu_scene) but never delete or resize them;
 * the target texture belongs to the host.
 */
#ifndef GI_METHOD_H
#define GI_METHOD_H

#include "gi/common.h"
#include "gi/gpu.h"
#include "gi/image.h"
#include "gi/params.h"
#include "gi/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

#define GI_ABI_MAJOR 1u
#define GI_ABI_MINOR                                                                               \
    3u /* 1.1: gi_method.layout; 1.2: gi_method.departures; 1.3: debug_buffers, debug_buffer */
#define GI_ABI_VERSION ((GI_ABI_MAJOR << 16) | GI_ABI_MINOR)
#define GI_ABI_VERSION_MAJOR(v) ((v) >> 16)

#if defined(__GNUC__)
#define GI_EXPORT __attribute__((visibility("default")))
#else
#define GI_EXPORT
#endif

/* Does struct *p (with a struct_size field) contain `field` completely? */
#define GI_HAS_FIELD(p, type, field)                                                               \
    ((p)->struct_size >= offsetof(type, field) + sizeof(((type *)0)->field))

/* What a method can do. The harness runs a method only on scenes and
 * settings its caps cover, and marks other cells "n/a" with the reason. */
typedef enum gi_caps {
    GI_CAP_DIRECT = 1u << 0,       /* direct light */
    GI_CAP_INDIRECT = 1u << 1,     /* at least one indirect (diffuse) bounce */
    GI_CAP_GLOSSY = 1u << 2,       /* glossy final bounce (Phong lobe) */
    GI_CAP_MIRROR = 1u << 3,       /* ideal mirrors */
    GI_CAP_AREA_LIGHTS = 1u << 4,  /* emissive triangles */
    GI_CAP_POINT_LIGHTS = 1u << 5, /* KHR_lights_punctual point and spot */
    GI_CAP_DIRECTIONAL = 1u << 6,  /* KHR_lights_punctual directional */
    GI_CAP_ENVIRONMENT = 1u << 7,  /* environment map */
    GI_CAP_RIGID_MOTION = 1u << 8, /* objects move between frames */
    GI_CAP_DEFORMATION = 1u << 9,  /* vertices change between frames */
    GI_CAP_PROGRESSIVE = 1u << 10, /* converges over frames of a still view */
    GI_CAP_PRECOMPUTE = 1u << 11,  /* prepare() does real precomputation */
    GI_CAP_VISIBILITY = 1u << 12,  /* direct light is shadowed */
    GI_CAP_TEXTURES = 1u << 13,    /* albedo textures */
} gi_caps;

/* Which scene things changed since the last frame (gi_changes.flags). */
enum {
    GI_CHANGED_TRANSFORMS = 1u << 0, /* object transforms (animation time) */
    GI_CHANGED_LIGHTS = 1u << 1,     /* light placement or power */
    GI_CHANGED_MATERIALS = 1u << 2,
    GI_CHANGED_CAMERA = 1u << 3,
    GI_CHANGED_VERTICES =
        1u << 4, /* vertex positions/normals (deformation: morph targets at the new
                    time, or gi_gpu_scene_update_vertices); needs GI_CAP_DEFORMATION */
};

typedef struct gi_changes {
    uint32_t flags;
    float time;             /* the scene time now in effect */
    uint64_t moved_objects; /* bit k: object k moved (objects >= 64: see flags) */
} gi_changes;

/* One frame to render. Matrices column-major (vecmath.h). */
typedef struct gi_view {
    uint32_t width, height;
    float view[16]; /* world -> eye */
    float proj[16]; /* eye -> clip, GL convention */
    float view_proj[16];
    float inv_view_proj[16];
    gi_vec3 eye;
    float yfov, znear, zfar;
    float time;           /* scene time of this frame, seconds */
    uint32_t frame_index; /* frames since the last reset of accumulation */
    uint32_t seed;        /* per-run seed; frame randomness derives from it */
    float exposure;       /* display exposure (stops) the report will use */
} gi_view;

/* For hosts: the view of camera frame cf on a width x height image at scene
 * time t (view, perspective projection with aspect width / height, their
 * product and its inverse, eye, yfov, znear, zfar); frame_index, seed and
 * exposure are 0, for the caller to set. */
void gi_view_from_camera(const gi_camera_frame *cf, uint32_t width, uint32_t height, float t,
                         gi_view *v);

/* Where render() writes: linear RGB radiance (alpha ignored) into an
 * RGBA32F 2D texture of view->width x view->height owned by the host.
 * Write it with an FBO attachment (`fbo` has it attached as colour 0) or
 * with imageStore. Row 0 is the bottom row (GL convention). */
typedef struct gi_target {
    GLuint texture;
    GLuint fbo;
    uint32_t width, height;
} gi_target;

typedef struct gi_host gi_host;
typedef struct gi_abi_layout gi_abi_layout;
struct gi_host {
    uint32_t struct_size;
    uint32_t abi_version;
    void *user; /* host-private */
    /* Log a message (level as gi_log_level) prefixed with the method id. */
    void (*log)(const gi_host *host, int level, const char *fmt, ...)
#if defined(__GNUC__)
        __attribute__((format(printf, 3, 4)))
#endif
        ;
    /* Progress of a long task, fraction in [0, 1]; shown on a terminal. */
    void (*progress)(const gi_host *host, const char *task, float fraction);
    /* Named stage timers: begin/end pairs, may nest, same name may recur in
     * a frame (times add). Usable in prepare() and render(). */
    void (*stage_begin)(const gi_host *host, const char *name);
    void (*stage_end)(const gi_host *host, const char *name);
    /* A number worth reporting (bytes, element counts, samples/s); the last
     * value set for a name wins. Written beside the timings.
     * Names with a meaning the harness knows (studies put them in their own
     * table columns):
     *   "data_bytes"  the size in bytes of the data the method precomputes
     *                 and keeps for rendering (GPU buffers and textures and
     *                 CPU copies it holds after prepare()/update(): maps,
     *                 atlases, grids, VPLs, links), excluding the scene
     *                 itself and the render target; the tradeoff tables'
     *                 "data (MB)" column. Parts may be reported beside it as
     *                 "data_bytes_<part>" (e.g. "data_bytes_atlas"). */
    void (*stat)(const gi_host *host, const char *name, double value);
    /* Non-zero once the user or the time limit asked to stop; long loops in
     * prepare() poll it and return GI_ERR_CANCELLED. */
    int (*cancelled)(const gi_host *host);
    /* A directory the method may keep precomputed data in (exists,
     * writable); name files by a hash of what they depend on (cache.h). */
    const char *cache_dir;
    /* GL function loader, for plugins that do not use libepoxy. */
    void *(*gl_get_proc_address)(const char *name);
    /* The scene on the GPU (set before prepare, NULL in create). */
    const gi_gpu_scene *gpu_scene;
    /* The GL context's facts. */
    const char *gl_renderer;
    int gl_is_software;
};

/* host->stage_begin (begin != 0) or host->stage_end of stage `name`; nothing
 * when host is NULL (precomputation code that tests run without a host). */
static inline void gi_host_stage(const gi_host *host, const char *name, int begin)
{
    if (!host)
        return;
    if (begin)
        host->stage_begin(host, name);
    else
        host->stage_end(host, name);
}

/* Sizes of the data structs a plugin reads or embeds, as its build saw
 * them (GI_ABI_LAYOUT fills it). */
struct gi_abi_layout {
    uint32_t revision; /* GI_LAYOUT_REVISION */
    uint32_t host, view, target, changes, gpu_scene, gpu_material, gpu_light, gpu_emitter;
    uint32_t scene, object, material, light, camera, vertex, param_desc;
    uint32_t gbuffer, depth_view, depth_desc, depth_atlas_desc, kit;
};

/* ABI 1.2: a known departure of the paper's method from one check of the
 * conformance suite (docs/conformance.md "Declared departures"). A plugin's
 * defaults are the paper's method; where that method, faithfully
 * implemented, cannot pass a check, the plugin says so here instead of
 * changing its defaults: the suite then still runs the check at the
 * defaults and reports the result, labelled with `reason`, and requires the
 * check to pass with `remedy`, the plugin's own option that fixes it. A
 * check that fails without a declaration fails. */
typedef struct gi_departure {
    /* "furnace" (the closed emitting spheres: furnace_0.5 / 0.8, and the
     * held-out family's furnace_in / furnace_out) or "held_out" (the
     * held-out family's scenes: trivial answers and convergence) */
    const char *check;
    /* One line: why the paper's method fails it, with the measured numbers
     * ("Eq. 5 counts only the nearest node of a bin: -27 % at rho 0.5") */
    const char *reason;
    /* The parameters that pass it, "k=v" separated by spaces
     * ("weight=surface"); they must parse against the parameter table. */
    const char *remedy;
} gi_departure;

/* ABI 1.3: a named intermediate image of the method (issue 33), which
 * gibench view shows and `gibench render --buffer NAME` writes: what
 * explains the method (a shadow term, a map, an atlas, the VPLs, the
 * gathered indirect light), not the final image again. */
typedef struct gi_debug_buffer_desc {
    const char *name;        /* [a-z0-9_]{1,31}, unique in the method */
    const char *description; /* one line: what a pixel holds and its unit */
    /* GI_DEBUG_SCREEN: view->width x view->height, pixel for pixel with
     * the target (a G-buffer quantity); GI_DEBUG_OWN_SIZE: its own size (a
     * map, an atlas, a slice), which the plugin chooses */
    uint32_t space;
} gi_debug_buffer_desc;
enum { GI_DEBUG_SCREEN = 0, GI_DEBUG_OWN_SIZE = 1 };

typedef struct gi_method {
    uint32_t struct_size;        /* sizeof(gi_method) the plugin was built with */
    uint32_t abi_version;        /* GI_ABI_VERSION the plugin was built with */
    const char *id;              /* short unique name: [a-z0-9_]+, e.g. "csm" */
    const char *title;           /* "Coherent Shadow Maps" */
    const char *citation;        /* "Ritschel, Grosch, Kautz, Mueller. EGSR 2007" */
    const char *version;         /* the plugin's own version string */
    uint32_t caps;               /* gi_caps */
    uint32_t max_bounces;        /* indirect bounces it can compute (0 = direct only) */
    const gi_param_desc *params; /* terminated by an entry with name NULL */

    gi_result (*create)(const gi_host *host, const gi_params *params, void **instance);
    gi_result (*prepare)(void *instance, const gi_gpu_scene *scene);
    gi_result (*update)(void *instance, const gi_gpu_scene *scene, const gi_changes *changes);
    gi_result (*render)(void *instance, const gi_view *view, const gi_target *target);
    void (*destroy)(void *instance);
    const char *(*last_error)(void *instance);
    /* ABI 1.1: the data layout the plugin was built against; set it to
     * GI_ABI_LAYOUT (gi/kit.h, which a plugin includes). Required. */
    gi_abi_layout layout;
    /* ABI 1.2: the method's declared departures, terminated by an entry
     * with check NULL; NULL (or a plugin built for ABI 1.1, whose
     * struct_size ends before this field) declares none. Read it through
     * gi_method_departure (gi/plugin.h), which guards with GI_HAS_FIELD. */
    const gi_departure *departures;
    /* ABI 1.3: the method's debug buffers, terminated by an entry with
     * name NULL; NULL (or a plugin built before ABI 1.3, whose struct_size
     * ends before this field) declares none. Read them through
     * gi_method_debug_buffers (gi/plugin.h), which guards with GI_HAS_FIELD. */
    const gi_debug_buffer_desc *debug_buffers;
    /* ABI 1.3, required when debug_buffers declares any: buffer `name` (one
     * of debug_buffers) as it stands after the last render(), which was
     * given `view`. *out: a new image from gi_image_create (gi/image.h; the
     * host frees it with gi_image_free), row 0 the top row, RGB in rgba
     * (alpha ignored), view->width x view->height for a GI_DEBUG_SCREEN
     * buffer. May render (GL is current) but must not change what the next
     * render() makes. On error *out is NULL and last_error says why. */
    gi_result (*debug_buffer)(void *instance, const char *name, const gi_view *view,
                              gi_image **out);
} gi_method;

typedef const gi_method *(*gi_method_entry_fn)(uint32_t host_abi_version);

/* The one symbol a plugin defines and exports (declared here so that the
 * definition is checked against it). */
GI_EXPORT const gi_method *gi_method_entry(uint32_t host_abi_version);

#ifdef __cplusplus
}
#endif
#endif
