/* Local lights of the csm plugin (Ritschel et al. 2007 §4.2, §3.3, §4.4):
 * the scene's lights as parameterised shapes, depth cube maps at N points
 * on each, and the query on them. GLSL twin: shaders/csm_local.glsl (held
 * equal by tests/csm_local.c).
 *
 * Lights (csm_lights_collect), in world space at the prepare time:
 *   - area (d = 2): an object with emissive triangles is one light; its
 *     emissive triangles are fitted by their planar bounding rectangle
 *     (normal = area-weighted mean of the triangle normals; in the plane
 *     the smallest-area rectangle with a side along a triangle edge, which
 *     is the minimum-area rectangle when the first 256 triangles hold the
 *     convex hull's edges): corner o,
 *     edges e1 (the longer) and e2. The mapping D(x) of §4 is
 *     D(u, v) = o + u e1 + v e2 on [0, 1]^2, discretised at the centres of
 *     an n_u x n_v grid: l(a, b) = o + (a + 1/2)/n_u e1 + (b + 1/2)/n_v e2.
 *   - linear (d = 1): the same rectangle when |e1| / |e2| exceeds the
 *     linear_aspect threshold: n_v = 1, the points lie on the centre line.
 *   - point (d = 0): a KHR_lights_punctual point or spot light, one point,
 *     n_u = n_v = 1 (e1 = e2 = 0).
 * The continuous grid coordinates of a point y near the light are
 *   u = ((y - o).e1 / |e1|^2) n_u - 1/2,  v likewise (0 where n = 1),
 * so the nearest grid point is (clamp(round(u)), clamp(round(v))).
 *
 * Cube maps (§3.3): at every grid point, six perspective 90-degree maps in
 * GL face order +X, -X, +Y, -Y, +Z, -Z (gi_mat4_cube_face_view), radial
 * depth. Sequence index of face k of grid point i (i = the point's
 * enumeration index, csm_order.h, over the n_u x n_v grid): k N + i, N =
 * n_u n_v, so one codec holds 6 N maps. A point x (same space as the grid
 * point l) is looked up in face gi_cube_face(x - l), at texel
 *   ((s.d / f.d) / 2 + 1/2) M, ((t.d / f.d) / 2 + 1/2) M   (row 0 at t = -1)
 * with the face's right s, up t and forward f (gi_cube_basis, gi/algo/cubemap.h), depth |x - l|. */
#ifndef CSM_LOCAL_H
#define CSM_LOCAL_H

#include "csm_cpu.h"
#include "gi/algo/cubemap.h"

typedef enum csm_light_kind {
    CSM_LIGHT_AREA = 0,
    CSM_LIGHT_LINEAR = 1,
    CSM_LIGHT_POINT = 2
} csm_light_kind;

typedef struct csm_light {
    csm_light_kind kind;
    int object;   /* the emissive object of an area/linear light, else -1 */
    int punctual; /* index into scene->lights of a point/spot light, else -1 */
    gi_vec3 origin, e1, e2, normal;
    uint32_t n_u, n_v;
} csm_light;

/* The lights of scene s at time t: one per object with emissive triangles
 * (area, or linear above linear_aspect), then one per point/spot light
 * (directional lights are distant: the orthographic CSMs serve them).
 * n_points: grid points per dimension of area lights (linear lights get
 * n_points x 1). *out is malloc'd (NULL when there is none); returns the
 * count. */
uint32_t csm_lights_collect(const gi_scene *s, float t, uint32_t n_points, float linear_aspect,
                            csm_light **out);

/* Grid point (a, b) of the rectangle (o, e1, e2) with n_u x n_v points. */
gi_vec3 csm_light_point(gi_vec3 o, gi_vec3 e1, gi_vec3 e2, uint32_t n_u, uint32_t n_v, uint32_t a,
                        uint32_t b);
/* Continuous grid coordinates (u, v) of point y. */
void csm_light_grid(gi_vec3 o, gi_vec3 e1, gi_vec3 e2, uint32_t n_u, uint32_t n_v, gi_vec3 y,
                    float *u, float *v);

/* One object's cube-map CSM for one light, in the object's local space:
 * the light's rectangle taken there (o, e1, e2), grid n_u x n_v in
 * enumeration `order`. */
typedef struct csm_local_desc {
    uint32_t M;
    gi_vec3 o, e1, e2;
    uint32_t n_u, n_v;
    gi_csm_order order;
    int z3;      /* CSM_DEPTH_* (csm_cpu.h) */
    float shell; /* thin-shell depth behind a lone first surface (csm_texel_depths); 0: open */
    uint32_t batch;
} csm_local_desc;

/* Renders (core depth renderer, radial metric, this object only, object-
 * local) and compresses the 6 n_u n_v cube faces in the sequence order
 * above. host may be NULL (tests); otherwise progress, timers depth_render
 * and compress, and cancellation as csm_build_object. */
gi_result csm_build_local(const gi_gpu_scene *gs, uint32_t object, const float sphere[4],
                          const csm_local_desc *desc, const gi_host *host, float p0, float p1,
                          gi_csm_data *out, gi_error *err);

/* Nearest-filter visibility (1 lit) between local point x and the grid
 * point nearest to grid coordinates (u, v) through that CSM; bias in local
 * units. */
int csm_local_visible_nearest(const gi_csm_data *data, const csm_local_desc *desc, gi_vec3 x,
                              float u, float v, float bias);

#endif
