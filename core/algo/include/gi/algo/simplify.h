/* Lower-detail copies of the scene's geometry for passes where a coarse
 * silhouette is enough (many small shadow maps, e.g. avg's VPL maps),
 * made by meshoptimizer's simplifier.
 *
 * A simplified copy is an index list only: its triangles use the scene's
 * own vertices (scene->vertices, the same indices as scene->indices), so
 * it is drawn from the scene's vertex buffer with the scene's VAO
 * (gi_simplified_draw) and follows everything that moves those vertices:
 * object transforms (the vertex's object) and morph targets written by
 * gi_gpu_scene_set_time. Which vertices are kept is chosen once, from the
 * rest pose; a caller that moves vertices itself (GI_CHANGED_VERTICES)
 * may build it again.
 *
 * Per object: vertices at equal positions are merged first (meshopt
 * shadow index buffer: attribute seams would otherwise stop the edges
 * between them from collapsing), then meshopt_simplify aims at
 * ceil(ratio x triangles) triangles without moving the surface by more
 * than max_error x the object's extent. Where that error bound (or the
 * mesh's open borders, which stay) stops it first, the object keeps more.
 * ratio >= 1 copies the scene's triangles unchanged.
 */
#ifndef GI_SIMPLIFY_H
#define GI_SIMPLIFY_H

#include "gi/gpu.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct gi_simplified {
    uint32_t triangle_count; /* total over all objects */
    uint32_t *indices;       /* 3 per triangle, into scene->vertices, object by object */
    uint32_t *object_first;  /* per object: its first triangle in `indices` */
    uint32_t *object_count;  /* per object: its triangle count */
    float max_error;         /* largest relative error meshopt reported over the objects */
    GLuint ibo;              /* the indices on the GPU (0 until gi_simplified_upload) */
} gi_simplified;

/* NULL with a message for a ratio outside (0, 1], a max_error < 0, or out
 * of memory. */
gi_simplified *gi_simplify_scene(const gi_scene *s, float ratio, float max_error, gi_error *err);
/* Uploads the indices into `ibo` (needs a current GL context). */
gi_result gi_simplified_upload(gi_simplified *m, gi_error *err);
void gi_simplified_free(gi_simplified *m);
/* Draws the simplified triangles with the scene's VAO (vertex attributes
 * as gi_gpu_scene_draw); the caller has a program bound. */
void gi_simplified_draw(const gi_simplified *m, const gi_gpu_scene *gs, GLsizei instances);

#ifdef __cplusplus
}
#endif
#endif
