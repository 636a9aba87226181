/* Ray casting on the CPU: the scene's triangles placed at one time t, in an
 * Embree 3 BVH. The one Embree scene builder of the tree: the reference path
 * tracer (harness/reference/) and every plugin or test that needs exact
 * ray queries on the CPU use it.
 *
 * Use:
 *     gi_rt *rt;
 *     if (gi_rt_create(scene, t, &rt, &err) != GI_OK) { ... err.text ... }
 *     gi_rt_hit h;
 *     if (gi_rt_intersect(rt, o, d, 0.0f, INFINITY, &h)) { ... h.t, h.triangle ... }
 *     gi_rt_set_time(rt, t2, &err);       // moves animated objects
 *     gi_rt_free(rt);
 * The scene must outlive the gi_rt (it is read, never copied or changed).
 *
 * Placement: every vertex is put in world space by its object's transform at
 * t (gi_scene_object_transform, the glTF animation sampled as everywhere
 * else), all triangles in ONE triangle geometry whose primitive index is the
 * scene-global triangle index (the G-buffer's triangle id). World shading
 * normals (inverse transpose, normalised; (0,0,0) where that is not finite)
 * are kept beside the positions for shading code. The BVH is built with
 * quality "high" and RTC_SCENE_FLAG_ROBUST (Embree avoids the optimisations
 * that reduce arithmetic accuracy) unless GI_RT_FAST_TRAVERSAL is asked for.
 *
 * Validation: a transform or a placed vertex that is not finite, or a
 * coordinate beyond 1e18 (its square overflows float), is an error
 * (GI_ERR_INVALID_ARGUMENT, "<scene file>: object k 'name': vertex i is not
 * finite at t = ..."), because Embree silently drops such triangles and the scene
 * would show holes instead of failing.
 *
 * Sides: the one rule of gi/scene.h. A triangle whose material is not
 * doubleSided does not exist for a ray that reaches its back (the side its
 * world-space corners wind clockwise): gi_rt_intersect* pass through it and
 * gi_rt_occluded ignores it. A double-sided one is hit from both sides;
 * gi_side (gi/scene.h) then says which side and turns the normals.
 * GI_RT_ALL_FACES turns culling off.
 *
 * Queries: gi_rt_intersect and gi_rt_occluded only read the committed BVH,
 * so any number of threads may query one gi_rt at once. gi_rt_set_time
 * rewrites the BVH and must not run while queries are in flight. The ray
 * interval is Embree's closed one: hits with tmin <= t <= tmax count
 * (tmin >= 0); d need not be unit length, t is in units of |d|. With no
 * moving object (no animated transform, no morph target) gi_rt_set_time
 * only records the time; otherwise it
 * re-places every vertex and rebuilds the BVH (a rebuild, not a refit: the
 * rigid motions of glTF animations can move objects far, and a refitted
 * BVH degrades with the distance moved).
 */
#ifndef GI_RAYTRACE_H
#define GI_RAYTRACE_H

#include "gi/common.h"
#include "gi/scene.h"
#include "gi/vecmath.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct gi_rt gi_rt; /* the scene's triangles placed at one time t, in a BVH */

typedef struct gi_rt_hit {
    float t;           /* ray parameter of the hit */
    uint32_t object;   /* scene object index (as in the G-buffer ids) */
    uint32_t triangle; /* scene-global triangle index (as in the G-buffer ids) */
    float u, v;        /* barycentrics of vertices 1 and 2 */
    gi_vec3 position;  /* world hit point, from the barycentrics */
    gi_vec3 ng;        /* unit geometric normal cross(p1 - p0, p2 - p0), front face = CCW;
                          (0, 0, 1) for a degenerate triangle */
} gi_rt_hit;

/* Places `scene` at `time` and builds the BVH. On success *out owns it
 * (gi_rt_free). NULL scene or out, or a non-finite time, is
 * GI_ERR_INVALID_ARGUMENT; see the manual above for what else fails. */
gi_result gi_rt_create(const gi_scene *scene, float time, gi_rt **out, gi_error *err);

