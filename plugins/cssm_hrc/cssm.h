/* prefix cssm_ for cssm_hrc: every non-static function and type of the
 * plugin's files starts with cssm_, and its parameter table is cssm_params.
 *
 * CPU side of the cssm_hrc plugin (Ritschel, Grosch, Kautz, Seidel,
 * "Interactive Illumination with Coherent Surface Shadow Maps", GI 2008):
 *  - the illumination atlas (§3.2.3, Fig. 5): texels with world position,
 *    normal, area and material (atlas.c);
 *  - the coherent traversals of the atlas (§3.2.3, Fig. 6/7): greedy,
 *    zig-zag and spiral, charts visited nearest-first (atlas.c);
 *  - the coherent surface shadow maps (§3.2): a depth cube map at each
 *    texel in traversal order, compressed by the core's CSM codec, and the
 *    visibility query between a texel and any point (§3.2.2) (cssm.c);
 *  - the hierarchy (§4.2): median cut, bounding spheres, child and skip
 *    pointers; the stack-less refine-and-gather traversal with the energy
 *    oracle and a maximum cut size (§4.3, Fig. 10), pull, and the final
 *    gather per receiver point with a Phong bound (§4.4), jitter (§4.5) and
 *    clamping (hrc.c).
 * Moving rigid objects (§3.3) are handled in motion.c: the maps of this
 * file then see the static objects only (cssm_build_opts), and each moving
 * object has its own CSSM and CSM in its frame. */
#ifndef CSSM_H
#define CSSM_H

#include "gi/algo/csm_codec.h"
#include "gi/method.h"
#include "gi/passes.h"
#include "gi/raytrace.h"
#include "gi/vecmath.h"

struct cssm_receiver;
struct cssm_motion;
struct cssm_ctree;

/* ---------------------------------------------------------------- atlas */

typedef enum cssm_traversal { CSSM_GREEDY = 0, CSSM_ZIGZAG = 1, CSSM_SPIRAL = 2 } cssm_traversal;

#define CSSM_NO_XY 0xFFFFFFFFu

typedef struct cssm_texel {
    gi_vec3 p, n;      /* world position and (geometric) unit normal */
    float area;        /* world area this texel stands for */
    float albedo[3];   /* Lambert albedo: the material's factor x its texture at the texel centre */
    float emission[3]; /* emitted radiance (front face) */
    float ks[3], exponent; /* Phong lobe of the material (view-dependent lightmap mode) */
    int32_t chart;         /* chart index, -1 for a surface sample without parametrisation */
    uint32_t x, y;         /* atlas texel (CSSM_NO_XY for a surface sample) */
    uint32_t triangle;     /* scene triangle it lies on */
} cssm_texel;

typedef struct cssm_chart {
    uint32_t x0, y0, w, h; /* rectangle in the atlas */
    uint32_t object;
    gi_vec3 origin, u,
        v; /* world position of atlas corner (x0, y0) and one texel step along x and y */
    gi_vec3 normal;
} cssm_chart;

typedef struct cssm_atlas {
    uint32_t R;    /* the atlas is R x R texels */
    int32_t *grid; /* R * R: texel index, -1 where no chart covers it */
    cssm_texel *texels;
    uint32_t count;        /* texels (chart texels, then surface samples) */
    uint32_t chart_texels; /* texels inside charts */
    cssm_chart *charts;
    uint32_t chart_count;
    float h;              /* texel edge length in world units */
    float diameter;       /* scene bounding-box diagonal */
    double surface_area;  /* of every triangle */
    double chart_area;    /* of the triangles in charts */
    double covered_area;  /* chart texels x h^2: the share of chart_area the texel grid covers */
    int32_t *tri_chart;   /* per scene triangle: its chart, -1 for none */
    uint32_t back_texels; /* the last back_texels texels: back sides of double-sided materials */
} cssm_atlas;

/* Builds the atlas of the scene at time t (world space, every object):
 * triangles of one object lying in one plane form a planar chart (the box
 * scenes' walls and blocks) packed into the R x R atlas; triangles of no
 * chart large enough (curved meshes) get evenly distributed surface
 * samples of the same density (§3.2.3, last paragraph). Texel areas sum to
 * each chart's / object's area. The triangles of double-sided materials
 * get a second texel per front texel, normal reversed, no chart, after
 * the surface samples (atlas.c, atlas_back_sides). samples_only: the texel size the charts
 * would get, but surface samples everywhere (no parametrisation: the
 * paper's greedy case). GI_ERR_INVALID_ARGUMENT when the scene has no
 * area. */
