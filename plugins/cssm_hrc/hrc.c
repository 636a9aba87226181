/* The hierarchy of cssm_hrc (§4.2) and the refine-and-gather traversal of
 * §4.3 / §4.4 (Fig. 10): median cut, bounding spheres and normal cones,
 * child and skip pointers; the energy oracle with a maximum cut size; the
 * gather with form factor x CSSM visibility; pull. */
#include "cssm.h"

#include "gi/rng.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct build_ctx {
    const cssm_atlas *a;
    cssm_tree *t;
    int axis;
} build_ctx;

static const cssm_atlas *sort_atlas;
static int sort_axis;

static float axis_of(gi_vec3 p, int k)
{
    return k == 0 ? p.x : k == 1 ? p.y : p.z;
}

static int cmp_axis(const void *x, const void *y)
{
    uint32_t i = *(const uint32_t *)x, j = *(const uint32_t *)y;
    float a = axis_of(sort_atlas->texels[i].p, sort_axis),
          b = axis_of(sort_atlas->texels[j].p, sort_axis);
    if (a != b)
        return a < b ? -1 : 1;
    return i < j ? -1 : (i > j);
}

/* A node's bounds over its leaves [first, first + count): bounding sphere
 * (grown by each texel's extent), area-weighted centroid and normal, normal
 * cone, area, representative texel; lo / hi get the box. */
static void node_fill(const cssm_atlas *a, const cssm_tree *t, cssm_node *nd, float lo[3],
                      float hi[3])
{
    const uint32_t first = nd->first, count = nd->count;
    for (int j = 0; j < 3; j++)
        lo[j] = FLT_MAX, hi[j] = -FLT_MAX;
    gi_vec3 cen = gi_v3(0, 0, 0), nsum = gi_v3(0, 0, 0);
    double area = 0.0;
    for (uint32_t k = first; k < first + count; k++) {
        const cssm_texel *x = &a->texels[t->leaves[k]];
        float q[3] = {x->p.x, x->p.y, x->p.z};
        for (int j = 0; j < 3; j++)
            lo[j] = fminf(lo[j], q[j]), hi[j] = fmaxf(hi[j], q[j]);
        cen = gi_v3_add(cen, gi_v3_scale(x->p, x->area));
        nsum = gi_v3_add(nsum, gi_v3_scale(x->n, x->area));
        area += x->area;
    }
    nd->area = (float)area;
    nd->centroid =
        area > 0.0 ? gi_v3_scale(cen, (float)(1.0 / area)) : a->texels[t->leaves[first]].p;
    float nl = gi_v3_length(nsum);
    nd->n = nl > 1e-12f ? gi_v3_scale(nsum, 1.0f / nl) : gi_v3(0, 1, 0);
    nd->c = gi_v3(0.5f * (lo[0] + hi[0]), 0.5f * (lo[1] + hi[1]), 0.5f * (lo[2] + hi[2]));
    float r = 0.0f, cmin = 1.0f, best = FLT_MAX;
    for (uint32_t k = first; k < first + count; k++) {
        const cssm_texel *x = &a->texels[t->leaves[k]];
        /* a texel is a small square: its extent counts toward the sphere */
        r = fmaxf(r, gi_v3_length(gi_v3_sub(x->p, nd->c)) + 0.75f * sqrtf(x->area));
        cmin = fminf(cmin, gi_v3_dot(x->n, nd->n));
        float d = gi_v3_length(gi_v3_sub(x->p, nd->centroid));
        if (d < best)
            best = d, nd->rep = t->leaves[k];
    }
    nd->r = r;
    nd->cos_cone = nl > 1e-12f ? cmin : -1.0f;
}

/* Builds the subtree over leaves[first, first + count) at node index *next;
 * returns its index. split: the size of the left child (0: the median cut
 * decides). */