/* Options of gi_rt_create_ex. */
enum {
    /* Embree's default traversal instead of RTC_SCENE_FLAG_ROBUST: about a
     * third fewer instructions per ray on the Cornell box, at the cost of
     * the rare ray that slips through the shared edge of two triangles
     * (Embree: "artifacts caused by rays shooting through edges of
     * neighboring primitives"). Hits otherwise agree to float rounding.
     * What Embree's own tutorial path tracer uses; the reference path
     * tracer's default (harness/reference/reference.h). */
    GI_RT_FAST_TRAVERSAL = 1u << 0,
    /* Every triangle is hit from both sides, whatever its material's
     * doubleSided: raw geometry, for a caller that applies its own rule.
     * Without it the one rule for sides (gi/scene.h) holds: a single-sided
     * triangle is invisible to every ray that reaches its back. */
    GI_RT_ALL_FACES = 1u << 1
};
/* gi_rt_create with options (GI_RT_*; 0 = gi_rt_create). An unknown bit is
 * GI_ERR_INVALID_ARGUMENT. */
gi_result gi_rt_create_ex(const gi_scene *scene, float time, unsigned flags, gi_rt **out,
                          gi_error *err);
/* Re-places the moving objects at `time` and rebuilds the BVH. On failure
 * the gi_rt is unchanged (still placed at its previous time). Moving:
 * animated transforms and morph targets (gi_scene_object_vertices). */
gi_result gi_rt_set_time(gi_rt *rt, float time, gi_error *err);
/* Re-places every vertex at the current time and rebuilds, for a caller
 * that owns its gi_scene and changed scene->vertices in place (a
 * procedural deformation; the glTF way, morph targets, needs only
 * gi_rt_set_time). Same failure rule as gi_rt_set_time. */
gi_result gi_rt_refresh(gi_rt *rt, gi_error *err);
void gi_rt_free(gi_rt *rt);

/* Closest hit of o + t d with tmin <= t <= tmax: 1 and *hit filled, or 0.
 * rt and hit must not be NULL (asserted). */
int gi_rt_intersect(const gi_rt *rt, gi_vec3 o, gi_vec3 d, float tmin, float tmax, gi_rt_hit *hit);
/* The closest hit's ray parameter, barycentrics (of vertices 1 and 2) and
 * scene-global triangle only, for callers that interpolate what they need
 * themselves (the reference path tracer): 1 and *t, *u, *v, *triangle set,
 * or 0. Same hits as gi_rt_intersect, without its position and normal. */
int gi_rt_intersect_tuv(const gi_rt *rt, gi_vec3 o, gi_vec3 d, float tmin, float tmax, float *t,
                        float *u, float *v, uint32_t *triangle);
/* Up to 8 rays at once through Embree's packet traversal
 * (rtcIntersect8, marked coherent: meant for rays that start together and
 * point alike, as a pixel's camera rays do). Ray i < n: origin o[i],
 * direction d[i], interval [tmin[i], tmax[i]]; hit[i] is 1 with t, u, v and
 * triangle set as gi_rt_intersect_tuv sets them, or 0. n <= 8. */
void gi_rt_intersect8_tuv(const gi_rt *rt, uint32_t n, const gi_vec3 *o, const gi_vec3 *d,
                          const float *tmin, const float *tmax, int *hit, float *t, float *u,
                          float *v, uint32_t *triangle);
/* 1 when any triangle lies on o + t d, tmin <= t <= tmax. */
int gi_rt_occluded(const gi_rt *rt, gi_vec3 o, gi_vec3 d, float tmin, float tmax);

/* The placement at the current time, for shading code (valid until the
 * next gi_rt_set_time or gi_rt_free): world positions and world unit
 * shading normals, 3 floats a vertex in scene vertex order. */
const float *gi_rt_positions(const gi_rt *rt);
const float *gi_rt_normals(const gi_rt *rt);
float gi_rt_time(const gi_rt *rt);
const gi_scene *gi_rt_scene(const gi_rt *rt);
/* "embree 3.13.5": the library version, for reports. */
const char *gi_rt_version(const gi_rt *rt);

#ifdef __cplusplus
}
#endif
#endif
