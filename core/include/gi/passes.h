/* Shared render passes: the G-buffer and depth maps.
 *
 * G-buffer (gi_gbuffer): one FBO with these RGBA textures, all width x height,
 * row 0 at the bottom (GL):
 *   tex_position  RGBA32F  world position xyz, w = linear eye depth (> 0),
 *                          w = 0 where no surface was hit
 *   tex_normal    RGBA16F  world shading normal xyz (unit, facing the eye: the
 *                          geometric normal where the vertex normal does not,
 *                          gi_facing_normal in gi/scene.h), w = 0
 *   tex_albedo    RGBA16F  Lambert albedo (texture applied), a = 1 if mirror
 *   tex_phong     RGBA16F  ks rgb, exponent
 *   tex_emission  RGBA16F  emitted radiance toward the eye (area lights seen
 *                          directly), a = 1 for a hit
 *   tex_ids       RGBA32UI object, material, triangle (scene-global index),
 *                          0xFFFFFFFF for all three where nothing was hit
 *   tex_depth     DEPTH32F hardware depth
 * Methods read them through the kit: gi_kit_bind (kit.h) binds them at the
 * units GI_TEX_GBUFFER_* of glsl_shared.h, and core/shaders/gbuffer_read.glsl
 * declares the samplers there and decodes a pixel (gi_gbuffer_surface).
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
 *
 * Depth atlas (gi_depth_atlas_*): many small first-surface depth maps (e.g.
 * 1024 maps of 32 x 32) in ONE R32F 2D texture, all drawn by ONE instanced
 * draw: instance i renders view i (gl_InstanceID indexes an SSBO of views)
 * into tile i, clipped to its tile by four gl_ClipDistance planes (viewport
 * arrays would allow only 16 views). Tile i is column i % columns, row
 * i / columns, row 0 at the bottom (GL); columns = ceil(sqrt(capacity)),
 * rows = ceil(capacity / columns). Depth is linear (the desc's metric),
 * written as colour with a depth test on a depth buffer of the atlas' size,
 * so each texel holds the first surface exactly as gi_depth_render with
 * surfaces = 1 would (tests/unit/test_depth_atlas.c holds the two equal).
 * Texels of tiles not rendered, and texels where nothing was hit, hold
 * FLT_MAX. All objects are drawn, placed by the transforms last set on the
 * gi_gpu_scene. Projections: perspective (the view's proj matrix) or
 * paraboloid (hemisphere around the view's -Z, Brabec et al. 2002; the back
 * hemisphere is clipped away); one projection per atlas.
 *   gi_depth_atlas_desc d = {.tile = 32, .capacity = 1024,
 *                            .projection = GI_PROJ_PARABOLOID, .metric = GI_DEPTH_RADIAL};
 *   gi_depth_atlas *a = gi_depth_atlas_create(&d, &err);
 *   gi_depth_atlas_render(a, gs, views, n, &err);     // n <= capacity
 *   glBindTextureUnit(unit, gi_depth_atlas_texture(a));
 *   glBindBufferBase(GL_SHADER_STORAGE_BUFFER, GI_SSBO_DEPTH_ATLAS,
 *                    gi_depth_atlas_views_buffer(a));
 * GLSL side: core/shaders/depth_atlas.glsl (gi_atlas_depth looks a world
 * point up in view i's tile); gi_depth_atlas_texel is its C twin.
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
 * order position, normal, albedo, phong, emission, ids (gbuffer_read.glsl
 * expects first_unit = GI_TEX_GBUFFER_POSITION). */
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

/* One depth map to render. (Desc structs here follow the zero-means-default
 * rule: a field left 0 asks for the default the comment names.) */
typedef struct gi_depth_view {
    float view[16]; /* world (or object-local, see `local`) -> eye */
    float proj[16]; /* ignored for paraboloid */
    gi_projection projection;
    float znear, zfar; /* paraboloid clip range (radial) */
} gi_depth_view;