static int32_t build(const cssm_atlas *a, cssm_tree *t, uint32_t first, uint32_t count,
                     uint32_t split, uint32_t *next)
{
    int32_t me = (int32_t)(*next)++;
    cssm_node *nd = &t->nodes[me];
    memset(nd, 0, sizeof *nd);
    nd->first = first;
    nd->count = count;
    float lo[3], hi[3];
    node_fill(a, t, nd, lo, hi);
    if (count == 1) {
        nd->child = -1;
        t->leaf_node[t->leaves[first]] = (uint32_t)me;
        return me;
    }
    uint32_t half = split;
    if (!half) {
        int axis = 0;
        for (int j = 1; j < 3; j++)
            if (hi[j] - lo[j] > hi[axis] - lo[axis])
                axis = j;
        sort_atlas = a;
        sort_axis = axis;
        qsort(t->leaves + first, count, sizeof *t->leaves, cmp_axis);
        half = count / 2;
    }
    int32_t left = build(a, t, first, half, 0, next);
    int32_t right = build(a, t, first + half, count - half, 0, next);
    t->nodes[me].child = left;
    t->nodes[left].skip = right;
    (void)right;
    return me;
}

/* Skip pointers: a left child's skip is its right sibling (set in build);
 * a right child's (and the root's) skip is its parent's skip. */
static void fix_skips(cssm_tree *t, int32_t node, int32_t skip)
{
    cssm_node *nd = &t->nodes[node];
    if (nd->child < 0) {
        nd->skip = skip;
        return;
    }
    int32_t left = nd->child, right = t->nodes[left].skip;
    nd->skip = skip;
    fix_skips(t, left, right);
    fix_skips(t, right, skip);
}

gi_result cssm_tree_build(const cssm_atlas *a, cssm_tree *out, gi_error *err)
{
    memset(out, 0, sizeof *out);
    uint32_t n = a->count;
    out->nodes = calloc(2 * (size_t)n, sizeof *out->nodes);
    out->leaves = malloc(n * sizeof *out->leaves);
    out->leaf_node = malloc(n * sizeof *out->leaf_node);
    if (!n || !out->nodes || !out->leaves || !out->leaf_node) {
        cssm_tree_free(out);
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "cssm_hrc: out of memory for the hierarchy");
    }
    for (uint32_t i = 0; i < n; i++)
        out->leaves[i] = i;
    uint32_t next = 0;
    /* the back sides (the last back_texels texels) in a subtree of their own */
    uint32_t front = a->back_texels < n ? n - a->back_texels : 0;
    build(a, out, 0, n, a->back_texels ? front : 0, &next);
    out->count = next;
    fix_skips(out, 0, -1);
    return GI_OK;
}

void cssm_tree_free(cssm_tree *t)
{
    if (!t)
        return;
    free(t->nodes);
    free(t->leaves);
    free(t->leaf_node);
    memset(t, 0, sizeof *t);
}

void cssm_tree_pull(const cssm_tree *t, const cssm_atlas *a, const float *texel_L, float *node_L)
{
    /* children follow their parent in pre-order: walk backwards */
    for (int32_t i = (int32_t)t->count - 1; i >= 0; i--) {
        const cssm_node *nd = &t->nodes[i];
        float *L = &node_L[3 * i];
        if (nd->child < 0) {
            memcpy(L, &texel_L[3 * t->leaves[nd->first]], 3 * sizeof *L);
            continue;
        }
        int32_t l = nd->child, r = t->nodes[l].skip;
        float al = t->nodes[l].area, ar = t->nodes[r].area, s = al + ar;
        for (int k = 0; k < 3; k++)
            L[k] = s > 0.0f ? (al * node_L[3 * l + k] + ar * node_L[3 * r + k]) / s : 0.0f;
    }
    (void)a;
}

/* Largest cosine between unit u and any direction toward a sphere seen at
 * unit direction w and half-angle with sine sin_h (cos of max(0, angle - h)). */
static float cos_bound(gi_vec3 u, gi_vec3 w, float sin_h)
{
    float c = gi_v3_dot(u, w);
    if (sin_h >= 1.0f)
        return 1.0f;
    float cos_h = sqrtf(1.0f - sin_h * sin_h);
    float s = sqrtf(fmaxf(0.0f, 1.0f - c * c));
    /* cos(a - h) = cos a cos h + sin a sin h, capped at 1 when a <= h */
    if (c >= cos_h)
        return 1.0f;
    return fmaxf(0.0f, c * cos_h + s * sin_h);
}

