/* The CPU side of the vlf method (Mortensen, Khanna, Slater, Afrigraph 2007):
 * the direction set with its spherical triangulation (§2.1, directions.c),
 * the parallel subfields and their per-ray depth order (§3.2, subfields.c,
 * vlf_sort.c), the faces and their elements (§3.1, faces.c, field.c), the
 * storage of diffuse elements and sparse non-diffuse tiles (§3.1, §6,
 * precision.c), and the propagation of unshot radiance through radiance
 * interfaces (§3.2-§3.5, propagate.c, scatter.c, perturbed.c, lights.c).
 * No GL here: the plugin (vlf.c) uploads the result for rendering (§4),
 * and the tests drive these functions directly. */
#ifndef VLF_FIELD_H
#define VLF_FIELD_H

#include <stddef.h>
#include <stdint.h>

#include "gi/common.h"
#include "gi/scene.h"
#include "gi/vecmath.h"

/* l bi-directional directions on the upper hemisphere and the spherical
 * triangulation of the 2l signed directions (s < l: +w_s, s >= l: -w_{s-l}). */
typedef struct vlf_dirs {
    uint32_t l;
    gi_vec3 *signed_dirs; /* 2l unit vectors */
    float *solid_angle;   /* 2l: a third of the areas of the triangles at each node (sum 4 pi) */
    uint32_t tri_count;
    uint32_t *tris; /* 3 per spherical triangle, counter-clockwise seen from outside */
    float *tri_inv; /* 9 per triangle: inverse of the matrix with columns a, b, c (row-major) */
    /* The search grid of vlf_dirs_locate: a cube map of 6 grid_n^2 cells,
     * each listing in index order the triangles that may hold a direction
     * of the cell (cell c: cell_tris[cell_start[c] .. cell_start[c + 1])). */
    uint32_t grid_n;
    uint32_t *cell_start; /* 6 grid_n^2 + 1 */
    uint32_t *cell_tris;
} vlf_dirs;

/* Builds the set with qhull. */
gi_result vlf_dirs_build(vlf_dirs *d, uint32_t l, gi_error *err);
void vlf_dirs_free(vlf_dirs *d);
/* The spherical triangle holding unit direction w and its barycentric
 * weights (non-negative, summing to 1) of its three nodes; returns the
 * triangle index. */
uint32_t vlf_dirs_locate(const vlf_dirs *d, gi_vec3 w, uint32_t node[3], float alpha[3]);
/* The same by testing every triangle in index order, without the grid: the
 * definition vlf_dirs_locate's answer equals (the tests compare them). */
uint32_t vlf_dirs_locate_all(const vlf_dirs *d, gi_vec3 w, uint32_t node[3], float alpha[3]);

/* Settings: the parameters' values (names of the paper where it has them). */
typedef struct vlf_settings {
    uint32_t l; /* bi-directional directions */
    uint32_t N; /* cells per side of a parallel subfield */
    uint32_t m; /* cells per side of a tile of non-diffuse storage */
    uint32_t S; /* radiance interface cells per subfield cell and side (its super-sampling, §3.3) */
    float density;       /* diffuse elements per unit length (scene scaled into the unit sphere) */
    uint32_t iterations; /* shooting iterations */
    uint32_t perturbed;  /* perturbed virtual directions per fixed direction for transport (0: the
                            fixed one, §3.5) */
    uint32_t seed;
    uint32_t order; /* depth order of a subfield (§3.2): VLF_ORDER_FACES, _RAYS or _PLAIN */
    uint32_t
        threads; /* CPU threads building the subfields (the result is the same for any count) */
    uint32_t bsp_levels; /* BSP cuts orthogonal to the direction, levels (paper: 2) */
    uint32_t bsp_min;    /* a list is cut only with at least this many faces (paper: 4K) */
    uint32_t precision;  /* storage format of the ir/radiance maps: VLF_PREC_32F, _16F or _RGB9E5 */
    uint32_t subdivide;  /* each scene triangle cut into subdivide^2 for sorting and transport
                            (tessellation sweep) */
    uint32_t hier_min; /* hierarchical shortcut (§3.2): objects of at least this many triangles in a
                        * box no other triangle reaches into are sorted on their own; 0: off */
    uint32_t raster;   /* keep each subfield's face order as triangles to draw (vlf_psf.rorder):
                        * propagation by the rasteriser (vlf_raster.c); needs order = faces */
    /* Polled between the build's steps and between directions of the sort
     * (also from its worker threads): non-zero stops the build with
     * GI_ERR_CANCELLED. NULL: never. */
    int (*cancelled)(void *user);
    void *cancel_user;
} vlf_settings;

/* Storage formats of the light-field maps (§3.1, §6): three float32 (12
 * bytes a value), RGBA16F (the paper's 64-bit format: three halves and an
 * unused alpha, 8 bytes) and the shared-exponent RGB9E5 (4 bytes, the
 * format the paper proposes to halve memory). */
