/* Shared render passes: the G-buffer and depth maps.
 *
 * G-buffer (gi_gbuffer): one FBO with these RGBA textures, all width x height,
 * row 0 at the bottom (GL):
 *   tex_position  RGBA32F  world position xyz, w = linear eye depth (> 0),
 *                          w = 0 where no surface was hit
 *   tex_normal    RGBA16F  world shading normal xyz (unit, facing the eye), w = 0
 *   tex_albedo    RGBA16F  Lambert albedo (texture applied), a = 1 if mirror
 *   tex_phong     RGBA16F  ks rgb, exponent
 *   tex_emission  RGBA16F  emitted radiance toward the eye (area lights seen
 *                          directly), a = 1 for a hit
 *   tex_ids       RGBA32UI object, material, triangle (scene-global index),
 *                          0xFFFFFFFF for all three where nothing was hit
 *   tex_depth     DEPTH32F hardware depth
 * Plugins sample them with texelFetch; the core also provides
 * core/shaders/gbuffer_read.glsl with the decoding helpers.
 *
 * Depth maps (gi_depth_*): LINEAR depth written to RGBA32F layers of a 2D
 * array texture: channel k holds the (k+1)-th surface along each ray
 * (depth peeling, up to 4 surfaces), +INF (FLT_MAX) where fewer surfaces
 * exist. Depth metrics:
 *   GI_DEPTH_EYE_Z     distance along the view axis (-z_eye), for ortho and
 *                      perspective maps
 *   GI_DEPTH_RADIAL    Euclidean distance to the eye, for cube and paraboloid
 *                      maps (a point's depth is then independent of the face)
 * Projections: orthographic and perspective take the view's proj matrix;
 * paraboloid maps the hemisphere around the view's -Z (Brabec et al.).
 * Cube maps are six perspective views (gi_mat4_cube_face_view) into six
 * consecutive layers in GL face order +X, -X, +Y, -Y, +Z, -Z.
 */
#ifndef GI_PASSES_H
#define GI_PASSES_H

#include "gi/gpu.h"
#include "gi/shader.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct gi_gbuffer {
    uint32_t width, height;
    GLuint fbo;
    GLuint tex_position, tex_normal, tex_albedo, tex_phong, tex_emission, tex_ids, tex_depth;
    GLuint program;
} gi_gbuffer;

gi_gbuffer *gi_gbuffer_create(uint32_t width, uint32_t height, gi_error *err);
void gi_gbuffer_free(gi_gbuffer *gb);
/* Renders the scene (at the time last set on gs) seen through view_proj;
 * `eye` is needed for the facing normal. */
gi_result gi_gbuffer_render(gi_gbuffer *gb, const gi_gpu_scene *gs, const float view[16],
                            const float proj[16], gi_error *err);
/* Binds the G-buffer textures to units first_unit .. first_unit+5 in the
 * order position, normal, albedo, phong, emission, ids. */
void gi_gbuffer_bind(const gi_gbuffer *gb, GLuint first_unit);

typedef enum gi_projection {
    GI_PROJ_ORTHOGRAPHIC = 0,
    GI_PROJ_PERSPECTIVE = 1,
    GI_PROJ_PARABOLOID = 2,
} gi_projection;

typedef enum gi_depth_metric {
    GI_DEPTH_EYE_Z = 0,
    GI_DEPTH_RADIAL = 1,
} gi_depth_metric;

/* One depth map to render. */
typedef struct gi_depth_view {
    float view[16];         /* world (or object-local, see `local`) -> eye */
    float proj[16];         /* ignored for paraboloid */
    gi_projection projection;
    float znear, zfar;      /* paraboloid clip range (radial) */
} gi_depth_view;

typedef struct gi_depth_desc {
    uint32_t size;          /* maps are size x size */
    uint32_t surfaces;      /* 1..4 peeled layers (2 = dual depth, 3 = z3) */
    gi_depth_metric metric;
    int object;             /* render only this object, -1 = all */
    int local;              /* 1: ignore object transforms (object-local maps) */
    int cull;               /* 0 none, 1 back faces, 2 front faces */
} gi_depth_desc;

typedef struct gi_depth_renderer gi_depth_renderer;

gi_depth_renderer *gi_depth_renderer_create(const gi_depth_desc *desc, gi_error *err);
void gi_depth_renderer_free(gi_depth_renderer *r);
/* Allocates an RGBA32F 2D array texture with `layers` maps for this renderer. */
GLuint gi_depth_texture_create(const gi_depth_renderer *r, uint32_t layers);
/* Renders `count` views into layers first_layer .. first_layer+count-1 of
 * `array_tex` (made by gi_depth_texture_create). */
gi_result gi_depth_render(gi_depth_renderer *r, const gi_gpu_scene *gs, const gi_depth_view *views,
                          uint32_t count, GLuint array_tex, uint32_t first_layer, gi_error *err);
/* Fills six views of a cube map at `eye` (90 degree perspective). */
void gi_depth_cube_views(gi_vec3 eye, float znear, float zfar, gi_depth_view out[6]);
/* Reads layer `layer` of a depth array back (size*size*4 floats, row 0 at
 * the bottom), for tests and CPU-side compression. Caller frees. */
float *gi_depth_read_layer(GLuint array_tex, uint32_t size, uint32_t layer);

#ifdef __cplusplus
}
#endif
#endif
