/* One object's Coherent Shadow Map over directions, in its local frame
 * (Ritschel et al. 2007 §3.1, §4.1): orthographic dual-depth maps of the
 * object alone for N_theta x N_phi directions of the full sphere,
 * compressed by the core's codec (gi/algo/csm_codec.h) in scanline order; and
 * the occlusion of a segment by the object. cssm_hrc uses it as "the CSM"
 * of a moving object (Ritschel et al. 2008 §3.3): the test whether the
 * object blocks the segment between two points of other objects, whose
 * endpoints lie outside its convex hull.
 *
 * Conventions (those of plugins/csm/csm_cpu.h, so that one can serve the
 * other):
 *   d(theta, phi) = (sin theta cos phi, cos theta, sin theta sin phi),
 *   cell (a, b) centred at phi = 2 pi (a + 1/2) / N_phi,
 *   theta = pi (b + 1/2) / N_theta; the map of a cell looks along -d from
 *   c + 2 R d (bounding sphere c, R), basis t = (-sin phi, 0, cos phi),
 *   b = d x t, footprint [-R, R]^2, depth 2 R - (x - c).d.
 *
 * Use (GL context current for build):
 *   gi_csm_distant c;
 *   gi_csm_distant_build(gs, object, &desc, &c, &err);
 *   ... gi_csm_distant_blocks(&c, p_local, q_local, bias) ...
 *   gi_csm_distant_free(&c);
 */
#ifndef GI_CSM_DISTANT_H
#define GI_CSM_DISTANT_H

#include "gi/algo/csm_codec.h"
#include "gi/algo/csm_order.h"
#include "gi/passes.h"
#include "gi/vecmath.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct gi_csm_distant_desc {
    uint32_t M;              /* map size; 0 = 32 */
    uint32_t n_theta, n_phi; /* directions; 0 = 32 and 2 n_theta */
    float shell;             /* depth behind a lone first surface, x R; 0 = 0.01 */
} gi_csm_distant_desc;

typedef struct gi_csm_distant {
    gi_csm_data data; /* maps in scanline order over (a along phi, b along theta) */
    float sphere[4];  /* the object's local bounding sphere (gi_mesh_object_sphere) */
    uint32_t n_theta, n_phi;
} gi_csm_distant;

/* Renders (core depth renderer: this object only, object-local, eye-z, two
 * surfaces) and compresses the maps. GI_ERR_INVALID_ARGUMENT for an object
 * out of range; the depth renderer's and codec's errors. */
gi_result gi_csm_distant_build(const gi_gpu_scene *gs, uint32_t object,
                               const gi_csm_distant_desc *desc, gi_csm_distant *out, gi_error *err);
void gi_csm_distant_free(gi_csm_distant *c);

/* 1 when the object blocks the segment p-q (object-local points): the
 * segment is taken along the nearest map direction through its point
 * nearest the sphere's centre, and it is blocked when the map's z_avg
 * there lies between the depths of p and q (by more than bias, local
 * units). Exact up to the direction and texel discretisation when p and q
 * lie outside the object's convex hull (the line then meets the hull in
 * one interval that holds every surface the map stores). */
int gi_csm_distant_blocks(const gi_csm_distant *c, gi_vec3 p, gi_vec3 q, float bias);

/* Visibility (1 lit, 0 shadowed) of point x toward unit direction w (both
 * in the object's local frame) through a CSM over directions with the
 * conventions above, maps in `order` over (a along phi, b along theta):
 * x is projected into the map of the direction cell nearest w and lit when
 * its depth is at most that texel's z_avg + bias (Ritschel et al. 2007
 * §3.2, the nearest filter of §4.5). Points outside the map's footprint
 * are lit. The query of the csm plugin and of cssm_hrc's direct=csm
 * (direct light from directions, receivers on surfaces). */
int gi_csm_dir_visible(const gi_csm_data *data, const float sphere[4], uint32_t n_theta,
                       uint32_t n_phi, gi_csm_order order, gi_vec3 x, gi_vec3 w, float bias);
/* The same through gi_csm_distant's maps (scanline order). */
int gi_csm_distant_visible(const gi_csm_distant *c, gi_vec3 x, gi_vec3 w, float bias);

#ifdef __cplusplus
}
#endif
#endif
