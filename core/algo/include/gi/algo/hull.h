/* Convex hulls of point sets (qhull, libqhull_r) and an overlap test
 * between two hulls placed by rigid transforms (GJK on the hull vertices).
 * Used by cssm_hrc for the condition of moving objects in Ritschel et al.
 * 2008 §3.3 (precomputed visibility stays valid only while the convex hulls
 * of the objects do not overlap); generic, so in core.
 *
 * Use:
 *     gi_hull h;
 *     if (gi_hull_build(points, n, &h, &err) != GI_OK) { ... err.text ... }
 *     ... gi_hull_overlap(&h, ma, &g, mb, margin) ...   // once per frame
 *     gi_hull_free(&h);
 * On GI_OK the caller owns h and frees it with gi_hull_free (freeing a
 * zeroed or failed hull is fine). A point set that spans no volume (a
 * plane, a line) still gets a hull: qhull is asked again with joggled
 * input ("QJ"), which gives a thin solid around it; a single point or
 * coincident points give a hull of that one vertex (no faces).
 */
#ifndef GI_HULL_H
#define GI_HULL_H

#include "gi/common.h"
#include "gi/vecmath.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct gi_hull {
    gi_vec3 *vertices; /* the hull's vertices (a subset of the input points) */
    uint32_t vertex_count;
    float *planes; /* 4 per face: unit outward normal n and offset d, n.x + d <= 0 inside */
    uint32_t face_count;
} gi_hull;

/* The convex hull of `count` points (3 floats each). GI_ERR_INVALID_ARGUMENT
 * for no points or a non-finite coordinate; GI_ERR_OUT_OF_MEMORY; any other
 * qhull failure is GI_ERR_INVALID_ARGUMENT with qhull's exit code. */
gi_result gi_hull_build(const float *points, uint32_t count, gi_hull *out, gi_error *err);
void gi_hull_free(gi_hull *h);

/* The triangles of the convex hull of `count` points (3 floats each), as
 * qhull gives them with option Qt (non-simplicial facets triangulated): 3
 * point indices per triangle in *tris (malloc'd, the caller frees it), in
 * qhull's facet order, each triangle's vertices in qhull's order (not
 * oriented). For points on a sphere this is their spherical Delaunay
 * triangulation (vlf's direction set). GI_ERR_INVALID_ARGUMENT with qhull's
 * exit code when qhull fails or returns a facet that is not a triangle;
 * GI_ERR_OUT_OF_MEMORY. On failure *tris is NULL and *tri_count 0. */
gi_result gi_hull_triangulate(const float *points, uint32_t count, uint32_t **tris,
                              uint32_t *tri_count, gi_error *err);

/* 1 when the hull holds point p (outside every face plane by at most
 * `margin`). A hull without faces holds nothing. */
int gi_hull_contains(const gi_hull *h, gi_vec3 p, float margin);

/* 1 when hull a placed by the affine transform ma (column-major 4x4, e.g.
 * an object's world_from_local; NULL = identity) and hull b placed by mb
 * come closer than `margin` (0: they intersect or touch), by GJK on the
 * Minkowski difference of the transformed vertices, in double precision.
 * Touching within the numbers' precision counts as overlapping. */
int gi_hull_overlap(const gi_hull *a, const float ma[16], const gi_hull *b, const float mb[16],
                    float margin);

/* Distance between the two placed hulls (0 when they overlap). */
double gi_hull_distance(const gi_hull *a, const float ma[16], const gi_hull *b, const float mb[16]);

#ifdef __cplusplus
}
#endif
#endif
