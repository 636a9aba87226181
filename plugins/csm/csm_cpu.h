/* CPU side of the csm plugin: the direction parameterisation, the map
 * basis and projection (GLSL twin: shaders/csm_geom.glsl, held equal by
 * tests/csm_twins.c), the precomputation of one object's
 * Coherent Shadow Map (precompute.c) and the nearest-filter query on the
 * decoded data (for tests).
 *
 * Directions (§4.1, d = 2, the full sphere), in the object's local frame:
 *   d(theta, phi) = (sin theta cos phi, cos theta, sin theta sin phi),
 *   theta in [0, pi] from +Y, phi in [0, 2 pi) from +X toward +Z.
 * Grid: N_theta x N_phi cells, cell (a, b) (a along phi, b along theta) has
 * its centre at phi = 2 pi (a + 1/2) / N_phi, theta = pi (b + 1/2) / N_theta.
 * A direction's continuous grid coordinates are
 *   u = phi / (2 pi) N_phi - 1/2,  v = theta / pi N_theta - 1/2,
 * so the nearest cell is (round(u) mod N_phi, clamp(round(v))).
 * The enumeration (csm_order.h) runs over the N_phi x N_theta grid with
 * na = N_phi, nb = N_theta.
 *
 * Map of cell (theta, phi): orthographic, looking along -d from the eye
 * c + CSM_EYE R d (sphere centre c, radius R), basis
 *   t = (-sin phi, 0, cos phi),  b = d x t,  (t, b, d) right-handed,
 * footprint [-R, R]^2, so a local point x maps to
 *   sx = (x - c).t / R, sy = (x - c).b / R  (in [-1, 1] inside the map),
 *   depth = CSM_EYE R - (x - c).d           (the depth renderer's eye z),
 * texel (floor((sx/2 + 1/2) M), floor((sy/2 + 1/2) M)), row 0 at sy = -1. */
#ifndef CSM_CPU_H
#define CSM_CPU_H

#include "gi/algo/csm_codec.h"
#include "gi/algo/csm_distant.h"
#include "gi/algo/csm_order.h"
#include "gi/method.h"
#include "gi/passes.h"
#include "gi/vecmath.h"

#define CSM_EYE 2.0f

void csm_cell_angles(uint32_t n_theta, uint32_t n_phi, uint32_t a, uint32_t b, float *theta,
                     float *phi);
gi_vec3 csm_dir(float theta, float phi);
/* Continuous grid coordinates (u along phi, v along theta) of unit w. */
void csm_grid_coords(gi_vec3 w, uint32_t n_theta, uint32_t n_phi, float *u, float *v);
void csm_basis(float theta, float phi, gi_vec3 *t, gi_vec3 *b, gi_vec3 *d);
/* (sx, sy, depth) of local point x in the map of (theta, phi). */
gi_vec3 csm_project(const float sphere[4], float theta, float phi, gi_vec3 x);
/* The depth renderer's view (local space) of that map. */
void csm_map_view(const float sphere[4], float theta, float phi, gi_depth_view *out);

/* std430 CsmObject of shaders/csm_query.glsl (160 bytes). */
typedef struct csm_gpu_object {
    float local_from_world[16];
    float world_from_local[16];
    float sphere[4];
    uint32_t M, offsets_base, segments_base, bias_bits; /* bias in local units, as float bits */
} csm_gpu_object;

typedef struct csm_build_desc {
    uint32_t M; /* map size */
    uint32_t n_theta, n_phi;
    gi_csm_order order;
    int z3;      /* CSM_DEPTH_*: 0 z2; 1 z3, else z2; 2 z3, else the spherical far plane (§3.1) */
    float shell; /* > 0: thin-shell depth (local units) behind a lone first surface; 0: open */
    uint32_t batch; /* maps per gi_depth_render call */
} csm_build_desc;

/* Second-depth options of §3.1 ("Details on depth values"), the `depth`
 * parameter: the second surface; the third surface (closed two-manifolds:
 * the back of an object needs no correct shadow) falling back to the second
 * where a texel has no third; or the third falling back to the spherical
 * far plane, the depth at which the texel's ray leaves the object's
 * bounding sphere. */