enum { VLF_PREC_32F = 0, VLF_PREC_16F = 1, VLF_PREC_RGB9E5 = 2 };

/* Bytes of one stored ir/radiance value in format prec. */
size_t vlf_precision_bytes(uint32_t prec);
/* Packs count RGB triplets (non-negative) into count * vlf_precision_bytes
 * bytes at out (16F: halves r, g, b, 0; RGB9E5: as GL_RGB9_E5), and back. */
void vlf_pack(uint32_t prec, const float *rgb, size_t count, void *out);
void vlf_unpack(uint32_t prec, const void *in, size_t count, float *rgb);
/* Rounds count RGB triplets in place to what format prec stores. */
void vlf_quantise(uint32_t prec, float *rgb, size_t count);

/* The depth order of each subfield's rays: the paper's face order (Newell's
 * painter's ordering with splitting and the BSP cut, vlf_sort.c), or each
 * ray's fragments sorted by depth (a layered depth image); for the tests
 * also the faces by nearest depth only and Newell's ordering without
 * splitting (both wrong where faces overlap in a cycle). */
enum { VLF_ORDER_FACES = 0, VLF_ORDER_RAYS = 1, VLF_ORDER_PLAIN = 2, VLF_ORDER_NOSPLIT = 3 };

/* A rectangle of tiles of one non-diffuse face in one subfield. */
typedef struct vlf_rect {
    int32_t x0, y0;
    uint32_t w, h;
    uint32_t offset; /* first cell in the tile storage */
} vlf_rect;

enum { VLF_ALBEDO_TABLE = 33 };

/* A face: the coplanar triangles of one material (the paper's planar
 * polygons), with a W x H chart of diffuse elements in its plane. */
typedef struct vlf_face {
    gi_vec3 origin; /* a point of the plane, the chart's corner (VLF coordinates) */
    gi_vec3 n;      /* unit normal */
    gi_vec3 t, b;   /* chart axes in the plane, unit */
    float area;     /* VLF units */
    uint32_t W, H;  /* chart texels */
    uint32_t first_elem;
    float kd[3], ks[3], exponent, emission[3];
    int mirror;
    uint32_t material; /* the scene's material */
    int textured;      /* its albedo has a texture (elements then average it, elem_kd) */
    int32_t nd;        /* index among non-diffuse faces, -1 for diffuse */
    int32_t twin; /* double-sided material: the face of the other side (same plane and chart, normal
                   * reversed, its own elements and tiles), -1 for single-sided */
    int back;     /* this is the back side of a double-sided face (no triangles of its own) */
    float
        send_scale; /* pi / sum over directions of |cos| dOmega (diffuse emission normalisation) */
    float albedo[VLF_ALBEDO_TABLE]; /* the glossy lobe's albedo over cos(incidence) 0 .. 1 (1 at
                                     * normal incidence; mirrors 1 throughout) */
} vlf_face;

/* Fragment lists of one subfield: the faces each ray meets, front to back
 * along +w, on the radiance interface's (N S)^2 rays (cell c's list is
 * frag[cell_start[c] .. cell_start[c+1])). */
typedef struct vlf_psf {
    gi_vec3 u, v, n;
    uint32_t *cell_start; /* N*N + 1 */
    uint32_t *frag;       /* element index of each fragment */
    uint32_t frag_count;
    /* With vlf_settings.raster: the face order as triangles to draw, front
     * to back along +w (a double-sided face's two sides one after the
     * other, the receiver of the sweep along +w first). Entry bits 0-29:
     * a scene triangle (tri_p), or with bit 30 a triangle of rextra (a
     * piece of a split triangle, 12 words: three corners, VLF
     * coordinates as float bits, each with its face's index as the fourth
     * word); bit 31: the side of the face's twin. */
    uint32_t *rorder, rorder_count;
    uint32_t *rextra;
    uint32_t rextra_count;
} vlf_psf;

typedef struct vlf_stats {
    double sort_s, propagate_s;
    double flux_emitted, flux_shot, flux_received, flux_back,
        flux_escaped;       /* sums over iterations */
    uint64_t samples;       /* fragments visited in propagation (the paper's "ray intersections") */
    size_t bytes_propagate; /* storage while propagating */
    size_t bytes_render;    /* storage kept for rendering */
    size_t bytes_maps_render; /* of it the total maps (diffuse atlas and tiles) in the storage
                                 format */
    uint32_t diffuse_elements, nondiffuse_elements, tiles;
    uint64_t sort_pieces;     /* faces (triangles and their pieces) placed, over all subfields */
    uint64_t sort_splits;     /* pieces split to break a cycle of overlaps, over all subfields */
    uint64_t sort_bsp_cuts;   /* pieces cut by a BSP plane, over all subfields */
    uint64_t sort_unresolved; /* cycles left unbroken (split limit), over all subfields */
    uint64_t sort_tests;      /* pairs of faces tested by Newell's ordering */
    uint64_t sort_groups;     /* objects sorted on their own by the hierarchical shortcut, over all
                                 subfields */
    uint64_t
        sort_hier_fallbacks; /* subfields sorted again without it (a stand-in split by a cycle) */
} vlf_stats;

