/* The implicit_vis method's CPU side (Dong, Kautz, Theobalt, Seidel, PG 2007):
 * surface elements, the geometric hierarchy, the cube-map bins, the
 * hierarchical link structure with implicit visibility and the gathering
 * of light along its links. No GL here, so that the tests can drive every
 * stage on its own. Names: prefix iv_ for implicit_vis.
 *
 * Files: bins.c (Sec. 4.2.2 "Discretization"), elements.c (Sec. 4.1, 5.1),
 * hierarchy.c (Sec. 4.1, 4.2.1), links.c and links_threads.c (Sec.
 * 4.2.2-4.2.4), illuminate.c (Sec. 4.3, 4.4); iv_internal.h holds what
 * they share among themselves.
 *
 * Use (Algorithm 1):
 *     iv_hier *h = iv_hier_create(scene, edge, IV_REMESH_ISOTROPIC, &err);
 *                                                 // CreateSurfels + CreateGeometricHierarchy
 *     iv_links *l = iv_links_create(h, N);
 *   per frame:
 *     iv_hier_update(h, scene, t);                // UpdateElements (Sec. 4.2.1)
 *     iv_links_build(l, h, subdiv, brute, splat); // CreateHierarchicalLinks (Sec. 4.2.2)
 *     iv_links_refine_push(l, h);                 // Refine + PushDownLinks (Sec. 4.2.3-4.2.4)
 *     iv_illuminate(l, h, &lights, bounces, E);   // ComputeIlluminate + PullupEnergy (Sec. 4.3)
 */
#ifndef IV_H
#define IV_H

#include "gi/envmap.h"
#include "gi/scene.h"

#include <math.h>
#include <stdint.h>

struct gi_host;

/* ---- cube-map bins (Sec. 4.2.2 "Discretization") ---- */

/* Bin of direction d (any length > 0) in a 6 x n x n world-aligned cube map:
 * face * n * n + row * n + column. Faces +X -X +Y -Y +Z -Z. */
uint32_t iv_bin_of(gi_vec3 d, uint32_t n);

/* Column or row of a face coordinate u in [-1, 1]: floor((u + 1) n / 2),
 * clamped. The value is >= 0 (or NaN, clamped to 0 as before), where a
 * truncating conversion is the floor, without a call to floorf. */
static inline int iv_bin_cell(float u, uint32_t n)
{
    float x = (u + 1.0f) * 0.5f * (float)n;
    int c = x > 0.0f ? (int)x : 0;
    return c >= (int)n ? (int)n - 1 : c;
}

/* The axis of a's largest |component| (the first on a tie): the cube face
 * axis of the bins. */
static inline int iv_major_axis(const float a[3])
{
    int ax = 0;
    if (fabsf(a[1]) > fabsf(a[ax]))
        ax = 1;
    if (fabsf(a[2]) > fabsf(a[ax]))
        ax = 2;
    return ax;
}

/* iv_bin_of, inlined where link creation asks it millions of times per
 * frame; and the bins of d and -d at once (*neg: the bin of -d), which
 * share the axis and the divisions (-a / m is -(a / m) to the bit). */
static inline uint32_t iv_bin_pair(gi_vec3 d, uint32_t n, uint32_t *neg)
{
    float a[3] = {d.x, d.y, d.z};
    int ax = iv_major_axis(a);
    float m = fabsf(a[ax]);
    if (!(m > 0.0f)) {
        *neg = 0;
        return 0;
    }
    uint32_t face = 2u * (uint32_t)ax + (a[ax] < 0.0f ? 1u : 0u);
    float u = a[(ax + 1) % 3] / m, v = a[(ax + 2) % 3] / m;
    *neg = (face ^ 1u) * n * n + (uint32_t)iv_bin_cell(-v, n) * n + (uint32_t)iv_bin_cell(-u, n);
    return face * n * n + (uint32_t)iv_bin_cell(v, n) * n + (uint32_t)iv_bin_cell(u, n);
}

static inline uint32_t iv_bin_fast(gi_vec3 d, uint32_t n)
{
    uint32_t neg;
    return iv_bin_pair(d, n, &neg);
}
/* Unit direction through the centre of bin b. */
gi_vec3 iv_bin_centre(uint32_t b, uint32_t n);
/* Solid angle of bin b (exact for a cube-map texel). */
float iv_bin_solid_angle(uint32_t b, uint32_t n);

/* ---- surface elements and the geometric hierarchy (Sec. 4.1) ---- */