enum { CSM_DEPTH_Z2 = 0, CSM_DEPTH_Z3 = 1, CSM_DEPTH_SPHERE = 2 };

/* The codec's depths of the M x M texels of one map from the depth
 * renderer's read-back layer `map` (4 floats a texel: z1, z2, z3, -; none
 * >= FLT_MAX): z1 as it is; the second depth is z2 (mode CSM_DEPTH_Z2), or
 * the third surface where the texel has one and else z2 (CSM_DEPTH_Z3: the
 * far side of the last shell) or else far[t] (CSM_DEPTH_SPHERE: the
 * spherical far plane, csm_sphere_far; `far` is only read in that mode). A texel with a first
 * surface and no second one (an open or single-sided surface: a ground plane, a quad, the
 * silhouette of a mesh with holes) gets z1 + shell when shell > 0: the
 * surface is taken as a shell of that thickness, so the codec's z_avg stays
 * within [z1, z1 + shell) and points of other objects behind the surface
 * stay shadowed. With shell = 0 (open_surfaces=open) the second depth stays
 * "none", which tells the codec that nothing lies behind z1: it may then put
 * z_avg at the largest z1 of a whole run of maps (or FLT_MAX), so points
 * behind the surface test lit. z1 + shell may round to z1 when shell is
 * below the float spacing at z1; the codec then stores z1 (a classic
 * shadow-map texel), still shadowing what lies behind. */
void csm_texel_depths(const float *map, size_t texels, int mode, float shell, const float *far,
                      float *z1, float *z2);

/* The spherical far plane of one M x M map: for each texel the depth, in
 * the map's metric, at which the ray through the texel's centre leaves the
 * sphere (centre sphere[0..2], radius sphere[3], the map's own space);
 * FLT_MAX where the ray misses it. `v` is the map's view (orthographic or
 * perspective, core clip depth [0, 1]). */
void csm_sphere_far(const gi_depth_view *v, gi_depth_metric metric, const float sphere[4],
                    uint32_t M, float *far);

/* What csm_encode_maps renders: `count` maps of `object` (object-local,
 * only that object), map q's view given by view(ctx, q, &v), rendered in
 * batches of `batch` (0: 16), read back and streamed into the codec as map
 * q, the depths taken by csm_texel_depths(z3, shell). `what` names the maps
 * in progress and error messages ("depth maps", "cube faces"). */
typedef struct csm_encode_desc {
    uint32_t object;
    uint32_t M, count;
    gi_depth_metric metric;
    int z3;              /* CSM_DEPTH_* */
    const float *sphere; /* the object's bounding sphere (CSM_DEPTH_SPHERE) */
    float shell;
    uint32_t batch;
    void (*view)(void *ctx, uint32_t q, gi_depth_view *out);
    void *ctx;
    const char *what;
} csm_encode_desc;

/* The distant maps and the local lights' cube maps through the core's
 * precomputation loop (gi/algo/csm_precompute.h): render, read back, compress
 * (§3.1). Progress, stage timers (depth_render, compress) and cancellation
 * as csm_build_object. */
gi_result csm_encode_maps(const gi_gpu_scene *gs, const csm_encode_desc *desc, const gi_host *host,
                          float p0, float p1, gi_csm_data *out, gi_error *err);

/* Renders and compresses the N_theta N_phi maps of `object` (local space,
 * bounding sphere `sphere`). `host` may be NULL (tests); with a host it
 * reports progress (fraction p0 + p1 * done), stage timers depth_render and
 * compress, and returns GI_ERR_CANCELLED when host->cancelled(). */
gi_result csm_build_object(const gi_gpu_scene *gs, uint32_t object, const float sphere[4],
                           const csm_build_desc *desc, const gi_host *host, float p0, float p1,
                           gi_csm_data *out, gi_error *err);

/* The nearest-filter visibility of a local point toward a local direction
 * through one object's CSM is the core's gi_csm_dir_visible
 * (gi/algo/csm_distant.h: the same conventions), shared with cssm_hrc. */

#endif