/* A point or spot light (world space): its first shot is by shadow rays. */
typedef struct vlf_punctual {
    int spot;
    gi_vec3 pos, dir;
    float I[3], range, cos_inner, cos_outer;
} vlf_punctual;

typedef struct vlf_field {
    vlf_settings prm;
    vlf_dirs dirs;
    gi_vec3 centre;
    float radius; /* world = centre + radius * vlf */
    uint32_t face_count, elem_count, nd_count;
    vlf_face *faces;
    uint32_t tri_count;  /* triangles sorted and rasterised: scene triangles x subdivide^2 */
    uint32_t tri_sub;    /* subdivide^2: triangle k is part of scene triangle k / tri_sub */
    uint32_t *tri_face;  /* face of each triangle */
    uint32_t *tri_group; /* scene object of each triangle (the hierarchical shortcut's groups) */
    gi_vec3 *tri_p;      /* 3 corners per triangle, VLF coordinates */
    /* The triangles the sort orders and the subfields rasterise: tri_* (the
     * pointers shared), or with vlf_settings.raster (subdivide = 1) each
     * face whose triangles tile a convex polygon drawn as that polygon's
     * fan (the paper's planar polygons, vlf_merge_faces) */
    uint32_t sort_count;
    gi_vec3 *sort_p;
    uint32_t *sort_face, *sort_group;
    uint32_t *elem_face;
    float *elem_area;
    float *elem_kd;  /* 3 per element: albedo (the material's, or the texture averaged over the
                        element) */
    vlf_psf *psf;    /* l (fixed directions) */
    vlf_rect *rects; /* nd_count * l */
    uint32_t nd_cells;
    uint8_t *nd_cover; /* nd_cells: the face covers this cell */
    /* radiance storage (RGB) */
    float *E_tot, *E_next, *L_cur; /* elem_count * 3: irradiance, unshot diffuse radiance */
    float *out_cur, *out_next, *out_tot, *in; /* nd_cells * 3 */
    const struct gi_envmap *env;
    struct vlf_punctual *punctual; /* point and spot lights, world space */
    uint32_t punctual_count;
    struct gi_rt *rt; /* the scene for their shadow rays (NULL without them) */
    float *elem_c;    /* 2 per element: centroid of its part on the face, chart texels */
    float *sun;       /* 2l x RGB: radiance the directional lights put into each signed direction's
                         interface */
    uint32_t sun_count; /* directional lights of the scene */
    vlf_stats st;
} vlf_field;

/* Builds the field for scene s at time t: faces, elements, directions and
 * the per-ray depth order of every subfield ("sort"). */
gi_result vlf_field_build(vlf_field *f, const gi_scene *s, float t, const vlf_settings *p,
                          gi_error *err);
/* Shoots unshot radiance for p->iterations iterations ("propagate").
 * `cancelled` (may be NULL) is polled between directions; returns
 * GI_ERR_CANCELLED then. */
gi_result vlf_field_propagate(vlf_field *f, int (*cancelled)(void *), void *user, gi_error *err);
void vlf_field_free(vlf_field *f);

/* The start of propagation shared by the CPU and the GPU paths: the maps
 * cleared, emission as the first unshot radiance, the point and spot
 * lights' first shot into the next maps, the counters zeroed. Fails only
 * out of memory. */
gi_result vlf_propagate_init(vlf_field *f, gi_error *err);
/* The radiance the interface of fixed direction i starts a sweep with
 * along sign * w_i: the sky's and the directional lights' (first
 * iteration only). */
void vlf_sweep_sky(const vlf_field *f, uint32_t i, int sign, int first_iteration, float sky[3]);
/* Weights g over the 2l signed directions of the light non-diffuse face fc
 * reflects into direction r (§3.4), and their normaliser (0: nothing is
 * reflected). */
double vlf_reflect_weights(const vlf_field *f, const vlf_face *fc, gi_vec3 r, float *g);
/* Albedo of the normalised Phong lobe of core brdf.h (ks (n + 2) / (2 pi)
 * cos^n alpha) per unit ks at incidence cos_t: 1 at normal incidence,
 * falling toward grazing where the lobe dips below the surface (numerical
 * quadrature); and face fc's table of it, interpolated. */
double vlf_phong_albedo(float n, float cos_t);
float vlf_phong_albedo_at(const vlf_face *fc, float cos_t);

/* Subfield frame of fixed direction i: cell coordinates (x, y) in [0, N)
 * and depth of VLF point q. */
void vlf_psf_project(const vlf_field *f, uint32_t i, gi_vec3 q, float *x, float *y, float *depth);
/* Element (chart texel, global index) of face fc holding VLF point q. */
uint32_t vlf_element_at(const vlf_field *f, const vlf_face *fc, gi_vec3 q);
/* World point to VLF coordinates. */
gi_vec3 vlf_to_vlf(const vlf_field *f, gi_vec3 world);

#endif