/* Re-meshing limits: subdivisions of one triangle (the display grid, and
 * the re-meshing by subdivision), surface points in all. */
#define IV_MAX_K 64u
#define IV_MAX_SAMPLES (8u * 1024u * 1024u)
/* Rounds of split, collapse, flip and smoothing of the isotropic re-meshing. */
#define IV_REMESH_ITERATIONS 3u

/* How the model is re-meshed to the target edge length (Sec. 5.1). */
enum {
    IV_REMESH_ISOTROPIC = 0, /* CGAL's isotropic re-meshing (gi/algo/remesh.h), each new vertex on
                                an original triangle */
    IV_REMESH_GRID = 1,      /* each triangle subdivided into a k x k grid of its own */
};

/* Grid point (i, j) of a triangle subdivided k times (i + j <= k; the
 * point's barycentric weights of corners 1 and 2 are i / k and j / k):
 * rows of constant j, k + 1 - j points each. */
static inline uint32_t iv_grid_index(uint32_t k, uint32_t i, uint32_t j)
{
    return j * (k + 1) - j * (j - 1) / 2 + i;
}

typedef struct iv_hier {
    /* Surface points (Sec. 4.1 and 5.1): the corners of every triangle;
     * with re-meshing the vertices of the re-meshed surface, each embedded
     * in an original triangle (triangle, barycentric weights), so that
     * rigid motion and morph targets move it and albedo, texture and
     * normals carry over. */
    uint32_t sample_count;
    uint32_t *samp_tri;  /* original triangle of each point */
    float *samp_b;       /* 2 per point: barycentric weights of corners 1 and 2 */
    uint32_t *samp_elem; /* point -> element */
    float *rest;         /* 3 per point: object-local rest position */
    /* The surface the points span: 3 points per triangle (without
     * re-meshing the original triangles; with the grid the sub-triangles;
     * isotropic: CGAL's triangles). A disc's area is a third of its
     * triangles', every frame. */
    uint32_t surf_count;
    uint32_t *surf_tri;
    /* The display's look-up: per original triangle a k x k grid (k = 1:
     * its corners), each grid point a blend of three elements. */
    uint32_t *tri_k;    /* per triangle: subdivisions of its display grid */
    uint32_t *tri_grid; /* per triangle + 1: its first grid point */
    uint32_t disp_count;
    uint32_t *disp_elem; /* 3 per grid point: elements */
    float *disp_w;       /* 3 per grid point: their weights */
    /* Elements: one oriented disc per distinct point (points equal in
     * position and normal merged). */
    uint32_t elem_count;
    uint32_t *elem_rep;           /* element -> one of its points */
    float *elem_albedo;           /* 3 per element: mean albedo of its points */
    float *elem_emit;             /* 3 per element: emitted radiance */
    uint8_t *elem_two_sided_emit; /* material doubleSided: emits, receives and reflects on both
                                     sides (else on the normal's side only) */
    uint32_t segment_count;       /* connected parts of each object: the roots */
    /* Nodes in breadth-first order: the roots first, children contiguous
     * and after their parent, so bottom-up is a backward sweep. */
    uint32_t node_count;
    uint32_t root_count;
    uint32_t *first_child;
    uint8_t *child_count; /* 0 for a leaf */
    int32_t *parent;      /* -1 for a root */
    int32_t *node_elem;   /* element of a leaf, -1 otherwise */
    uint32_t *elem_node;  /* element -> its leaf */
    uint32_t depth;       /* levels of the deepest tree */
    /* Per frame (iv_hier_update), world space. */
    float *pos;  /* 3 per node: area-weighted mean of the children */
    float *nrm;  /* 3 per node: area-weighted mean normal (unit for a leaf; shorter where children
                    disagree) */
    float *area; /* per node: sum of the children */
    float *spos; /* scratch: 3 per surface point at t */
    gi_vertex *verts;   /* scratch: an object's vertices at t */
    float *wpos, *wnrm; /* scratch: the model's vertices at t, world space */
} iv_hier;

/* target_edge > 0: the model re-meshed to that edge length (world units
 * at t = 0) by `remesher` (IV_REMESH_*); with the grid each triangle is
 * subdivided k times, k its longest edge over target_edge rounded up (at
 * most IV_MAX_K). 0: the model as it is. */
iv_hier *iv_hier_create(const gi_scene *s, float target_edge, int remesher, gi_error *err);
void iv_hier_free(iv_hier *h);
/* Positions, normals and areas of the elements at time t (rigid motion and
 * morph targets), then every node from its children (Sec. 4.2.1). */