gi_result cssm_atlas_build(const gi_scene *s, float t, uint32_t R, int samples_only,
                           cssm_atlas *out, gi_error *err);
void cssm_atlas_free(cssm_atlas *a);
/* Reads texel x's material from triangle tri (world corners p, x->p on
 * it): albedo factor x albedo texture at x->p (the mesh uvs interpolated,
 * gi_scene_albedo), emission, Phong lobe. */
void cssm_texel_material(const gi_scene *s, uint32_t tri, const gi_vec3 p[3], cssm_texel *x);

/* The chart of scene triangle tri for a point whose (eye-facing) normal is
 * n: tri_chart, or -1 when n faces away from the chart's normal (the back
 * side of a double-sided triangle, whose texels are surface samples). */
int32_t cssm_side_chart(const cssm_atlas *a, uint32_t tri, gi_vec3 n);

/* Continuous texel coordinates (texel centres at x + 1/2) of world point p
 * in chart c's rectangle. */
void cssm_chart_coords(const cssm_atlas *a, uint32_t chart, gi_vec3 p, float *u, float *v);
/* Bicubic (uniform cubic B-spline) interpolation of per-texel values
 * (3 per texel) at chart-local coordinates (u, v) over the 4 x 4 texels of
 * that chart around it, weights renormalised over the texels that exist;
 * 0 when none does. */
int cssm_chart_bicubic(const cssm_atlas *a, uint32_t chart, float u, float v, const float *values,
                       float out[3]);

/* The order in which the texels' cube maps are rendered and compressed:
 * order[k] = texel visited k-th (a permutation of 0 .. count-1). Greedy:
 * nearest unvisited texel in 3D from texel 0 on, over all texels. Zig-zag
 * and spiral: chart after chart, the next chart the one whose first texel
 * is nearest (3D) to the last texel visited; inside a chart the rows of
 * its rectangle alternately left to right and right to left (zig-zag) or
 * a left-hand walk along the border of the unvisited region, stepping back
 * along the path when stuck (spiral); surface samples follow, greedily.
 * Returns a malloc'd array or NULL on no memory. */
uint32_t *cssm_traverse(const cssm_atlas *a, cssm_traversal how);
/* How a traversal steps through the atlas (Table 2's explanation): the mean
 * 3D step between consecutive cube maps in texel sizes h, the steps longer
 * than 2 h (jumps: a chart change, a sample far off) and their share of the
 * path's length, the steps that leave a plane (normal or plane changes). */
typedef struct cssm_traversal_measure {
    double step_mean;
    uint32_t jumps;
    double jump_length_share;
    uint32_t plane_changes;
} cssm_traversal_measure;
void cssm_traversal_measures(const cssm_atlas *a, const uint32_t *order, cssm_traversal_measure *m);
const char *cssm_traversal_name(cssm_traversal how);

/* ----------------------------------------------------------------- CSSM */

typedef struct cssm_maps {
    uint32_t M, N;       /* cube faces M x M, N texels */
    gi_csm_data face[6]; /* one codec sequence per cube face, maps in traversal order */
    uint32_t *seq;       /* texel -> index in the sequence */
    gi_vec3 *eye;        /* texel -> cube map centre (position + eps normal) */
    float znear, zfar;
    uint64_t dont_care;   /* face texels in the negative half-space (stored as "any value") */
    uint64_t face_texels; /* 6 M^2 N */
    const struct cssm_motion
        *motion; /* moving-object mode (§3.3, motion.c), NULL: one static scene */
    int escape;  /* built with escape intervals (cssm_build_opts.escape, env_cssm.h) */
} cssm_maps;

/* What the cube maps see (§3.3: per object a CSSM). Zero: every object, in
 * world space (the static scene). */