void cssm_node_fetch(const cssm_tree *t, const float *node_L, const cssm_ctree *ct, int32_t i,
                     cssm_node_view *v)
{
    if (ct) {
        cssm_ctree_view(ct, (uint32_t)i, v);
        return;
    }
    const cssm_node *S = &t->nodes[i];
    const float *L = &node_L[3 * i];
    v->c = S->c;
    v->r = S->r;
    v->p = S->centroid;
    v->n = S->n;
    v->cos_cone = S->cos_cone;
    v->area = S->area;
    for (int k = 0; k < 3; k++)
        v->I[k] = L[k] * S->area;
    v->child = S->child;
    v->skip = S->skip;
    v->first = S->first;
    v->count = S->count;
    v->rep = S->rep;
}

/* The oracle's upper bound (luminance) of what node S sends to rc. */
static float bound_view(const cssm_node_view *S, const cssm_receiver *rc)
{
    gi_vec3 w = gi_v3_sub(S->c, rc->x);
    float d = gi_v3_length(w);
    if (!(d > S->r))
        return FLT_MAX; /* the receiver lies inside the sphere: no bound */
    w = gi_v3_scale(w, 1.0f / d);
    float sin_h = S->r / d, dmin = d - S->r;
    float cr = cos_bound(rc->n, w, sin_h);
    /* sender: the normals within the cone around S->n, toward -w */
    float cs = 1.0f;
    if (S->cos_cone > -1.0f) {
        float cc = fmaxf(-1.0f, fminf(1.0f, S->cos_cone));
        float sin_c = sqrtf(fmaxf(0.0f, 1.0f - cc * cc));
        /* widen the cone by the sphere's half-angle */
        float sh = sin_h, chh = sqrtf(fmaxf(0.0f, 1.0f - sh * sh));
        float cw = cc * chh - sin_c * sh, sw = sin_c * chh + cc * sh; /* cos/sin of (cone + h) */
        float c = -gi_v3_dot(S->n, w), s = sqrtf(fmaxf(0.0f, 1.0f - c * c));
        cs = c >= cw ? 1.0f : fmaxf(0.0f, c * cw + s * sw);
    }
    float kd = gi_luminance(rc->kd) / GI_PI;
    float f = kd;
    if (rc->glossy && gi_luminance(rc->ks) > 0.0f) {
        gi_vec3 r = gi_v3_sub(gi_v3_scale(rc->n, 2.0f * gi_v3_dot(rc->n, rc->wo)), rc->wo);
        float cl = cos_bound(r, w, sin_h);
        f += gi_luminance(rc->ks) * (rc->exponent + 2.0f) / (2.0f * GI_PI) * powf(cl, rc->exponent);
    }
    return f * gi_luminance(S->I) * cr * cs / (dmin * dmin);
}

float cssm_bound(const cssm_node *S, const float L[3], const cssm_receiver *rc)
{
    cssm_node_view v = {.c = S->c,
                        .r = S->r,
                        .p = S->centroid,
                        .n = S->n,
                        .cos_cone = S->cos_cone,
                        .area = S->area};
    for (int k = 0; k < 3; k++)
        v.I[k] = L[k] * S->area;
    return bound_view(&v, rc);
}

/* The leaf (its rank in leaves[]) that stands for node S in a gather:
 * lightcuts' representative, which this paper's final gather and
 * refinement oracle build on (§4.4: "Recently, Walter et al. [24]
 * introduced lightcuts ... a hierarchy of VPLs"; §4.3: "The same upper
 * bound computation as presented in [24] is used here"). A node is a VPL
 * carrying the "radiant intensity" of §4.2.1, and lightcuts picks a
 * cluster's representative among its children with probability
 * proportional to their intensity, so that the cluster's light is sent from
 * where its light is: the walk goes down from S, at each node to the left
 * or right child with probability I_left / (I_left + I_right) (luminance).
 * An unlit texel is never picked while a lit one is below S, and the
 * gather, I_S G V at the picked leaf, has the expectation
 * sum_k I_k G_k V_k over the leaves. Jitter (§4.5, "we pick a random
 * location" inside the VPL's area) draws the walk's numbers from the
 * frame's generator; without jitter they come from a hash of the node's
 * index, a fixed choice per node and light set as in lightcuts. As in
 * lightcuts the node's light leaves from the representative's position
 * and normal (a mean normal of a cluster that holds the light and the
 * walls beside it points nowhere the light does). The area
 * rule of before (the texel nearest the centroid, uniform leaves with
 * jitter) is rep=centroid. */
