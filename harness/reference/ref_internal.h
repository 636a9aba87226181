/* Internals of the reference path tracer shared by its translation units:
 * the scene as the tracer sees it (ref_scene.c builds it), the per-sample
 * path integrator (ref_path.c) and the renderer around them (reference.c).
 * Not a public header: only the .c files beside it include it. */
#ifndef GI_REF_INTERNAL_H
#define GI_REF_INTERNAL_H

#include "reference.h"

#include "gi/brdf.h"
#include "gi/envmap.h"
#include "gi/raytrace.h"
#include "gi/vecmath.h"

/* Per triangle, 32 bytes: what shading needs beside the vertices. */
typedef struct ref_tri {
    gi_vec3 ng; /* unit geometric normal, cross(p1 - p0, p2 - p0) (front face) */
    uint32_t material;
    float area;
    float light_prob; /* probability that next-event estimation picks it; 0 if not an emitter */
    float pad[2];
} ref_tri;

typedef struct ref_material {
    gi_brdf brdf; /* kd = untextured albedo */
    int textured; /* kd comes from gi_scene_albedo(uv) */
    int emits;    /* emission non-zero */
    int double_sided;
    float emission[3];
} ref_material;

/* A punctual light placed at the render time. */
typedef struct ref_light {
    gi_light_type type;
    gi_vec3 position, direction; /* direction: where it points (spot, directional) */
    float intensity[3];
    float range, cos_inner, cos_outer;
} ref_light;

typedef struct ref_camera {
    gi_vec3 eye, forward, right, up;
    float tan_half_y, aspect; /* tan(yfov / 2), width / height */
    float znear, zfar;        /* clip planes along forward, as the rasteriser has them */
} ref_camera;

typedef struct ref_scene {
    const gi_scene *scene;
    gi_rt *rt;        /* the core's BVH over the scene placed at the render time */
    const float *pos; /* world positions, 3 floats a vertex (gi_rt_positions) */
    const float *nrm; /* world unit shading normals, 3 floats a vertex (gi_rt_normals) */
    ref_tri *tris;
    ref_material *mats;
    uint32_t emitter_count;
    uint32_t *emitters; /* triangle of each emitter */
    float *emitter_cdf; /* emitter_count + 1 entries, 0 .. 1 */
    ref_light *lights;
    uint32_t light_count;
    const gi_envmap *env; /* NULL when the scene has none */
    int env_sampleable;   /* the map is not black */
    ref_camera cam;
    uint32_t width, height, seed;
    int max_bounces; /* < 0: unlimited */
    gi_ref_strategy strategy;
    int pixel_center; /* camera rays through pixel centres (gi_ref_desc) */
} ref_scene;

/* Builds everything above from the desc (validates first). */
gi_result ref_scene_build(ref_scene *rs, const gi_ref_desc *d, gi_error *err);
void ref_scene_release(ref_scene *rs);

/* Counters a worker keeps for one pass. */
typedef struct ref_counters {
    uint64_t rays;
} ref_counters;

/* A camera ray: origin, direction and the interval the rasteriser's
 * near and far planes leave. */
typedef struct ref_ray {
    gi_vec3 o, d;
    float tnear, tfar;
} ref_ray;

/* The first hit of a camera ray when the caller has traced it already. */
typedef struct ref_hit {
    float t, u, v;
    uint32_t prim;
} ref_hit;

/* The camera ray of one sample through pixel (x, y), row 0 the top; draws
 * the sample's first two numbers from *rng (the position in the pixel). */
void ref_camera_ray(const ref_scene *rs, uint32_t x, uint32_t y, uint32_t *rng, ref_ray *ray);

/* Radiance along the path that starts with camera ray `ray`, with the
 * random stream *rng after ref_camera_ray. `first` is the ray's hit when
 * the caller traced it (hit: 1 or 0), or NULL to trace it here. */
void ref_path_trace(const ref_scene *rs, const ref_ray *ray, const ref_hit *first, int hit,
                    uint32_t *rng, float L[3], ref_counters *c);

#endif