/* Which side of a single-sided triangle is a surface in a depth map or
 * atlas (the one rule for sides, gi/scene.h). Double-sided triangles are
 * drawn in every mode. core/shaders/depth.frag and depth_atlas.frag use the
 * same numbers.
 * EYE: the side seen from the eye (a camera's view, or a map that stands
 * for rays cast from its eye: a back face is no surface).
 * RECEIVERS: the side seen from the receivers, for a map that stands for
 * shadow rays cast from the shaded points toward the eye (as gi_rt and the
 * reference cast them): such a ray meets a single-sided triangle only when
 * its front faces the receiver, i.e. faces away from the eye, so the map
 * keeps the faces the eye sees from behind and drops those it sees from
 * the front.
 * BOTH: both sides of every triangle (raw geometry), for a caller that
 * needs the entry and exit depths of closed objects and applies the rule
 * itself or states where it does not.
 * EYE_THEN_BOTH: the first surface as EYE, every later peeled surface of
 * both sides: a closed object's entry and exit bound a closed interval
 * (dual depth), and a single-sided face the eye sees from behind still
 * hides nothing in front of the first surface (rays cast from the eye).
 * RECEIVERS_THEN_BOTH: as EYE_THEN_BOTH with the first surface as
 * RECEIVERS; a closed object's first surface is then its exit and the
 * second the receiver behind it, so a dual-depth midpoint lies between
 * the two (light leaks where an object touches its receiver).
 * ANY_THEN_RECEIVERS: the first surface of either side; the second, when
 * the first is no surface for the receivers (a single-sided face the eye
 * sees from the front), the first surface behind it that is one for them,
 * else the next of either side; later ones of both sides. The map's first
 * channel holds that first depth negated when the first surface is none
 * for the receivers, so a caller tells a face the eye sees from the front
 * with nothing behind it that the receivers see (it hides nothing from
 * them) from a surface without a second one. For dual-depth maps that
 * stand for rays cast from the receivers: a closed object's entry and exit
 * bound it, a face the eye sees from behind (a caster for the receivers)
 * starts an interval, and one it sees from the front alone casts nothing. */
typedef enum gi_sides {
    GI_SIDES_EYE = 0,
    GI_SIDES_RECEIVERS = 1,
    GI_SIDES_BOTH = 2,
    GI_SIDES_EYE_THEN_BOTH = 3,
    GI_SIDES_RECEIVERS_THEN_BOTH = 4,
    GI_SIDES_ANY_THEN_RECEIVERS = 5,
} gi_sides;

typedef struct gi_depth_desc {
    uint32_t size;          /* maps are size x size */
    uint32_t surfaces;      /* 1..4 peeled layers (2 = dual depth, 3 = z3); 0 = 1 */
    gi_depth_metric metric; /* 0 = GI_DEPTH_EYE_Z */
    uint32_t only_object;   /* 0 = all objects; k + 1 = object k alone */
    int local;              /* 1: ignore object transforms (object-local maps); 0 = world */
    int cull;               /* 0 none, 1 back faces, 2 front faces */
    uint32_t skip_object;   /* 0 = none; k + 1 = every object but k (with only_object 0) */
    const unsigned char
        *skip_objects; /* NULL = none; per object, 1: not drawn (with only_object 0);
                          read while the renderer draws, so it must outlive it */
    /* Which side of a single-sided triangle exists (gi_sides above). */
    gi_sides receiver_side;
} gi_depth_desc;

typedef struct gi_depth_renderer gi_depth_renderer;

gi_depth_renderer *gi_depth_renderer_create(const gi_depth_desc *desc, gi_error *err);
void gi_depth_renderer_free(gi_depth_renderer *r);
/* Frustum culling (on by default): each view draws only the runs of
 * triangles whose boxes are not wholly outside its clip volume, which
 * gives the same maps as drawing everything (paraboloid views are drawn
 * whole). Off draws every triangle of every view, for tests and timing. */
void gi_depth_renderer_set_culling(gi_depth_renderer *r, int on);
/* Triangles drawn and offered, summed over the views so far; a view's
 * visible runs are found once and drawn for each peeled surface, counted
 * once. With culling off, or for paraboloid views, neither counts. */
void gi_depth_renderer_drawn(const gi_depth_renderer *r, uint64_t *drawn, uint64_t *total);
/* Allocates an RGBA32F 2D array texture with `layers` maps for this renderer. */
GLuint gi_depth_texture_create(const gi_depth_renderer *r, uint32_t layers);
/* Renders `count` views into layers first_layer .. first_layer+count-1 of
 * `array_tex` (made by gi_depth_texture_create). */
gi_result gi_depth_render(gi_depth_renderer *r, const gi_gpu_scene *gs, const gi_depth_view *views,
                          uint32_t count, GLuint array_tex, uint32_t first_layer, gi_error *err);
/* Fills six views of a cube map at `eye` (90 degree perspective). */
void gi_depth_cube_views(gi_vec3 eye, float znear, float zfar, gi_depth_view out[6]);
/* Face `face` (GL order +X, -X, +Y, -Y, +Z, -Z) of those six views. */
void gi_depth_cube_view(gi_vec3 eye, float znear, float zfar, int face, gi_depth_view *out);
/* Reads layer `layer` of a depth array back (size*size*4 floats, row 0 at
 * the bottom), for tests and CPU-side compression. Caller frees. */
float *gi_depth_read_layer(GLuint array_tex, uint32_t size, uint32_t layer);
/* The same into out (size*size*4 floats), for loops that read many maps:
 * one buffer for all of them, not a fresh allocation of a quarter megabyte
 * (128^2) per map, which glibc maps and unmaps each time (above its mmap
 * threshold). */