void iv_hier_update(iv_hier *h, const gi_scene *s, float t);
/* Edge lengths of the surface the elements span (surf_tri), rest pose,
 * world units at t = 0: mean and coefficient of variation (standard
 * deviation / mean), each edge counted once per triangle. */
void iv_hier_edge_stats(const iv_hier *h, const gi_scene *s, double *mean, double *cv);
static inline int iv_is_leaf(const iv_hier *h, uint32_t node)
{
    return h->child_count[node] == 0;
}

/* Solid angle of a disc of (projected) area a seen on its axis from
 * distance sqrt(r2): 2 pi (1 - 1 / sqrt(1 + a / (pi r2))), which is
 * a / r2 for a small disc and stays below a hemisphere for a near one.
 * Written to keep its precision for small a. */
static inline float iv_disc_solid_angle(double a, double r2)
{
    if (!(r2 > 0.0))
        return 0.0f;
    double x = a / (3.14159265358979323846 * r2), q = sqrt(1.0 + x);
    return (float)(2.0 * 3.14159265358979323846 * x / (q * (q + 1.0)));
}

/* ---- the hierarchical link structure (Sec. 4.2) ---- */

/* How a link weighs in its bin (Sec. 3, Eq. 4 and 5; README "Weights"). */
enum {
    IV_WEIGHT_EQ5 = 0,     /* Eq. 5 as printed: the linked node's own solid angle, A cos / r^2 */
    IV_WEIGHT_BIN = 1,     /* the nearest node covers its whole bin (the bin's solid angle) */
    IV_WEIGHT_SURFACE = 2, /* Eq. 4 over the nearest surface: the solid angles of every node of
                              the nearest node's segment that falls in the bin, summed */
};

/* One bin of a node: its shortest link, the node at the other end (-1:
 * empty) and the link's length, side by side so that writing a link
 * touches one cache line (README "One link stored once"). */
typedef struct iv_cell {
    float dist;
    int32_t other;
} iv_cell;

typedef struct iv_links {
    uint32_t n;    /* bins per cube side (the paper's N) */
    uint32_t bins; /* 6 n n */
    uint32_t nodes;
    iv_cell *cell;    /* nodes x bins: the bin's link (README "One link stored once") */
    uint32_t threads; /* > 1: links created on this many threads, the same links to the bit (README
                         "Multi-threaded link creation"); 0 or 1: on one */
    int bilinear;   /* links written into the four bins around their direction (README "Deviations")
                     */
    float coverage; /* > 0: a bin whose links' solid angles sum to less than this share of it is lit
                       through that part only (README "Deviations"); 0: Eq. 5, the nearest covers
                       all */
    int weight;     /* IV_WEIGHT_*: how a link weighs in its bin */
    float *cover;   /* nodes x bins, only where read (iv_links_need_cover), else NULL: solid angle
                       of every node linked in the bin (Eq. 4's sum; with IV_WEIGHT_SURFACE only
                       the nodes of the nearest node's segment); after refinement summed down each
                       leaf's path */
    uint32_t *root; /* per node: the root of its tree (its segment) */
    uint8_t *one_sided; /* per node: every disc below it is single-sided (seen from behind it is
                           not there: the one rule for sides) */
    float *bin_dir;     /* 3 per bin: centre direction */
    float *bin_omega;   /* per bin: solid angle */
    /* After iv_links_refine_push: the receiving links of each leaf
     * (unidirectional), and the light links among them (Sec. 4.3.1 "Speedup"). */
    uint32_t *leaf_off;  /* elements + 1 */
    uint32_t *leaf_bin;  /* bin of each receiving link */
    uint32_t *leaf_src;  /* node at its other end */
    uint32_t *light_off; /* elements + 1 */
    uint32_t *light_bin, *light_src;
    size_t leaf_cap, light_cap;
    /* Counters of the last build. */
    uint64_t tries;     /* node pairs considered */
    uint64_t created;   /* bin entries written (a shorter link replacing one counts) */
    uint64_t receiving; /* leaf links after refinement and push-down */
    /* Asked for a cancel every 64 k node pairs of link creation (issue 32);
     * NULL: never. `stopped`: the last build stopped on it, its links are
     * incomplete. */
    const struct gi_host *host;
    int stopped;
    int oom; /* the last build found no memory for the coverage: no links */
    /* Scratch of the threaded build (links_threads.c), kept from frame to
     * frame so that listing the pairs writes no fresh pages: per thread
     * the pairs it listed, 4 words each. */
    uint32_t **pair_buf;
    size_t *pair_cap;
    uint32_t pair_bufs;
    /* keep_pairs (README "Pairs of still segments"): the pairs Sec. 4.2.2
     * linked between two segments of which neither moved since the last
     * build are taken from it, not tested anew (the same pairs: a pair's
     * subdivision depends on its two trees only). kept_tries: of `tries`,
     * those taken so. */
    int keep_pairs;
    struct iv_kept *kept;
    uint64_t kept_tries;
} iv_links;