static uint32_t pick_leaf(const cssm_tree *t, const float *node_L, const cssm_ctree *ct,
                          const cssm_node_view *S, int32_t index, uint32_t *rng)
{
    uint32_t fixed = gi_rng_init((uint32_t)index, 0, 0x2e9u);
    uint32_t *g = rng ? rng : &fixed;
    cssm_node_view v = *S;
    while (v.child >= 0) {
        cssm_node_view l, r;
        cssm_node_fetch(t, node_L, ct, v.child, &l);
        cssm_node_fetch(t, node_L, ct, l.skip, &r);
        float il = fmaxf(0.0f, gi_luminance(l.I)), ir = fmaxf(0.0f, gi_luminance(r.I));
        float pl = il + ir > 0.0f ? il / (il + ir) : l.area / fmaxf(l.area + r.area, FLT_MIN);
        v = gi_rng_next_float(g) < pl ? l : r;
    }
    return v.first;
}

/* vis=trace (Fig. 14): 1 when nothing lies on the segment from the receiver
 * x along unit w to the gathered point at distance d, less the depth bias at
 * the sender's end (the point lies on its own surface), else 0. */
static float trace_visible(const cssm_gather_opts *o, gi_vec3 x, gi_vec3 w, float d)
{
    float tmax = d - o->bias;
    if (!(tmax > 0.0f))
        return 1.0f;
    return gi_rt_occluded(o->trace, x, w, 0.0f, tmax) ? 0.0f : 1.0f;
}

/* One gathered node: sample position (the node's gather position, or with
 * jitter a random point of a leaf texel below it, §4.5), visibility
 * through that texel's CSSM (the leaf: pick_leaf). leaves: leaf rank ->
 * texel. */
static void transfer(const cssm_tree *t, const float *node_L, const cssm_ctree *ct,
                     const cssm_atlas *a, const cssm_maps *maps, const cssm_node_view *S,
                     int32_t index, const cssm_receiver *rc, const cssm_gather_opts *o,
                     float out[3], cssm_gather_stats *st)
{
    const uint32_t *leaves = ct ? ct->leaves : t->leaves;
    gi_vec3 y = S->p, ny = S->n;
    uint32_t vis_texel = S->rep;
    if (!o->rep_centroid) {
        /* lightcuts: the cluster's intensity sent from its representative's
         * position and orientation (jitter: a random point of it) */
        vis_texel = leaves[pick_leaf(t, node_L, ct, S, index, o->rng)];
        y = a->texels[vis_texel].p;
        ny = a->texels[vis_texel].n;
    } else if (o->rng) { /* a uniform leaf below S */
        uint32_t k = S->first + (uint32_t)(gi_rng_next_float(o->rng) * (float)S->count);
        if (k >= S->first + S->count)
            k = S->first + S->count - 1;
        vis_texel = leaves[k];
        if (S->count == 1)
            ny = a->texels[vis_texel].n;
    }
    if (o->rng) {
        const cssm_texel *x = &a->texels[vis_texel];
        gi_vec3 tu, tv;
        gi_onb(x->n, &tu, &tv);
        float side = sqrtf(x->area);
        float u1 = gi_rng_next_float(o->rng) - 0.5f, u2 = gi_rng_next_float(o->rng) - 0.5f;
        y = gi_v3_add(x->p, gi_v3_add(gi_v3_scale(tu, u1 * side), gi_v3_scale(tv, u2 * side)));
    }
    gi_vec3 w = gi_v3_sub(y, rc->x);
    float d2 = gi_v3_dot(w, w);
    if (!(d2 > 0.0f))
        return;
    float d = sqrtf(d2);
    w = gi_v3_scale(w, 1.0f / d);
    float cr = gi_v3_dot(rc->n, w), cs = -gi_v3_dot(ny, w);
    if (cr <= 0.0f || cs <= 0.0f)
        return;
    float c2 = o->clamp * o->clamp;
    if (d2 < c2) {
        d2 = c2;
        if (st)
            st->clamped++;
    }
    float v = o->trace ? trace_visible(o, rc->x, w, d)
              : maps   ? cssm_visible_rc(maps, vis_texel, rc, o->bias, o->pcf)
                       : 1.0f;
    if (v <= 0.0f)
        return;
    float g = cr * cs / d2 * v;
    float f[3] = {rc->kd[0] / GI_PI, rc->kd[1] / GI_PI, rc->kd[2] / GI_PI};
    if (rc->glossy && gi_luminance(rc->ks) > 0.0f) {
        gi_vec3 r = gi_v3_sub(gi_v3_scale(rc->n, 2.0f * gi_v3_dot(rc->n, rc->wo)), rc->wo);
        float cl = gi_v3_dot(r, w);
        float lobe =
            cl > 0.0f ? (rc->exponent + 2.0f) / (2.0f * GI_PI) * powf(cl, rc->exponent) : 0.0f;
        for (int k = 0; k < 3; k++)
            f[k] += rc->ks[k] * lobe;
    }
    for (int k = 0; k < 3; k++)
        out[k] += f[k] * S->I[k] * g;
}

