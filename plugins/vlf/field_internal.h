/* Declarations shared by the files of the vlf method's CPU side (see
 * vlf_field.h), not part of its interface: the fragment lists of a subfield
 * (§3.2, subfields.c), the steps that build the field (faces.c,
 * subfields.c, used by field.c), and the steps of propagation kept in files
 * of their own (lights.c, scatter.c, perturbed.c, used by propagate.c). A
 * file including it defines _POSIX_C_SOURCE first (clock_gettime).
 *
 * The steps without a gi_error fail only for lack of memory: they return
 * GI_ERR_OUT_OF_MEMORY (or NULL) without a message, and the function of
 * vlf_field.h that runs them words it (it knows what was being built). */
#ifndef VLF_FIELD_INTERNAL_H
#define VLF_FIELD_INTERNAL_H

#include <stddef.h>
#include <stdint.h>
#include <time.h>

#include "gi/scene.h"
#include "vlf_field.h"
#include "vlf_sort.h"

/* Seconds on the monotonic clock, for the stage times of vlf_stats. */
static inline double vlf_now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ---- Subfields (§3.2, subfields.c) ---------------------------------------- */

/* A fragment: where a ray (interface cell) meets an element. */
typedef struct vlf_frag {
    uint32_t cell;
    float depth;
    uint32_t rank; /* 0; 1 for the second side of a double-sided face (after the first at the same
                      depth) */
    uint32_t elem;
} vlf_frag;

typedef struct vlf_frag_buf {
    vlf_frag *v;
    size_t n, cap;
} vlf_frag_buf;

/* Sort counters of one thread. */
typedef struct vlf_sort_counts {
    uint64_t pieces, splits, bsp_cuts, unresolved, tests, groups, fallbacks;
} vlf_sort_counts;

/* The fragments of every face along subfield frame fr, in buf, grouped by
 * ray (interface cell) and front to back along fr->n within each ray
 * (§3.2). Faces order: the faces sorted by vlf_sort_faces and rasterised in
 * that order, each ray's fragments then kept in the order they came
 * (a stable bucket sort by cell); rays order: all fragments sorted by cell
 * and depth. bbox (4 per face, may be NULL) grows by the subfield cells
 * each face covers. */
gi_result vlf_list_fragments(const vlf_field *f, const vlf_psf *fr, vlf_frag_buf *buf,
                             vlf_frag_buf *tmp, vlf_sorter *so, int32_t *bbox,
                             vlf_sort_counts *cnt);
/* The sort stage on f->prm.threads threads (the calling one among them):
 * every subfield's depth order and tile rectangles. */
gi_result vlf_build_subfields(vlf_field *f);

/* The slot of subfield cell (cx, cy) in the tile storage of rectangle r. */
static inline size_t vlf_rect_slot(const vlf_rect *r, uint32_t cx, uint32_t cy)
{
    return r->offset + (size_t)((int32_t)cy - r->y0) * r->w + (size_t)((int32_t)cx - r->x0);
}

/* ---- Building the field (field.c, lights.c) ------------------------------- */

/* Sets the message of a build that ran out of memory; returns
 * GI_ERR_OUT_OF_MEMORY. */
gi_result vlf_build_out_of_memory(const vlf_field *f, gi_error *err);
/* The scene's lights at time t other than emission and sky (lights.c):
 * the directional lights' radiance into the interfaces (f->sun), the
 * point and spot lights (f->punctual) with the scene for their shadow rays
 * (f->rt). */
gi_result vlf_add_lights(vlf_field *f, const gi_scene *s, float t, gi_error *err);

/* ---- Faces and elements (§3.1, faces.c) ----------------------------------- */

/* Faces: the scene's triangles grouped by material and plane (normal and
 * offset to 1e-3), each group one face with a chart of density texels per
 * unit length over its bounding rectangle in the plane (§3.1: one
 * irradiance texture per face; the charts are the atlas). */
gi_result vlf_group_faces(vlf_field *f, const gi_scene *s, float t); /* or GI_ERR_CANCELLED */
/* Area of each element inside its face: every triangle clipped exactly
 * against the texels of its bounding box. */
void vlf_element_areas(vlf_field *f, const gi_scene *s);
/* Cuts every triangle into k^2 (a regular grid of its barycentric
 * coordinates, the winding kept): the same surfaces as more faces, for the
 * paper's claim that propagation is linear in the number of faces. */
gi_result vlf_subdivide_triangles(vlf_field *f, uint32_t k);
/* The triangles to sort (f->sort_*, see vlf_field.h): tri_*, or with
 * any order but rays (any path) and subdivide = 1 the faces that tile a convex polygon
 * as its fan (the rasteriser then draws tens, not thousands, of triangles
 * a direction). Fails only out of memory. */
gi_result vlf_merge_faces(vlf_field *f);

/* ---- Propagation (§3.2-§3.5) ---------------------------------------------- */

/* The point and spot lights' first shot into the next maps (lights.c). */
gi_result vlf_punctual_first_shot(vlf_field *f);
/* Non-diffuse scattering (§3.4) of what subfield i brought (scatter.c). */
void vlf_scatter(vlf_field *f, uint32_t i);

/* The perturbed directions of §3.5 during propagation (perturbed.c): their
 * fragment lists sorted on the propagating thread, or on f->prm.threads
 * threads beside the sweeps. NULL out of memory. */
typedef struct vlf_perturbed vlf_perturbed;
vlf_perturbed *vlf_perturbed_create(vlf_field *f);
/* The sweeps of every perturbed direction of fixed direction i, both ways,
 * standing in for the fixed direction's. */
gi_result vlf_perturbed_sweeps(vlf_perturbed *pt, uint32_t i, int first_iteration);
void vlf_perturbed_free(vlf_perturbed *pt); /* NULL is fine */

#endif
