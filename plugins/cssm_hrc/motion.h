/* Moving rigid objects in cssm_hrc (Ritschel et al. 2008 §3.3), for one
 * moving object A among static ones (the rest, S):
 *
 *  - the static CSSM (cssm_hrc's maps): cube maps at the texels of S that
 *    see S alone (the depth renderer skips A), world space;
 *  - A's own CSSM: cube maps at A's texels that see A alone, in A's local
 *    frame, made once; queried through the inverse of A's transform now,
 *    the paper's D T^-1;
 *  - A's CSM (gi/csm_distant.h, local frame): whether A blocks a segment
 *    between two points of S;
 *  - per object the convex hull of its vertices (gi/hull.h, local frame,
 *    once); per frame the hulls placed by the objects' transforms and
 *    tested against A's.
 *
 * Visibility between a texel j and a receiver x (cssm_visible_rc):
 *   j on A, x on A:  A's CSSM at j (T^-1 x). Nothing of S lies inside A's
 *                    hull (the condition checked per frame), so nothing of
 *                    S lies between two points of A.
 *   j on A, x on S:  A's CSSM at j (T^-1 x) x the static CSSM of x's texel
 *                    (for a pixel: the nearest texel of its object, its
 *                    "proxy") toward j.
 *   j on S, x on A:  the static CSSM at j x, for a texel x, A's CSSM at x
 *                    toward T^-1 j; for a pixel, A's CSM on the segment
 *                    T^-1 j - T^-1 x (j lies outside A's hull).
 *   j on S, x on S:  the static CSSM at j x not (A's CSM blocks j-x); both
 *                    ends lie outside A's hull.
 * The condition: no triangle of S inside A's convex hull (shrunk by 0.1 %
 * so that resting contact does not count): `hull_intrusion`. The paper's
 * literal condition, A's hull against the other objects' hulls, is
 * reported as `hull_overlap` (a room around A always overlaps). */
#ifndef CSSM_MOTION_H
#define CSSM_MOTION_H

#include "cssm.h"

#include "gi/csm_distant.h"
#include "gi/hull.h"

typedef struct cssm_motion {
    int32_t moving;             /* A, -1: not in moving-object mode */
    unsigned char *on_moving;   /* per texel: 1 on A */
    unsigned char *on_static;   /* per texel: 1 not on A */
    gi_vec3 *local_p, *local_n; /* per texel: position and normal in A's frame (A's texels) */
    cssm_chart *local_charts;   /* the atlas' charts in A's frame (A's charts) */
    uint32_t *object_of;        /* per texel: its object */
    unsigned char *object_moves; /* per object: 1 for A (what the static CSSM does not draw) */
    uint32_t *obj_first,
        *obj_texels;       /* texels of object k: obj_texels[obj_first[k] .. obj_first[k + 1]) */
    cssm_maps self;        /* A's CSSM, A's frame */
    gi_csm_distant csm;    /* A's CSM, A's frame */
    float T0inv[16];       /* A's local_from_world at prepare time */
    float T[16], Tinv[16]; /* A's world_from_local and local_from_world now */
    float scale;           /* A's transform's scale (world units per local unit) */
    gi_hull *hulls;        /* per object, local frame */
    uint32_t object_count;
    uint32_t overlaps, intrusions; /* the last check */
    char what[160];                /* the last check in words (warning) */
} cssm_motion;

/* The moving object of scene s: the one animated object, -1 when none;
 * *count gets the number of animated objects. */
int32_t cssm_motion_find(const gi_scene *s, uint32_t *count);

/* Per-texel bookkeeping, A's frame at prepare time t, the hulls. The maps
 * (self, csm) are made by cssm_motion_build_maps. */
gi_result cssm_motion_init(const gi_scene *s, float t, const cssm_atlas *a, int32_t moving,
                           cssm_motion *out, gi_error *err);
/* A's CSSM and CSM (a GL context current). host may be NULL. */
gi_result cssm_motion_build_maps(cssm_motion *m, const gi_gpu_scene *gs, const cssm_atlas *a,
                                 const uint32_t *order, uint32_t M, const gi_host *host,
                                 gi_error *err);
void cssm_motion_free(cssm_motion *m);

/* Places A at time t: its texels and charts in the atlas, T and T^-1. */
void cssm_motion_place(cssm_motion *m, const gi_scene *s, float t, cssm_atlas *a);
/* The hull check at time t: m->overlaps (objects whose placed hull meets
 * A's), m->intrusions (objects with a triangle inside A's hull shrunk by
 * 0.1 % about its centroid), m->what. Returns m->intrusions. */
uint32_t cssm_motion_check(cssm_motion *m, const gi_scene *s, float t);

/* The proxy texel of a surface point on triangle tri (a pixel): the
 * nearest texel of the triangle's object whose normal faces the same way,
 * -1 when none. */
int32_t cssm_motion_proxy(const cssm_motion *m, const gi_scene *s, const cssm_atlas *a,
                          uint32_t tri, gi_vec3 p, gi_vec3 n);

#endif