/* Fig. 10 over either layout (ct NULL: the float nodes with node_L). */
/* §4.3's refinement test compares the tone-mapped bound, (b·scale)^(1/2.2),
 * with the threshold. powf is monotone, so the test equals b·scale > lim for
 * the largest lim whose tone-mapped value is still not above the threshold:
 * found once per receiver instead of one powf per visited node (the powf was
 * 15 % of the gather). The search steps to the exact float boundary, so the
 * cut, and the image, are the same bit for bit. */
float cssm_refine_limit(float thr)
{
    const float e = 1.0f / 2.2f;
    if (!(thr > 0.0f))
        return thr < 0.0f ? -1.0f : 0.0f; /* every positive bound refines */
    float lim = powf(thr, 2.2f);
    while (lim > 0.0f && powf(lim, e) > thr)
        lim = nextafterf(lim, 0.0f);
    for (float up = nextafterf(lim, INFINITY); up < INFINITY && powf(up, e) <= thr;
         up = nextafterf(lim, INFINITY))
        lim = up;
    return lim;
}

static void gather_any(const cssm_tree *t, const float *node_L, const cssm_ctree *ct,
                       const cssm_atlas *a, const cssm_maps *maps, const cssm_receiver *rc,
                       const cssm_gather_opts *o, float out[3], cssm_gather_stats *st)
{
    out[0] = out[1] = out[2] = 0.0f;
    const uint32_t *leaves = ct ? ct->leaves : t->leaves;
    /* Fig. 10: refine by the child pointer, gather and leave by the skip
     * pointer. `pending` counts the subtrees still to be visited, so that
     * gathered + pending is the size the cut reaches at least. */
    const float lim = cssm_refine_limit(o->threshold);
    const float scale = exp2f(o->exposure);
    uint32_t gathered = 0, pending = 1;
    int32_t i = 0;
    while (i >= 0) {
        cssm_node_view S;
        cssm_node_fetch(t, node_L, ct, i, &S);
        if (S.child < 0 && rc->self >= 0 && leaves[S.first] == (uint32_t)rc->self) {
            pending--;
            i = S.skip; /* no transfer to itself */
            continue;
        }
        const int lit = S.I[0] > 0.0f || S.I[1] > 0.0f || S.I[2] > 0.0f;
        int refine = 0;
        if (S.child >= 0 && gathered + pending + 1 <= o->max_cut && lit) {
            float b = bound_view(&S, rc);
            refine = b >= FLT_MAX || b * scale > lim;
        }
        if (refine) {
            pending++;
            i = S.child;
            continue;
        }
        if (lit)
            transfer(t, node_L, ct, a, maps, &S, i, rc, o, out, st);
        gathered++;
        pending--;
        i = S.skip;
    }
    if (st) {
        st->nodes += gathered;
        st->receivers++;
    }
}

void cssm_gather(const cssm_tree *t, const cssm_atlas *a, const cssm_maps *maps,
                 const float *node_L, const cssm_receiver *rc, const cssm_gather_opts *o,
                 float out[3], cssm_gather_stats *st)
{
    gather_any(t, node_L, NULL, a, maps, rc, o, out, st);
}

void cssm_cgather(const cssm_ctree *ct, const cssm_atlas *a, const cssm_maps *maps,
                  const cssm_receiver *rc, const cssm_gather_opts *o, float out[3],
                  cssm_gather_stats *st)
{
    gather_any(NULL, NULL, ct, a, maps, rc, o, out, st);
}

/* One gather over every texel of the atlas from node radiance node_L (or
 * the packed nodes ct); pass: 1 the direct gather, b bounce b (the
 * jitter's stream with o->atlas_jitter). */
