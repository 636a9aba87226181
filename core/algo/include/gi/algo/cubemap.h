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

#include <math.h>
#include <stdint.h>

#include "gi/vecmath.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Face holding direction d (the largest |component|; ties go to x, then y). */
static inline int gi_cube_face(gi_vec3 d)
{
    float ax = fabsf(d.x), ay = fabsf(d.y), az = fabsf(d.z);
    if (ax >= ay && ax >= az)
        return d.x >= 0.0f ? 0 : 1;
    if (ay >= az)
        return d.y >= 0.0f ? 2 : 3;
    return d.z >= 0.0f ? 4 : 5;
}

/* The face's right s, up t and forward f (rows of gi_mat4_cube_face_view). */
static inline void gi_cube_basis(int face, gi_vec3 *s, gi_vec3 *t, gi_vec3 *f)
{
    /* as gi_mat4_cube_face_view: forward and the "up" it passes to look_at */
    static const float dir[6][3] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                    {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
    static const float up[6][3] = {{0, -1, 0}, {0, -1, 0}, {0, 0, 1},
                                   {0, 0, -1}, {0, -1, 0}, {0, -1, 0}};
    *f = gi_v3_load(dir[face]);
    *s = gi_v3_cross(*f, gi_v3_load(up[face]));
    *t = gi_v3_cross(*s, *f);
}

/* Map coordinates (sx, sy) in [-1, 1] of direction d in face `face`. */
static inline void gi_cube_project(int face, gi_vec3 d, float *sx, float *sy)
{
    gi_vec3 s, t, f;
    gi_cube_basis(face, &s, &t, &f);
    float z = gi_v3_dot(f, d);
    *sx = gi_v3_dot(s, d) / z;
    *sy = gi_v3_dot(t, d) / z;
}

/* Unit direction through the centre of texel (x, y) of face `face` of an
 * M x M cube map (the inverse of the projection above at texel centres). */
gi_vec3 gi_cube_texel_dir(int face, uint32_t M, uint32_t x, uint32_t y);

#ifdef __cplusplus
}
#endif
#endif
