/* The depth order of the vlf method's faces along one subfield direction
 * (Mortensen, Khanna, Slater 2007, §3.2): the scene's triangles sorted
 * front to back by Newell's painter's ordering, with a triangle split by
 * another's plane where a cycle of overlaps makes any plain order wrong,
 * and the scene cut first by planes orthogonal to the direction through
 * its centre of mass (the paper's BSP split for large scenes). No GL, no
 * threads here: subfields.c and perturbed.c run one sorter per thread, one
 * direction at a time. */
#ifndef VLF_SORT_H
#define VLF_SORT_H

#include <stdint.h>

#include "gi/common.h"
#include "gi/vecmath.h"

/* A convex polygon: a scene triangle or a piece of one after splitting,
 * its vertices in the sorter's pool (subfield frame: x = p.u, y = p.v,
 * depth z = p.n; front = small z). */
typedef struct vlf_piece {
    uint32_t tri;          /* scene triangle it is part of */
    uint32_t first, count; /* vertices in the pool */
    float lo[3], hi[3];    /* bounds in the frame */
} vlf_piece;

/* Workspace of one sorting thread, reused across directions. */
typedef struct vlf_sorter {
    gi_vec3 *vert;
    uint32_t nv, cap_v;
    vlf_piece *poly;
    uint32_t np, cap_p;
    float *plane; /* 4 per scene triangle: unit normal with z >= 0 and offset, in the frame */
    uint32_t cap_plane;
    uint32_t *list; /* pieces still to place, by nearest depth */
    uint32_t nlist, cap_list;
    uint32_t *out; /* the order: pieces front to back */
    uint32_t nout, cap_out;
    int32_t *chain_pos; /* position of a piece on the candidate chain, -1 if not on it */
    uint32_t *chain;
    uint8_t *state;  /* 0 waiting, 1 placed, 2 replaced by its pieces */
    uint32_t *stamp; /* last candidate scan that met the piece */
    uint32_t cap_state;
    /* a uniform grid over the projections of the list being ordered: the
     * pieces whose projected bounds meet each cell (linked lists), and the
     * pieces too wide for it, met by every scan */
    uint32_t G, *cell_first, cap_cells;
    float gx0, gy0, gsx, gsy;
    uint32_t *node_piece, *node_next, nnode, cap_node;
    uint32_t *wide, nwide, cap_wide;
    uint32_t scan;
    uint64_t tests;          /* pairs tested */
    uint32_t splits;         /* pieces split to break a cycle */
    uint32_t bsp_cuts;       /* pieces cut by a BSP plane */
    uint32_t unresolved;     /* cycles left in place when the split limit was reached */
    uint32_t groups;         /* groups sorted on their own (the hierarchical shortcut) */
    uint32_t hier_fallbacks; /* sorts redone without the shortcut (a stand-in split by a cycle) */
    /* Polled every 1024 candidates while ordering (NULL: never): when it
     * returns non-zero the sort stops and vlf_sort_faces returns
     * GI_ERR_CANCELLED, so that a cancel does not wait for a whole
     * direction's sort. */
    int (*cancelled)(void *);
    void *cancel_user;
    uint32_t polls;
    int stopped;
} vlf_sorter;

enum { VLF_SORT_NEWELL = 0, VLF_SORT_PLAIN = 1, VLF_SORT_NOSPLIT = 2 };

/* Orders the triangles tri_p[3 k .. 3 k + 2] (k < tri_count) along n (frame
 * u, v, n orthonormal): on return s->out[0 .. s->nout) are pieces front to
 * back, s->poly and s->vert hold them. mode VLF_SORT_NEWELL: Newell's
 * ordering with splitting; VLF_SORT_PLAIN: by nearest depth only (the
 * plain painter's sort, wrong where faces overlap cyclically) and
 * VLF_SORT_NOSPLIT (Newell's ordering leaving cycles in place) are kept for
 * the tests. bsp_levels > 0: lists of at least bsp_min pieces are cut at the
 * depth of their centre of mass into front and back lists, each ordered on
 * its own, up to bsp_levels deep. group (may be NULL) gives each triangle's
 * group (a scene object); with hier_min > 0, groups of at least hier_min
 * triangles whose bounding box in the frame no other triangle reaches into
 * are sorted on their own and spliced in where their box's front face
 * falls in the order of the rest (the hierarchical shortcut of §3.2).
 * Fails only out of memory (GI_ERR_OUT_OF_MEMORY, no message: the caller
 * words it). */
gi_result vlf_sort_faces(vlf_sorter *s, const gi_vec3 *tri_p, uint32_t tri_count,
                         const uint32_t *group, uint32_t hier_min, gi_vec3 u, gi_vec3 v, gi_vec3 n,
                         int mode, uint32_t bsp_levels, uint32_t bsp_min);
void vlf_sorter_free(vlf_sorter *s);

#endif