typedef struct cssm_build_opts {
    uint32_t only_object; /* k + 1: object k alone */
    const unsigned char
        *skip_objects; /* per object, 1: not drawn (with only_object 0); NULL: none */
    int local;         /* 1: object-local geometry (with only_object) */
    const float
        *eye_from_world; /* maps the texels' eyes (world) into the maps' space; NULL: identity */
    const unsigned char
        *dont_care; /* per texel, 1: a map of "don't care" only (not queried, no segments) */
    int escape;     /* 1: a face texel that saw a surface enters the codec as [z1, min(z2, far)),
                       one that saw none as [far, inf): z_avg >= far tells the direction escapes
                       (env=cssm, env_cssm.h); 0: [z1, z2), none as (inf, inf) */
    const char *render_stage; /* stage timer of rendering and read-back; NULL: "cssm_render" */
    /* Which rays the maps answer, so which rule for sides they are drawn by
     * (gi/scene.h; gi_sides, gi/passes.h). 0: rays cast from a receiver
     * toward the map's eye, as the reference casts them (the visibility of
     * a sender texel or of a light point): GI_SIDES_ANY_THEN_RECEIVERS.
     * 1: rays cast from the eye (the escape test of env=cssm, which needs
     * it: `escape` without it is an error): GI_SIDES_EYE_THEN_BOTH. */
    int from_eye;
} cssm_build_opts;

/* Renders (the core's precomputation loop gi/algo/csm_precompute.h with its
 * depth renderer: world space, every object, radial depth, two surfaces)
 * the depth cube map of every texel in order `order`
 * (§3.2.1: near plane 1e-3 of the diameter, far plane the diameter,
 * texels whose cone lies wholly in the negative half-space of the texel's
 * normal "don't care") and streams them into six codecs. host may be NULL;
 * with a host: stage timers cssm_render and compress, progress,
 * cancellation. */
gi_result cssm_maps_build(const gi_gpu_scene *gs, const cssm_atlas *a, const uint32_t *order,
                          uint32_t M, const gi_host *host, cssm_maps *out, gi_error *err);
/* The same with what the maps see chosen by opts (NULL: as above). */
gi_result cssm_maps_build_ex(const gi_gpu_scene *gs, const cssm_atlas *a, const uint32_t *order,
                             uint32_t M, const cssm_build_opts *opts, const gi_host *host,
                             cssm_maps *out, gi_error *err);
void cssm_maps_free(cssm_maps *m);
/* What cssm_maps_build sets besides the compressed faces (sizes, seq, eye,
 * near and far planes): for data read back from the cache. */
gi_result cssm_maps_setup(const cssm_atlas *a, const uint32_t *order, uint32_t M, cssm_maps *out,
                          gi_error *err);
/* Compressed bytes over the six sequences, and the paper's uncompressed
 * 2 bytes per depth texel (Table 2). */
uint64_t cssm_maps_bytes(const cssm_maps *m);
uint64_t cssm_maps_bytes_uncompressed(const cssm_maps *m);
uint64_t cssm_maps_segments(const cssm_maps *m);

/* Visibility (§3.2.2, Fig. 4) between texel j and world point x: x is
 * projected into j's cube map; 1 lit, 0 occluded. bias: depth bias in
 * world units; pcf: the 2 x 2 texels around the projection, bilinearly
 * weighted (the generalised PCF of the CSM, over texels of one face). */
float cssm_visible(const cssm_maps *m, uint32_t j, gi_vec3 x, float bias, int pcf);

/* The visibility of texel j from receiver rc: cssm_visible toward rc->x,
 * or in moving-object mode the combination of §3.3 (motion.c). */
float cssm_visible_rc(const cssm_maps *m, uint32_t j, const struct cssm_receiver *rc, float bias,
                      int pcf);

/* ------------------------------------------------------------ hierarchy */

typedef struct cssm_node {
    gi_vec3 c;        /* bounding sphere centre */
    float r;          /* and radius */
    gi_vec3 centroid; /* area-weighted mean position */
    gi_vec3 n;        /* area-weighted mean normal, unit */
    float cos_cone;   /* cosine of the normal cone's half-angle (-1: everything) */
    float area;
    int32_t child; /* left child (-1 for a leaf); the right child is the left child's skip */
    int32_t skip;  /* next node in depth-first order past this subtree (-1: end) */
    uint32_t first, count; /* leaves [first, first + count) of cssm_tree.leaves */
    uint32_t rep;          /* representative texel (nearest the centroid) */
} cssm_node;

typedef struct cssm_tree {
    cssm_node *nodes; /* depth-first pre-order: the root is 0, a left child follows its parent */
    uint32_t count;
    uint32_t *leaves;    /* texel of leaf k (the median-cut order) */
    uint32_t *leaf_node; /* texel -> its leaf node */
} cssm_tree;

/* One node as the traversal reads it, from either layout: the float
 * cssm_node with its pulled radiance, or a packed 128-bit node decoded
 * (compact.c). I is the radiant intensity, radiance x area per channel
 * (what the paper's node stores), so a gather sends I cos_s cos_r / d^2. */