static gi_result gather_atlas(const cssm_tree *t, const float *node_L, const cssm_ctree *ct,
                              const cssm_atlas *a, const cssm_maps *maps, const cssm_gather_opts *o,
                              uint32_t pass, float *out, cssm_gather_stats *st, gi_error *err)
{
    if (o->atlas_gather) /* the same gathers in a compute pass (bounces_on=gpu) */
        return o->atlas_gather(o->atlas_ctx, node_L, ct, pass, out, st, err);
    cssm_gather_opts oj = *o;
    uint32_t rng = 0;
    oj.rng = o->atlas_jitter ? &rng : NULL;
    for (uint32_t i = 0; i < a->count; i++) {
        const cssm_texel *x = &a->texels[i];
        cssm_receiver rc = {
            .x = cssm_receiver_point(maps, a, x->p, x->n), .n = x->n, .self = (int32_t)i};
        memcpy(rc.kd, x->albedo, sizeof rc.kd);
        rng = gi_rng_init(i, o->atlas_frame, o->atlas_seed ^ (CSSM_ATLAS_SALT + pass));
        gather_any(t, node_L, ct, a, maps, &rc, &oj, &out[3 * i], st);
    }
    return GI_OK;
}

gi_vec3 cssm_receiver_point(const cssm_maps *maps, const cssm_atlas *a, gi_vec3 p, gi_vec3 n)
{
    float eps = maps ? maps->znear : 1e-3f * a->diameter;
    return gi_v3_add(p, gi_v3_scale(n, 2.0f * eps));
}

/* Pull of per-texel values into the layout the gathers read. */
static void pull_any(const cssm_tree *t, cssm_ctree *ct, const cssm_atlas *a, const float *texel_L,
                     float *nodes)
{
    if (ct)
        cssm_ctree_pull(ct, a, texel_L);
    else
        cssm_tree_pull(t, a, texel_L, nodes);
}

gi_result cssm_solve(const cssm_tree *t, const cssm_atlas *a, const cssm_maps *maps,
                     const cssm_gather_opts *o, uint32_t bounces, const float *direct,
                     const gi_host *host, float *texel_L, float *node_L, cssm_gather_stats *st,
                     gi_error *err)
{
    return cssm_solve_ex(t, NULL, a, maps, o, bounces, direct, host, texel_L, node_L, st, err);
}

gi_result cssm_solve_ex(const cssm_tree *t, cssm_ctree *ct, const cssm_atlas *a,
                        const cssm_maps *maps, const cssm_gather_opts *o, uint32_t bounces,
                        const float *direct, const gi_host *host, float *texel_L, float *node_L,
                        cssm_gather_stats *st, gi_error *err)
{
    const uint32_t N = a->count;
    float *Le = calloc(3 * (size_t)N, sizeof *Le), *Rk = calloc(3 * (size_t)N, sizeof *Rk);
    float *Rn = calloc(3 * (size_t)N, sizeof *Rn),
          *nodes = calloc(3 * (size_t)t->count, sizeof *nodes);
    if (!Le || !Rk || !Rn || !nodes) {
        free(Le), free(Rk), free(Rn), free(nodes);
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "cssm_hrc: out of memory for the lighting");
    }
    for (uint32_t i = 0; i < N; i++)
        memcpy(&Le[3 * i], a->texels[i].emission, 3 * sizeof(float));
    memcpy(texel_L, Le, 3 * (size_t)N * sizeof *texel_L);
    gi_result r = GI_OK;
    if (bounces >= 1) {
        /* direct: the emitting texels gathered like any sender, plus the rest */
        gi_host_stage(host, "direct", 1);
        if (!o->no_emission) {
            pull_any(t, ct, a, Le, nodes);
            r = gather_atlas(t, nodes, ct, a, maps, o, 1, Rk, st, err);
        }
        if (direct)
            for (size_t k = 0; k < 3 * (size_t)N; k++)
                Rk[k] += direct[k];
        for (size_t k = 0; k < 3 * (size_t)N; k++)
            texel_L[k] += Rk[k];
        gi_host_stage(host, "direct", 0);
    }
    for (uint32_t b = 2; b <= bounces && r == GI_OK; b++) {
        gi_host_stage(host, "pull", 1);
        pull_any(t, ct, a, Rk, nodes);
        gi_host_stage(host, "pull", 0);
        gi_host_stage(host, "bounce", 1);
        memset(Rn, 0, 3 * (size_t)N * sizeof *Rn);
        r = gather_atlas(t, nodes, ct, a, maps, o, b, Rn, st, err);
        for (size_t k = 0; k < 3 * (size_t)N; k++)
            texel_L[k] += Rn[k];
        float *sw = Rk;
        Rk = Rn;
        Rn = sw;
        gi_host_stage(host, "bounce", 0);
    }
    gi_host_stage(host, "pull", 1);
    cssm_tree_pull(t, a, texel_L, node_L);
    if (ct)
        cssm_ctree_pull(ct, a, texel_L);
    gi_host_stage(host, "pull", 0);
    free(Le), free(Rk), free(Rn), free(nodes);
    return r;
}

