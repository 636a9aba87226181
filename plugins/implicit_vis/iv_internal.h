/* Declarations that the implicit_vis CPU files share among themselves,
 * not used by the lifecycle (implicit_vis.c) or the tests: the surface
 * elements (elements.c, Sec. 4.1 and 5.1) that the hierarchy
 * (hierarchy.c) is built on, and the steps of link creation (Sec. 4.2.2)
 * that the single-threaded build (links.c) and the multi-threaded one
 * (links_threads.c) share. The plugin's interface is iv.h. */
#ifndef IV_INTERNAL_H
#define IV_INTERNAL_H

#include "iv.h"

/* ---- surface elements (elements.c, hierarchy.c) ---- */

/* The surface points of s (re-meshed to `target` by `remesher` when
 * target > 0; see iv_hier_create) and their elements, into h's point,
 * surface, display-grid and element arrays. */
gi_result iv_elements_make(iv_hier *h, const gi_scene *s, float target, int remesher,
                           gi_error *err);
/* The error of a hierarchy that cannot be built, `reason` in brackets
 * ("no triangles", "out of memory"). */
gi_result iv_hier_fail(const char *reason, gi_error *err);

/* ---- link creation (links.c, links_threads.c) ---- */

/* What Sec. 4.2.2 does with the pair (A, B): nothing, link them, or try
 * B's children, or A's. Depends on the geometry only, never on the links
 * made so far, so pairs can be enumerated in any order or in parallel. */
enum { IV_PAIR_NONE, IV_PAIR_LINK, IV_PAIR_SPLIT_B, IV_PAIR_SPLIT_A };

/* The IV_PAIR_* for (A, B); d = B - A and r2 = |d|^2 are set unless it
 * is IV_PAIR_NONE, and for IV_PAIR_LINK bins[0] = the bin of d (A's
 * toward B), bins[1] = the bin of -d (B's toward A). */
int iv_pair_decide(const iv_links *l, const iv_hier *h, float subdiv, uint32_t A, uint32_t B,
                   gi_vec3 *dout, float *r2out, uint32_t bins[2]);
/* Receiver A's side of the link A-B (d = B - A, r = |d|, b = the bin of
 * d): B written into A's bin toward it, or with `splat` into every bin a
 * near disc covers. */
void iv_put_side(iv_links *l, const iv_hier *h, uint32_t A, uint32_t B, gi_vec3 d, float r,
                 uint32_t b, int splat);
/* Empties the bins of nodes first, first + step, ... */
void iv_links_clear_nodes(iv_links *l, uint32_t first, uint32_t step);
/* The hierarchical links on `threads` threads (each node's bins emptied
 * first); 0 when it could not (out of memory, no thread), and the caller
 * builds them on one. */
int iv_links_build_parallel(iv_links *l, const iv_hier *h, float subdiv, int splat, int threads);
/* The pairs linked from one top-level task (a segment with itself, or two
 * segments) at the last build, 4 words each as the threaded build lists
 * them, and the pair tests they took. */
typedef struct iv_pair_list {
    uint32_t *pairs;
    size_t n, cap;
    uint64_t tries;
} iv_pair_list;

/* What keep_pairs keeps from build to build (links_kept.c). */
typedef struct iv_kept {
    uint32_t roots;
    float *geom;        /* per node at the last build: position, normal, area (7 floats) */
    uint8_t *still;     /* per segment: every node of it the same to the bit as at the last build */
    iv_pair_list *list; /* per top-level task, in the order the build makes them: segment i
                           with itself (i), then segments i < j */
    int valid;          /* geom and list are of one completed build */
} iv_kept;

/* Marks the segments that did not move since the last completed build
 * (all moved when there was none) and records the current geometry; the
 * lists are invalid until iv_kept_done. NULL when out of memory (then
 * nothing is kept). */
iv_kept *iv_kept_begin(iv_links *l, const iv_hier *h);
/* Whether the top-level task of segments A and B (A with itself when B
 * is UINT32_MAX) can take its kept list: neither segment moved. */
int iv_kept_usable(const iv_kept *k, uint32_t A, uint32_t B);
/* Appends n pairs to task t's list; 0 when out of memory. */
int iv_kept_append(iv_kept *k, uint32_t t, const uint32_t *pairs, size_t n);
void iv_kept_free(iv_kept *k);

/* Whether l->host asks to stop (issue 32); thread-safe as the host's
 * cancelled() is (a flag set by a signal handler). */
int iv_links_cancelled(const iv_links *l);

#endif
