/* Depth cube maps as the core's depth renderer draws them (passes.h: six
 * 90-degree perspective faces in GL order +X, -X, +Y, -Y, +Z, -Z,
 * gi_mat4_cube_face_view): which face a direction falls into and where.
 * Used by the csm plugin's local lights (Ritschel et al. 2007 §3.3) and by
 * cssm_hrc's coherent surface shadow maps (Ritschel et al. 2008 §3.2).
 * GLSL twin: plugins/csm/shaders/csm_local.glsl (csm_cube_*), held equal by
 * plugins/csm/tests/csm_local.c.
 *
 * A direction d (from the cube's centre) lies in face gi_cube_face(d); with
 * the face's right s, up t and forward f (gi_cube_basis) its map
 * coordinates are sx = s.d / f.d, sy = t.d / f.d in [-1, 1], texel
 *   (floor((sx / 2 + 1/2) M), floor((sy / 2 + 1/2) M))   (row 0 at sy = -1)
 * of an M x M face. */
#ifndef GI_CUBEMAP_H
#define GI_CUBEMAP_H

#include <stdint.h>

#include "gi/vecmath.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Face holding direction d (the largest |component|; ties go to x, then y). */
int gi_cube_face(gi_vec3 d);
/* The face's right s, up t and forward f (rows of gi_mat4_cube_face_view). */
void gi_cube_basis(int face, gi_vec3 *s, gi_vec3 *t, gi_vec3 *f);
/* Map coordinates (sx, sy) in [-1, 1] of direction d in face `face`. */
void gi_cube_project(int face, gi_vec3 d, float *sx, float *sy);
/* Unit direction through the centre of texel (x, y) of face `face` of an
 * M x M cube map (the inverse of the projection above at texel centres). */
gi_vec3 gi_cube_texel_dir(int face, uint32_t M, uint32_t x, uint32_t y);

#ifdef __cplusplus
}
#endif
#endif
