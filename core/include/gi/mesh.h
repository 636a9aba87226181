/* Mesh measurements the methods share: triangle areas and their sampling
 * CDF, bounding spheres, welded vertices with vertex-triangle adjacency and
 * per-vertex areas (implicit visibility surfels, Dong et al. Sec. 4.1).
 * Everything in world space at a given time unless said otherwise.
 * Morph targets: the triangle areas follow them (time t); the sphere and
 * the welded vertices are of the rest pose (scene->vertices), as are the
 * precomputations that use them (such methods lack GI_CAP_DEFORMATION).
 */
#ifndef GI_MESH_H
#define GI_MESH_H

#include "gi/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Area of each triangle at time t (transforms and morph targets); out has
 * triangle_count floats. */
void gi_mesh_triangle_areas(const gi_scene *s, float t, float *out);
/* Bounding sphere (Ritter) of one object's rest pose in its local space:
 * centre xyz, radius. */
void gi_mesh_object_sphere(const gi_scene *s, uint32_t object, float out[4]);

/* Vertices merged where positions are equal (within eps x scene size),
 * per object; normals averaged. */
typedef struct gi_welded {
    uint32_t vertex_count;
    float *positions;      /* 3 per welded vertex, object-local */
    float *normals;        /* 3 per welded vertex, unit */
    uint32_t *object;      /* object of each welded vertex */
    uint32_t *remap;       /* scene vertex -> welded vertex */
    uint32_t *tri_offsets; /* vertex_count + 1 offsets into tri_list */
    uint32_t *tri_list;    /* triangles around each welded vertex */
    float *areas;          /* a third of the adjacent triangles' areas (local space) */
} gi_welded;

gi_welded *gi_mesh_weld(const gi_scene *s, float eps);
void gi_welded_free(gi_welded *w);

#ifdef __cplusplus
}
#endif
#endif
