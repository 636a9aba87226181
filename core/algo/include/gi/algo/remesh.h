/* Isotropic re-meshing of a triangle mesh to a target edge length, and
 * point location on a triangle mesh, both by CGAL (Polygon Mesh
 * Processing's isotropic_remeshing, an AABB tree of the triangles). The
 * C interface of core/algo/remesh.cpp.
 *
 * Every vertex of the re-meshed surface keeps its embedding on the input:
 * the input triangle it lies on (the nearest one) and its barycentric
 * weights there, so that whatever the input carries per vertex or per
 * triangle (albedo, texture coordinates, normals, rigid motion, morph
 * targets) can be carried over by interpolation (implicit visibility
 * Sec. 4.1 and 5.1: surface elements at the vertices of an evenly
 * re-meshed model).
 *
 * Open borders of the input (and edges shared by more than two triangles,
 * which are cut apart first) keep every input vertex on them, so a border
 * keeps its shape and a flat surface its area; CGAL splits their edges
 * along the border. So do creases sharper than 60 degrees. Vertices are
 * not merged: where the input splits a vertex (a hard edge, a seam), the
 * mesh has a border there.
 * A caller that wants hard edges or material boundaries kept passes the
 * patches on either side as separately indexed vertices (a border each).
 */
#ifndef GI_REMESH_H
#define GI_REMESH_H

#include "gi/common.h"

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct gi_remeshed {
    uint32_t vertex_count;
    float *positions; /* 3 per vertex */
    uint32_t *face;   /* per vertex: the input triangle it lies on */
    float *bary;      /* 3 per vertex: its barycentric weights on that triangle's corners */
    uint32_t triangle_count;
    uint32_t *indices; /* 3 per triangle, into the vertices above */
} gi_remeshed;

/* Re-meshes the input (3 floats per vertex, 3 indices per triangle) to
 * edges of about target_edge (> 0), `iterations` rounds of split, collapse,
 * flip and tangential smoothing (CGAL's default is 1; 3 to 5 even out a
 * badly shaped mesh). NULL with a one-line message on bad input (an index
 * out of range, no triangle, target_edge <= 0) or when CGAL fails. */
gi_remeshed *gi_remesh_isotropic(const float *positions, uint32_t vertex_count,
                                 const uint32_t *indices, uint32_t triangle_count,
                                 float target_edge, uint32_t iterations, gi_error *err);
void gi_remeshed_free(gi_remeshed *r);

/* Nearest point on the mesh to each of `count` points: its triangle (face)
 * and barycentric weights there (3 per point, summing to 1). Returns
 * GI_OK, or an error with a message on bad input. */
gi_result gi_mesh_locate(const float *positions, uint32_t vertex_count, const uint32_t *indices,
                         uint32_t triangle_count, const float *points, uint32_t count,
                         uint32_t *face, float *bary, gi_error *err);

#ifdef __cplusplus
}
#endif
#endif