typedef struct cssm_node_view {
    gi_vec3 c;      /* bounding sphere centre */
    float r;        /* and radius */
    gi_vec3 p;      /* gather position (float: the centroid; packed: the one stored centre) */
    gi_vec3 n;      /* mean normal */
    float cos_cone; /* normal cone (-1: everything) */
    float area;
    float I[3]; /* radiant intensity */
    int32_t child, skip;
    uint32_t first, count; /* leaves below: leaves[first, first + count) */
    uint32_t rep;          /* texel whose CSSM gives the node's visibility */
} cssm_node_view;

/* Node i as the traversal reads it: the float node with its pulled
 * radiance node_L (intensity = radiance x area), or with ct not NULL the
 * packed node decoded (the GPU gather uploads these views). */
void cssm_node_fetch(const cssm_tree *t, const float *node_L, const struct cssm_ctree *ct,
                     int32_t i, cssm_node_view *v);

/* Median cut over the texel positions (§4.2): split at the median of the
 * longest axis of the box until one texel is left. With back-side texels
 * (double-sided materials) the root's children are the front texels and
 * the back texels, each median cut: a front and a back texel share a
 * position, so a median cut alone would keep them together down to the
 * leaves and every cluster of a double-sided surface would have a mean
 * normal of zero. */
gi_result cssm_tree_build(const cssm_atlas *a, cssm_tree *out, gi_error *err);
void cssm_tree_free(cssm_tree *t);
/* Pull (§4.1.1): per node the area-weighted mean of per-texel radiance
 * `texel_L` (3 floats a texel) into `node_L` (3 floats a node). */
void cssm_tree_pull(const cssm_tree *t, const cssm_atlas *a, const float *texel_L, float *node_L);

/* ------------------------------------------------ compact nodes (§4.2.1)
 * "For each node, all data is stored in 128 bits using a single 32-bit
 * RGBA integer texel. 24 bits are used for: Center position, average
 * normal and radiant intensity, 8 bits for: radius, normal cone angle and
 * area, and 16 bits for both pointers." The four words (compact.c):
 *   w[0]  centre: 8 bits per axis in the scene's box | radius: 8 bits, log
 *   w[1]  normal: octahedral 12 + 12 bits          | cone angle: 8 bits, linear in [0, pi]
 *   w[2]  intensity: 6-bit shared exponent + 3 x 6-bit mantissa | area: 8 bits, log
 *   w[3]  child: 16 bits | skip: 16 bits (0xFFFF: none)
 * One centre serves as the sphere's centre and as the gather position
 * without jitter (the float node gathers at its area-weighted centroid);
 * radius and cone are rounded up so that the
 * decoded sphere holds the true one and the decoded cone the true one
 * (the oracle's bounds stay upper bounds). Node index 0xFFFF is the null
 * pointer: 65 535 nodes at most (32 768 texels). */
#define CSSM_COMPACT_MAX_NODES 65535u

typedef struct cssm_pnode {
    uint32_t w[4];
} cssm_pnode;

typedef struct cssm_ctree {
    cssm_pnode *nodes;
    uint32_t count;
    float lo[3], step[3]; /* centre: lo + q step, q in 0 .. 255 */
    float rtab[256];      /* radius of each code (log between the smallest and largest node) */
    float atab[256];      /* area of each code (log) */
    float ctab[256];      /* cosine of the cone angle pi q / 255 */
    float iscale;   /* intensity scale of the light set in the nodes (exponent 60 is 1 x iscale) */
    uint32_t *side; /* 2 per node: first leaf, representative texel (visibility and jitter, not in
                       the 128 bits) */
    uint32_t *leaves; /* leaf rank -> texel (a copy of cssm_tree.leaves) */
} cssm_ctree;

/* GI_OK when the tree over `texels` texels (2 texels - 1 nodes) fits the
 * 16-bit pointers; otherwise GI_ERR_INVALID_ARGUMENT and the one-line
 * error in err. */
gi_result cssm_ctree_check(uint32_t texels, gi_error *err);
/* Sets up an empty packed tree of count nodes: the centre box [lo, hi],
 * the radius and area ranges of the log codes. GI_ERR_INVALID_ARGUMENT
 * (one line in err) when count exceeds CSSM_COMPACT_MAX_NODES. */