double cssm_pdf_build(const cssm_atlas *a, const float *texel_values, double *cdf)
{
    cdf[0] = 0.0;
    for (uint32_t i = 0; i < a->count; i++)
        cdf[i + 1] =
            cdf[i] + (double)fmaxf(0.0f, gi_luminance(&texel_values[3 * i])) * a->texels[i].area;
    return cdf[a->count];
}

void cssm_gather_mc(const cssm_atlas *a, const cssm_maps *maps, const float *texel_values,
                    const double *cdf, uint32_t S, const cssm_receiver *rc,
                    const cssm_gather_opts *o, float out[3])
{
    out[0] = out[1] = out[2] = 0.0f;
    const double total = cdf[a->count];
    if (!(total > 0.0) || !S || !o->rng)
        return;
    for (uint32_t k = 0; k < S; k++) {
        double u = gi_rng_next_float(o->rng) * total;
        uint32_t lo = 0, hi = a->count; /* first i with cdf[i + 1] > u */
        while (lo + 1 < hi) {
            uint32_t mid = (lo + hi) / 2;
            if (cdf[mid] <= u)
                lo = mid;
            else
                hi = mid;
        }
        const cssm_texel *x = &a->texels[lo];
        if (rc->self == (int32_t)lo)
            continue;
        double p = (cdf[lo + 1] - cdf[lo]) / total;
        if (!(p > 0.0))
            continue;
        gi_vec3 tu, tv;
        gi_onb(x->n, &tu, &tv);
        float side = sqrtf(x->area);
        float u1 = gi_rng_next_float(o->rng) - 0.5f, u2 = gi_rng_next_float(o->rng) - 0.5f;
        gi_vec3 y =
            gi_v3_add(x->p, gi_v3_add(gi_v3_scale(tu, u1 * side), gi_v3_scale(tv, u2 * side)));
        gi_vec3 w = gi_v3_sub(y, rc->x);
        float d2 = gi_v3_dot(w, w);
        if (!(d2 > 0.0f))
            continue;
        const float d = sqrtf(d2);
        w = gi_v3_scale(w, 1.0f / d);
        float cr = gi_v3_dot(rc->n, w), cs = -gi_v3_dot(x->n, w);
        if (cr <= 0.0f || cs <= 0.0f)
            continue;
        d2 = fmaxf(d2, o->clamp * o->clamp);
        float v = o->trace ? trace_visible(o, rc->x, w, d)
                  : maps   ? cssm_visible_rc(maps, lo, rc, o->bias, o->pcf)
                           : 1.0f;
        if (v <= 0.0f)
            continue;
        float g = (float)(x->area * cr * cs / d2 * v / (p * S));
        float f[3] = {rc->kd[0] / GI_PI, rc->kd[1] / GI_PI, rc->kd[2] / GI_PI};
        if (rc->glossy && gi_luminance(rc->ks) > 0.0f) {
            gi_vec3 r = gi_v3_sub(gi_v3_scale(rc->n, 2.0f * gi_v3_dot(rc->n, rc->wo)), rc->wo);
            float cl = gi_v3_dot(r, w);
            float lobe =
                cl > 0.0f ? (rc->exponent + 2.0f) / (2.0f * GI_PI) * powf(cl, rc->exponent) : 0.0f;
            for (int c = 0; c < 3; c++)
                f[c] += rc->ks[c] * lobe;
        }
        for (int c = 0; c < 3; c++)
            out[c] += f[c] * texel_values[3 * lo + c] * g;
    }
}