void gi_depth_read_layer_into(GLuint array_tex, uint32_t size, uint32_t layer, float *out);

/* ---- depth atlas (see the manual above) ---- */
typedef struct gi_depth_atlas_desc {
    uint32_t tile;            /* each map is tile x tile texels (1..4096) */
    uint32_t capacity;        /* max maps; columns = ceil(sqrt(capacity)) */
    gi_projection projection; /* GI_PROJ_PERSPECTIVE or GI_PROJ_PARABOLOID */
    gi_depth_metric metric;   /* GI_DEPTH_EYE_Z or GI_DEPTH_RADIAL */
    int cull;                 /* 0 none, 1 back faces, 2 front faces */
    /* Which side of a single-sided triangle exists: GI_SIDES_EYE or
     * GI_SIDES_RECEIVERS (maps that stand for visibility rays cast from the
     * receivers toward the eye, as the reference casts them); the atlas
     * keeps one surface, so no other mode. */
    gi_sides receiver_side;
} gi_depth_atlas_desc;

typedef struct gi_depth_atlas gi_depth_atlas;

/* NULL with a message when the desc is invalid or the atlas (columns x
 * tile by rows x tile) exceeds GL_MAX_TEXTURE_SIZE. Needs a current GL
 * context. */
gi_depth_atlas *gi_depth_atlas_create(const gi_depth_atlas_desc *d, gi_error *err);
void gi_depth_atlas_free(gi_depth_atlas *a);
/* Renders views[0..count) into tiles 0..count-1 with one instanced draw
 * and clears every other tile to FLT_MAX. count > capacity, a view whose
 * projection differs from the atlas', or (paraboloid) a view without
 * 0 <= znear < zfar is GI_ERR_INVALID_ARGUMENT and draws nothing.
 * Leaves the views SSBO bound at GI_SSBO_DEPTH_ATLAS. */
gi_result gi_depth_atlas_render(gi_depth_atlas *a, const gi_gpu_scene *gs,
                                const gi_depth_view *views, uint32_t count, gi_error *err);
/* Draws the `triangle_count` triangles of index buffer `ibo` (indices into
 * the scene's vertices, e.g. a lower-detail copy, gi/algo/simplify.h) in
 * the renders that follow, through gi_gpu_scene_draw_indices; ibo 0 = the
 * scene's own triangles. The caller keeps the buffer alive while it is set. */
void gi_depth_atlas_set_geometry(gi_depth_atlas *a, GLuint ibo, uint32_t triangle_count);
struct gi_host;
/* With a host set, gi_depth_atlas_render draws in batches of about a
 * million triangles (times views) and asks host->cancelled() before each:
 * GI_ERR_CANCELLED, count 0, when it says stop (issue 32: a few thousand
 * maps of a large scene are one long draw). NULL (the default): one draw. */
void gi_depth_atlas_set_host(gi_depth_atlas *a, const struct gi_host *host);
GLuint
gi_depth_atlas_texture(const gi_depth_atlas *a); /* R32F, linear depth, FLT_MAX where empty */
GLuint gi_depth_atlas_views_buffer(const gi_depth_atlas *a); /* SSBO read by depth_atlas.glsl */
uint32_t gi_depth_atlas_columns(const gi_depth_atlas *a);
uint32_t gi_depth_atlas_rows(const gi_depth_atlas *a);
uint32_t gi_depth_atlas_count(const gi_depth_atlas *a); /* views drawn by the last render */
const gi_depth_atlas_desc *gi_depth_atlas_get_desc(const gi_depth_atlas *a);
/* GPU memory the atlas holds: its R32F texture and D32F depth buffer. */
uint64_t gi_depth_atlas_bytes(const gi_depth_atlas *a);
/* Tile `tile` read back: tile x tile floats, row 0 at the bottom; NULL when
 * tile >= capacity. For tests and CPU-side use. Caller frees. */
float *gi_depth_atlas_read_tile(const gi_depth_atlas *a, uint32_t tile);
/* C twin of gi_atlas_texel (depth_atlas.glsl): the texel (within its tile)
 * that world point p falls into in view v, and p's own depth in `metric`.
 * Returns 0 when p is outside the view's footprint (behind a perspective
 * eye, outside its frustum's sides, or in a paraboloid's back hemisphere);
 * *point_depth is set either way. */
int gi_depth_atlas_texel(const gi_depth_view *v, gi_projection projection, gi_depth_metric metric,
                         uint32_t tile, gi_vec3 p, uint32_t *tx, uint32_t *ty, float *point_depth);

#ifdef __cplusplus
}
#endif
#endif