gi_result cssm_ctree_setup(cssm_ctree *ct, uint32_t count, const float lo[3], const float hi[3],
                           float r_lo, float r_hi, float a_lo, float a_hi, gi_error *err);
/* Packs the float tree (geometry and pointers; the intensity is set by
 * cssm_ctree_pull): the float node's bounding sphere, normal, cone and
 * area.
 * Refuses trees of more than CSSM_COMPACT_MAX_NODES nodes. */
gi_result cssm_ctree_build(const cssm_tree *t, const cssm_atlas *a, cssm_ctree *out, gi_error *err);
void cssm_ctree_free(cssm_ctree *ct);
/* Encodes node i's geometry, pointers and intensity from v (v->c, r, n,
 * cos_cone, area, I, child, skip; v->p is not stored: it is v->c), the
 * radius grown by the centre's rounding and the cone by the normal's. */
void cssm_ctree_encode(cssm_ctree *ct, uint32_t i, const cssm_node_view *v);
/* Re-encodes node i's intensity only. */
void cssm_ctree_set_intensity(cssm_ctree *ct, uint32_t i, const float I[3]);
/* Decodes node i (count of leaves from the pointers, first and rep from
 * the side table). */
void cssm_ctree_view(const cssm_ctree *ct, uint32_t i, cssm_node_view *v);
/* Pull on packed nodes (§4.1.1): a leaf gets radiance x area of its texel,
 * an inner node the sum of its two children as decoded, each re-encoded
 * (what a shader pass writing the node texture does). The intensity
 * scale is the largest channel of the sum over the texels. */
void cssm_ctree_pull(cssm_ctree *ct, const cssm_atlas *a, const float *texel_L);

/* A receiver of the refine-and-gather traversal: a texel (diffuse, self
 * skipped) or a G-buffer pixel (Lambert + normalised Phong toward wo). */
typedef struct cssm_receiver {
    gi_vec3 x, n;
    int32_t self;    /* receiver texel (skipped), -1 for a pixel */
    uint32_t proxy1; /* moving-object mode, a pixel: 1 + a texel on its triangle (0: none) */
    uint32_t
        moving; /* moving-object mode, a pixel: 1 + the mover it lies on, 0 on a static object */
    int glossy; /* use ks, exponent, wo */
    float kd[3], ks[3], exponent;
    gi_vec3 wo;
} cssm_receiver;

struct cssm_gather_stats;

/* The salt of the HRC bounces' jitter streams (cssm_gather_opts.atlas_jitter;
 * the GLSL twin in shaders/cssm_bounce.comp). */
#define CSSM_ATLAS_SALT 0xa71u

typedef struct cssm_gather_opts {
    float threshold;  /* refine while the tone-mapped bound exceeds it (§4.3) */
    uint32_t max_cut; /* maximum nodes in the cut */
    float exposure;   /* tone mapping: (L 2^exposure)^(1 / 2.2) */
    float clamp;      /* distances below it count as it (§5 "Quality") */
    float bias;       /* CSSM depth bias, world units */
    int pcf;
    uint32_t *rng;    /* non-NULL: jitter each gathered node inside its area (§4.5) */
    int rep_centroid; /* 1: a node's visibility from the texel nearest its centroid, jitter over
                       * uniform leaves (rep=centroid); 0: the leaf picked by intensity
                       * (lightcuts' representative, hrc.c pick_leaf) */
    int no_emission; /* cssm_solve: R_1 = direct only, the emitting texels not gathered (their light
                      * comes from the direct light of direct=csm, §4.7) */
    /* set (vis=trace): every gather's visibility is an exact ray query from the
     * receiver to the point it gathers from (the VPL, jittered or not) instead of
     * the CSSM look-up: the paper's Fig. 14 comparison; the ray ends `bias`
     * short of that point */
    const gi_rt *trace;
    /* cssm_solve_ex with atlas_jitter: the HRC bounces' gathers jittered as
     * the final gather's (§4.5, bounces_every=frame): texel i's generator
     * of gather pass k (1: the direct gather, b: bounce b) is
     * gi_rng_init(i, atlas_frame, atlas_seed ^ (CSSM_ATLAS_SALT + k)), so
     * that each frame's bounces draw anew and the frames' average converges */
    int atlas_jitter;
    uint32_t atlas_frame, atlas_seed;
    /* set: cssm_solve_ex's per-texel gathers (§4.1.1) run there instead of
     * the C loop (bounces_on=gpu, gpu_gather.c): every texel of the atlas
     * gathered from node_L (or the packed nodes ct) into out[3 N], the
     * counts added to st; a failure sets err */
    gi_result (*atlas_gather)(void *ctx, const float *node_L, const struct cssm_ctree *ct,
                              uint32_t pass, float *out, struct cssm_gather_stats *st,
                              gi_error *err);
    void *atlas_ctx;
} cssm_gather_opts;

