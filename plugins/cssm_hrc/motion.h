/* Moving rigid objects in cssm_hrc (Ritschel et al. 2008 §3.3), for any
 * number of moving objects (the movers A_1 .. A_K) among static ones (the
 * rest, S):
 *
 *  - the static CSSM (cssm_hrc's maps): cube maps at the texels of S that
 *    see S alone (the depth renderer skips every mover), world space;
 *  - per mover A its own CSSM: cube maps at A's texels that see A alone,
 *    in A's local frame, made once; queried through the inverse of A's
 *    transform now, the paper's D T^-1;
 *  - per mover A its CSM (gi/algo/csm_distant.h, local frame): whether A blocks
 *    a segment between two points outside its hull;
 *  - with two or more movers, per static object its CSM too (local frame):
 *    whether S blocks a segment between points of two different movers,
 *    which no static cube map sees;
 *  - per object the convex hull of its vertices (gi/algo/hull.h, local frame,
 *    once); per frame every pair of objects with a mover in it is tested.
 *
 * Visibility between a texel j and a receiver x (cssm_visible_rc), g(.)
 * the mover a point lies on or S:
 *   g(j) = g(x) = A:  A's CSSM at j (T_A^-1 x). Nothing else lies inside
 *                     A's hull (the condition checked per frame), so
 *                     nothing else lies between two points of A.
 *   g(j) = g(x) = S:  the static CSSM at j;
 *   otherwise         the self test at j (its CSSM toward x) x the self
 *                     test at x toward j (a texel: its CSSM; a pixel on S:
 *                     the static CSSM of its "proxy", the nearest texel of
 *                     its object; a pixel on a mover B: B's CSM on the
 *                     segment) x, when neither end lies on S, every static
 *                     object's CSM (an object whose hull holds an end is
 *                     left out: it cannot lie between two points inside a
 *                     convex shell such as the box's walls; see README);
 *   and always        x not (the CSM of every other mover blocks j-x).
 * With one mover this is the table of the README. The condition: no
 * triangle of another object inside a mover's convex hull (shrunk by 0.1 %
 * so that resting contact does not count): `hull_intrusion`. The paper's
 * literal condition, the hulls of two objects overlapping, is reported as
 * `hull_overlap` (a room around a mover always overlaps it). Both per
 * pair, too. */
#ifndef CSSM_MOTION_H
#define CSSM_MOTION_H

#include "cssm.h"

#include "gi/algo/csm_distant.h"
#include "gi/algo/hull.h"

typedef struct cssm_mover {
    uint32_t object;       /* its scene object */
    cssm_maps self;        /* its CSSM, its frame (maps at its texels; the others "don't care") */
    gi_csm_distant csm;    /* its CSM, its frame */
    float T0inv[16];       /* local_from_world at prepare time */
    float T[16], Tinv[16]; /* world_from_local and local_from_world now */
    float scale;           /* the transform's scale (world units per local unit) */
} cssm_mover;

/* A pair of objects with a mover in it, and its last hull check. */
typedef struct cssm_hull_pair {
    uint32_t a, b;           /* objects, a < b */
    unsigned char overlap;   /* the placed hulls meet */
    unsigned char intrusion; /* a surface of one lies inside the other's (mover's) hull */
} cssm_hull_pair;

typedef struct cssm_motion {
    int32_t moving; /* the first mover's object, -1: not in moving-object mode */
    uint32_t mover_count;
    cssm_mover *movers;
    int32_t *mover_of;          /* per object: its mover, -1 for a static object */
    unsigned char *on_moving;   /* per texel: 1 on a mover */
    unsigned char *on_static;   /* per texel: 1 not on a mover */
    gi_vec3 *local_p, *local_n; /* per texel on a mover: position and normal in its frame */
    cssm_chart *local_charts;   /* the atlas' charts of movers in their frames */
    uint32_t *object_of;        /* per texel: its object */
    unsigned char
        *object_moves; /* per object: 1 for a mover (what the static CSSM does not draw) */
    uint32_t *obj_first,
        *obj_texels; /* texels of object k: obj_texels[obj_first[k] .. obj_first[k + 1]) */
    gi_hull *hulls;  /* per object, local frame */
    uint32_t object_count;
    gi_csm_distant
        *static_csm;    /* per object, with two or more movers: a static object's CSM (else zero) */
    float *static_Tinv; /* per object: 16 floats, a static object's local_from_world */
    float *static_scale; /* per object: its transform's scale */
    cssm_hull_pair *pairs;
    uint32_t pair_count;
    uint32_t overlaps, intrusions; /* the last check: pairs that overlap / intrude */
    char what[200];                /* the last check's first intrusion in words (warning) */
} cssm_motion;

/* The first moving object of scene s, -1 when none; *count gets the
 * number of animated objects. */
int32_t cssm_motion_find(const gi_scene *s, uint32_t *count);

/* Per-texel bookkeeping, the movers' frames at prepare time t, the hulls
 * and pairs; every animated object of s is a mover. The maps (each
 * mover's self and csm, the static CSMs) are made by
 * cssm_motion_build_maps. */
gi_result cssm_motion_init(const gi_scene *s, float t, const cssm_atlas *a, cssm_motion *out,
                           gi_error *err);
/* Each mover's CSSM and CSM, and with two or more movers the static
 * objects' CSMs (a GL context current). host may be NULL. */
gi_result cssm_motion_build_maps(cssm_motion *m, const gi_gpu_scene *gs, const cssm_atlas *a,
                                 const uint32_t *order, uint32_t M, const gi_host *host,
                                 gi_error *err);
void cssm_motion_free(cssm_motion *m);

/* Places every mover at time t: its texels and charts in the atlas, T and
 * T^-1. */
void cssm_motion_place(cssm_motion *m, const gi_scene *s, float t, cssm_atlas *a);
/* The hull check at time t, per pair of objects with a mover in it:
 * overlap (placed hulls meet) and intrusion (a triangle of one inside the
 * hull of the other, a mover, shrunk by 0.1 % about its centroid); totals
 * m->overlaps, m->intrusions, and m->what. Returns m->intrusions. */
uint32_t cssm_motion_check(cssm_motion *m, const gi_scene *s, float t);

/* The world position of texel j's cube map centre now (static maps or
 * its mover's, placed). */
gi_vec3 cssm_motion_eye(const cssm_motion *m, const cssm_maps *maps, uint32_t j);
/* 1 + the mover that triangle tri lies on, 0 for a static one. */
uint32_t cssm_motion_mover1(const cssm_motion *m, const gi_scene *s, uint32_t tri);

/* The proxy texel of a surface point on triangle tri (a pixel): the
 * nearest texel of the triangle's object whose normal faces the same way,
 * -1 when none. */
int32_t cssm_motion_proxy(const cssm_motion *m, const gi_scene *s, const cssm_atlas *a,
                          uint32_t tri, gi_vec3 p, gi_vec3 n);

#endif