iv_links *iv_links_create(const iv_hier *h, uint32_t n);
void iv_links_free(iv_links *l);
/* Whether the link modes read the bins' coverage (coverage > 0 or
 * IV_WEIGHT_SURFACE; iv_link_share): iv_links_build keeps l->cover only
 * then, and under Eq. 5 writes a link into its cell alone. */
int iv_links_need_cover(const iv_links *l);
/* Sec. 4.2.2: links from the top-level pairs down, a node subdivided while
 * its solid angle seen from the other exceeds `subdiv` times the bin's;
 * each bin keeps its shortest link. brute != 0: every leaf against every
 * leaf instead (the non-hierarchical version, Sec. 3.1). splat != 0: a
 * leaf disc that covers several bins of the other end is written into all
 * of them (README "Deviations"), else into the bin of its centre only. */
void iv_links_build(iv_links *l, const iv_hier *h, float subdiv, int brute, int splat);
/* Sec. 4.2.3 and 4.2.4 in one breadth-first pass: each node's bin keeps
 * the shorter of its own link and its parent's (a parent's link moves to
 * the children that hold no shorter one), so that a leaf ends with the
 * shortest link found on its path to the root; then the leaves' links are
 * listed as receiving links, and those from emitting nodes as light links. */
void iv_links_refine_push(iv_links *l, const iv_hier *h);
/* The receiving links of iv_links_refine_push flattened for the GPU
 * (Sec. 4.3.1): 4 words per link, bin, node at the other end, the share of
 * the bin it covers (float bits; 1 under Eq. 5) and its length (float
 * bits); first every receiving link (l->receiving of them, each leaf's in
 * bin order), then the light links. off: 2 per element + 1, its first
 * receiving link and its first light link (counted from the light links'
 * start). links holds 4 (receiving + light links) words, off 2 (elements + 1).
 * Packed on l->threads threads (the same words). */
void iv_links_pack(const iv_links *l, const iv_hier *h, uint32_t *links, uint32_t *off);

/* ---- illumination (Sec. 4.3, 4.4) ---- */

/* The weight of leaf x's link in bin b as a multiple of the bin's solid
 * angle (IV_WEIGHT_*, or with coverage > 0 the share its links cover):
 * the link's Eq. 5 weight is this times the bin's cosine-weighted solid
 * angle. 0 for an empty bin. */
float iv_link_share(const iv_links *l, const iv_hier *h, uint32_t x, uint32_t b);
/* The share of bin b of leaf x through which the environment is seen
 * (Sec. 4.4): 1 for an empty bin; for a linked one 0 under Eq. 5 and the
 * bin rule ("any empty bin can see the lighting environment"), else what
 * its share leaves open. */
float iv_env_open(const iv_links *l, const iv_hier *h, uint32_t x, uint32_t b);
/* Whether a linked bin passes the environment through what its share
 * leaves open (coverage > 0 or IV_WEIGHT_SURFACE); the GPU's u_env_share. */
int iv_env_partial(const iv_links *l);

typedef struct iv_lights {
    const gi_scene *scene;
    float t;              /* punctual lights placed at this time */
    const gi_envmap *env; /* NULL: black */
    /* NULL: the paper's direct light along the links. Else 6 per element,
     * the direct irradiance on both sides as iv_illuminate's out (traced,
     * README "Traced direct light"): it replaces the first gather, and
     * e_out then holds the indirect bounces only. */
    const float *direct;
} iv_lights;

/* Gathers the direct light (light links, punctual lights through their bin,
 * the environment through empty bins; or lights->direct) and `bounces` indirect bounces at the
 * leaves with Eq. 5 (each link weighted by iv_link_share), pulling the
 * reflected radiance up after each gather. Out: per element the irradiance
 * on both sides of its disc, e_out[6 e + 0..2] on the normal's side,
 * [6 e + 3..5] on the other (0 for a single-sided disc: lit on its front
 * only). */
void iv_illuminate(const iv_links *l, iv_hier *h, const iv_lights *lights, uint32_t bounces,
                   float *e_out);

#endif