typedef struct cssm_gather_stats {
    uint64_t nodes; /* cut sizes summed */
    uint64_t receivers;
    uint64_t clamped; /* gathers whose distance was clamped */
} cssm_gather_stats;

/* The stack-less traversal of Fig. 10 for one receiver: returns in out[3]
 * the reflected radiance f * sum over the cut of L_S A_S cos_s cos_r / d^2
 * V (for a texel receiver f = kd / pi). node_L: pulled radiance per node.
 * maps may be NULL (everything visible). */
void cssm_gather(const cssm_tree *t, const cssm_atlas *a, const cssm_maps *maps,
                 const float *node_L, const cssm_receiver *rc, const cssm_gather_opts *o,
                 float out[3], cssm_gather_stats *st);
/* The same traversal over packed nodes (nodes=compact), each decoded as
 * it is read, intensity as pulled into ct. */
void cssm_cgather(const cssm_ctree *ct, const cssm_atlas *a, const cssm_maps *maps,
                  const cssm_receiver *rc, const cssm_gather_opts *o, float out[3],
                  cssm_gather_stats *st);
/* §4.3's refinement test without a powf per node: the largest value y with
 * (y)^(1/2.2) <= thr, so that "refine when (b·exposure)^(1/2.2) > thr" is
 * exactly "refine when b·exposure > limit". */
float cssm_refine_limit(float thr);
/* Upper bound of what node S sends to the receiver (the oracle's L_max),
 * luminance. */
float cssm_bound(const cssm_node *S, const float L[3], const cssm_receiver *rc);

/* §4.6 "Indirect Light" alternative (instant radiosity with the atlas as a
 * pdf): a table to draw texels with probability proportional to
 * lum(value) x area; cdf has count + 1 entries. Returns the total (0: no
 * texel sends anything). */
double cssm_pdf_build(const cssm_atlas *a, const float *texel_values, double *cdf);
/* S texels drawn from that table, each at a random point of its square
 * (rng), visibility through its CSSM: the Monte Carlo estimate of the same
 * sum as cssm_gather (f L_j A_j cos_s cos_r / d^2 V, distances clamped). */
void cssm_gather_mc(const cssm_atlas *a, const cssm_maps *maps, const float *texel_values,
                    const double *cdf, uint32_t S, const cssm_receiver *rc,
                    const cssm_gather_opts *o, float out[3]);

/* The receiver position of a surface point: lifted along its normal as
 * the cube maps' eyes are (2 near planes). */
gi_vec3 cssm_receiver_point(const cssm_maps *maps, const cssm_atlas *a, gi_vec3 p, gi_vec3 n);

/* GPU HRC of §4.1.1 on the atlas (Fig. 8): texel_L (3 per texel) gets
 * emission + R_1 + ... + R_n with
 *   R_1 = kd/pi gather(pull(emission)) + direct (3 per texel, may be NULL:
 *         light from sources that are not atlas texels; with
 *         o->no_emission R_1 = direct alone),
 *   R_k = kd/pi gather(pull(R_{k-1})),  k = 2 .. n,
 * and node_L (3 per node) its pull. Stage timers direct, pull, bounce when
 * host is not NULL. */
gi_result cssm_solve(const cssm_tree *t, const cssm_atlas *a, const cssm_maps *maps,
                     const cssm_gather_opts *o, uint32_t bounces, const float *direct,
                     const gi_host *host, float *texel_L, float *node_L, cssm_gather_stats *st,
                     gi_error *err);
/* The same with packed nodes: ct not NULL, every pull goes into ct (re-encoded)
 * and every gather reads ct; ct ends holding the pull of texel_L (node_L
 * is filled too). */
gi_result cssm_solve_ex(const cssm_tree *t, cssm_ctree *ct, const cssm_atlas *a,
                        const cssm_maps *maps, const cssm_gather_opts *o, uint32_t bounces,
                        const float *direct, const gi_host *host, float *texel_L, float *node_L,
                        cssm_gather_stats *st, gi_error *err);

#endif
