/* The implicit_vis method's hierarchical link structure (Sec. 4.2.2-4.2.4):
 * per node a 6 x N x N cube map of bins, each keeping only the shortest
 * link toward its direction (the implicit visibility); links made from
 * the top-level pairs down, a node subdivided while it looks bigger than
 * a bin from the other end; then refined and pushed down to the leaves'
 * receiving links. The same links on several threads: links_threads.c.
 * See iv.h. */
#include "iv_internal.h"

#include "gi/method.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

iv_links *iv_links_create(const iv_hier *h, uint32_t n)
{
    iv_links *l = calloc(1, sizeof *l);
    if (!l)
        return NULL;
    l->n = n;
    l->bins = 6 * n * n;
    l->nodes = h->node_count;
    size_t cells = (size_t)l->bins * l->nodes;
    l->cell = malloc(cells * sizeof *l->cell);
    l->bin_dir = malloc((size_t)l->bins * 3 * sizeof(float));
    l->bin_omega = malloc(l->bins * sizeof(float));
    l->root = malloc((size_t)l->nodes * sizeof *l->root);
    l->one_sided = calloc(l->nodes ? l->nodes : 1, 1);
    l->leaf_off = calloc((size_t)h->elem_count + 1, sizeof *l->leaf_off);
    l->light_off = calloc((size_t)h->elem_count + 1, sizeof *l->light_off);
    if (!l->cell || !l->bin_dir || !l->bin_omega || !l->leaf_off || !l->light_off || !l->root ||
        !l->one_sided) {
        iv_links_free(l);
        return NULL;
    }
    /* breadth-first: a parent comes before its children */
    for (uint32_t i = 0; i < l->nodes; i++)
        l->root[i] = h->parent[i] < 0 ? i : l->root[h->parent[i]];
    for (uint32_t i = l->nodes; i-- > 0;) {
        if (iv_is_leaf(h, i)) {
            l->one_sided[i] = !h->elem_two_sided_emit[h->node_elem[i]];
            continue;
        }
        uint8_t all = 1;
        for (uint32_t k = 0; k < h->child_count[i]; k++)
            all &= l->one_sided[h->first_child[i] + k];
        l->one_sided[i] = all;
    }
    for (uint32_t b = 0; b < l->bins; b++) {
        gi_v3_store(iv_bin_centre(b, n), &l->bin_dir[3 * b]);
        l->bin_omega[b] = iv_bin_solid_angle(b, n);
    }
    return l;
}

void iv_links_free(iv_links *l)
{
    if (!l)
        return;
    free(l->cell), free(l->cover), free(l->bin_dir), free(l->bin_omega);
    free(l->leaf_off), free(l->leaf_bin), free(l->leaf_src);
    free(l->light_off), free(l->light_bin), free(l->light_src);
    free(l->root), free(l->one_sided);
    for (uint32_t i = 0; i < l->pair_bufs; i++)
        free(l->pair_buf[i]);
    free(l->pair_buf), free(l->pair_cap);
    iv_kept_free(l->kept);
    free(l);
}

/* Writes node B into bin b of node A where it is nearer than what the bin
 * holds (the implicit visibility), and adds its solid angle `omega` to the
 * bin's coverage: every node's, or with IV_WEIGHT_SURFACE only those of
 * the nearest node's segment (a nearer node of another segment starts the
 * sum afresh, a farther one is hidden). */
static void put(iv_links *l, uint32_t A, uint32_t b, uint32_t B, float r, float omega)
{
    size_t i = (size_t)A * l->bins + b;
    iv_cell *c = &l->cell[i];
    if (!l->cover)
        ; /* Eq. 5: no coverage read, none kept */
    else if (l->weight != IV_WEIGHT_SURFACE)
        l->cover[i] += omega;
    else if (c->other < 0 || l->root[c->other] == l->root[B])
        l->cover[i] += omega;
    else if (r < c->dist)
        l->cover[i] = omega;
    if (r < c->dist) {
        c->dist = r;
        c->other = (int32_t)B;
        l->created++;
    }
}

/* The link to B in the (up to) four bins of A around direction d, each
 * with its bilinear share of B's solid angle (texel-centre interpolation
 * on d's cube face): a node between bins covers part of each. */
static void put_bilinear(iv_links *l, uint32_t A, gi_vec3 d, uint32_t B, float r, float omega)
{
    float a[3] = {d.x, d.y, d.z};
    int ax = iv_major_axis(a);
    float m = fabsf(a[ax]);
    if (!(m > 0.0f))
        return;
    int n = (int)l->n;
    uint32_t face = 2u * (uint32_t)ax + (a[ax] < 0.0f ? 1u : 0u);
    float fu = (a[(ax + 1) % 3] / m + 1.0f) * 0.5f * (float)n - 0.5f,
          fv = (a[(ax + 2) % 3] / m + 1.0f) * 0.5f * (float)n - 0.5f;
    int i0 = (int)floorf(fu), j0 = (int)floorf(fv);
    float tx = fu - (float)i0, ty = fv - (float)j0;
    for (int dj = 0; dj < 2; dj++)
        for (int di = 0; di < 2; di++) {
            float w = (di ? tx : 1.0f - tx) * (dj ? ty : 1.0f - ty);
            if (w < 1e-3f)
                continue;
            int i = i0 + di, j = j0 + dj;
            i = i < 0 ? 0 : (i >= n ? n - 1 : i);
            j = j < 0 ? 0 : (j >= n ? n - 1 : j);
            put(l, A, face * l->n * l->n + (uint32_t)j * l->n + (uint32_t)i, B, r, omega * w);
        }
}

/* Receiver A's side of the link A-B, d = B - A. A disc B that covers more
 * than one of A's bins (only a leaf can: a bigger cluster is subdivided)
 * is written into every bin it covers when `splat` is on: its disc,
 * oriented by its normal, sampled on a grid as fine as a bin seen at its
 * distance, as a shadow map rasterises a near occluder. */
void iv_put_side(iv_links *l, const iv_hier *h, uint32_t A, uint32_t B, gi_vec3 d, float r,
                 uint32_t b, int splat)
{
    float cover = h->area[B] / (r * r) / l->bin_omega[b];
    gi_vec3 n = gi_v3_load(&h->nrm[3 * B]);
    /* the one rule for sides (gi/scene.h): a single-sided node (every disc
     * below it facing one way) seen from behind is not there, and hides
     * nothing. A looks at B along d. Unlike gi_side, a node seen exactly
     * edge-on (a disc of the same plane) stays: it is a neighbour of A's
     * surface, not its back, and the nearest-node rule needs it. */
    if (l->one_sided[B] && gi_v3_dot(n, n) > 0.98f && gi_v3_dot(n, d) > 0.0f)
        return;
    /* B's solid angle seen from A: its area foreshortened by its mean
     * normal; a cluster whose discs face many ways (short mean normal)
     * shows more than its mean normal says */
    float c = fabsf(gi_v3_dot(n, d)) / r, len = gi_v3_length(n);
    float omega = h->area[B] * fmaxf(c, 1.0f - len) / (r * r);
    if (!splat || cover <= 1.0f || !iv_is_leaf(h, B)) {
        if (l->bilinear)
            put_bilinear(l, A, d, B, r, omega);
        else
            put(l, A, b, B, r, omega);
        return;
    }
    gi_vec3 pa = gi_v3_load(&h->pos[3 * A]), pb = gi_v3_load(&h->pos[3 * B]);
    gi_vec3 u = fabsf(n.x) < 0.9f ? gi_v3(1, 0, 0) : gi_v3(0, 1, 0);
    u = gi_v3_normalize(gi_v3_cross(n, u));
    gi_vec3 v = gi_v3_cross(n, u);
    float rad = sqrtf(h->area[B] / (float)GI_PI);
    int g = (int)ceilf(2.0f * sqrtf(cover)) + 1;
    g = g > 8 ? 8 : g;
    int inside = 0;
    for (int j = 0; j < g; j++)
        for (int i = 0; i < g; i++) {
            float x = (2.0f * ((float)i + 0.5f) / (float)g - 1.0f),
                  y = (2.0f * ((float)j + 0.5f) / (float)g - 1.0f);
            inside += x * x + y * y <= 1.0f;
        }
    /* the near disc's own solid angle, spread over the bins it spans: a
     * disc's, below a hemisphere however near. a / r^2 grows without bound
     * for a disc nearer than its size (the foot of a thin panel standing
     * on a floor), and Eq. 4's sums with it, so that light grew from
     * bounce to bounce (held-out seed 10 sky; README "Traced direct light") */
    omega = iv_disc_solid_angle((double)h->area[B] * fmaxf(c, 1.0f - len), (double)r * r);
    put(l, A, b, B, r, 0.0f);
    for (int j = 0; j < g; j++)
        for (int i = 0; i < g; i++) {
            float x = (2.0f * ((float)i + 0.5f) / (float)g - 1.0f),
                  y = (2.0f * ((float)j + 0.5f) / (float)g - 1.0f);
            if (x * x + y * y > 1.0f)
                continue;
            gi_vec3 q = gi_v3_add(pb, gi_v3_add(gi_v3_scale(u, x * rad), gi_v3_scale(v, y * rad)));
            gi_vec3 dq = gi_v3_sub(q, pa);
            float rq = gi_v3_length(dq);
            if (rq > 1e-10f)
                put(l, A, iv_bin_fast(dq, l->n), B, rq, omega / (float)inside);
        }
}

/* Stores the link A-B in A's bin toward B (bins[0]) and B's bin toward A
 * (bins[1]). */
static void insert(iv_links *l, const iv_hier *h, uint32_t A, uint32_t B, gi_vec3 d, float r,
                   const uint32_t bins[2], int splat)
{
    iv_put_side(l, h, A, B, d, r, bins[0], splat);
    iv_put_side(l, h, B, A, gi_v3_scale(d, -1.0f), r, bins[1], splat);
}

typedef struct link_ctx {
    iv_links *l;
    const iv_hier *h;
    float subdiv;
    int splat;
} link_ctx;

/* Two flat nodes (every disc below them facing one way) in one plane
 * exchange no light, both cosines being 0, and block only directions in
 * that plane: they are not linked (README "Deviations"). */
static int coplanar(const iv_hier *h, uint32_t A, uint32_t B, gi_vec3 d, float r2)
{
    gi_vec3 na = gi_v3_load(&h->nrm[3 * A]), nb = gi_v3_load(&h->nrm[3 * B]);
    if (gi_v3_dot(na, na) < 0.998f || gi_v3_dot(nb, nb) < 0.998f || gi_v3_dot(na, nb) < 0.998f)
        return 0;
    float r = sqrtf(r2), ca = gi_v3_dot(na, d) / r, cb = gi_v3_dot(nb, d) / r;
    return fabsf(ca) < 0.01f && fabsf(cb) < 0.01f;
}

int iv_pair_decide(const iv_links *l, const iv_hier *h, float subdiv, uint32_t A, uint32_t B,
                   gi_vec3 *dout, float *r2out, uint32_t bins[2])
{
    gi_vec3 d = gi_v3_sub(gi_v3_load(&h->pos[3 * B]), gi_v3_load(&h->pos[3 * A]));
    float r2 = gi_v3_dot(d, d);
    int leafA = iv_is_leaf(h, A), leafB = iv_is_leaf(h, B);
    int needA, needB;
    if (!(r2 > 1e-20f)) {
        needA = !leafA;
        needB = !leafB;
        if (!needA && !needB)
            return IV_PAIR_NONE; /* two discs at one point: no direction to bin them in */
    } else {
        if (coplanar(h, A, B, d, r2))
            return IV_PAIR_NONE;
        /* the bins the link would take on each side, kept for its writes */
        bins[0] = iv_bin_pair(d, l->n, &bins[1]);
        float oa = subdiv * l->bin_omega[bins[1]];
        float ob = subdiv * l->bin_omega[bins[0]];
        needB = !leafB && h->area[B] / r2 > ob;
        needA = !leafA && h->area[A] / r2 > oa;
    }
    if (needA && needB) {
        if (h->area[A] > h->area[B])
            needB = 0;
        else
            needA = 0;
    }
    *dout = d;
    *r2out = r2;
    return needB ? IV_PAIR_SPLIT_B : (needA ? IV_PAIR_SPLIT_A : IV_PAIR_LINK);
}

/* Sec. 4.2.2: link A and B, or their children where one looks bigger than
 * a bin from the other. */
int iv_links_cancelled(const iv_links *l)
{
    return l->host && l->host->cancelled && l->host->cancelled(l->host);
}

static void link_pair(link_ctx *c, uint32_t A, uint32_t B)
{
    const iv_hier *h = c->h;
    if (c->l->stopped ||
        ((++c->l->tries & 0xFFFF) == 0 && (c->l->stopped = iv_links_cancelled(c->l))))
        return; /* a cancel: the recursion unwinds */
    gi_vec3 d;
    float r2;
    uint32_t bins[2];
    switch (iv_pair_decide(c->l, h, c->subdiv, A, B, &d, &r2, bins)) {
    case IV_PAIR_SPLIT_B:
        for (uint32_t k = 0; k < h->child_count[B]; k++)
            link_pair(c, A, h->first_child[B] + k);
        break;
    case IV_PAIR_SPLIT_A:
        for (uint32_t k = 0; k < h->child_count[A]; k++)
            link_pair(c, h->first_child[A] + k, B);
        break;
    case IV_PAIR_LINK:
        insert(c->l, h, A, B, d, sqrtf(r2), bins, c->splat);
        break;
    default:
        break;
    }
}

/* The pairs inside one tree: each child with itself, then every two children. */
static void link_self(link_ctx *c, uint32_t A)
{
    const iv_hier *h = c->h;
    uint32_t f = h->first_child[A], n = h->child_count[A];
    for (uint32_t i = 0; i < n; i++)
        link_self(c, f + i);
    for (uint32_t i = 0; i < n; i++)
        for (uint32_t j = i + 1; j < n; j++)
            link_pair(c, f + i, f + j);
}

static void links_clear(iv_links *l)
{
    iv_links_clear_nodes(l, 0, 1);
    l->tries = l->created = 0;
}

void iv_links_clear_nodes(iv_links *l, uint32_t first, uint32_t step)
{
    for (uint32_t x = first; x < l->nodes; x += step) {
        size_t base = (size_t)x * l->bins;
        iv_cell *c = &l->cell[base];
        for (uint32_t b = 0; b < l->bins; b++) /* plain stores the compiler can widen */
            c[b].dist = FLT_MAX, c[b].other = -1;
        if (l->cover)
            memset(&l->cover[base], 0, l->bins * sizeof *l->cover);
    }
}

int iv_links_need_cover(const iv_links *l)
{
    return l->coverage > 0.0f || l->weight == IV_WEIGHT_SURFACE;
}

/* The coverage array where the modes read it, freed where they do not
 * (the links' writes then touch one cell each); 0 when out of memory. */
static int links_cover(iv_links *l)
{
    if (!iv_links_need_cover(l)) {
        free(l->cover);
        l->cover = NULL;
        return 1;
    }
    if (!l->cover)
        l->cover = malloc((size_t)l->bins * l->nodes * sizeof *l->cover);
    return l->cover != NULL;
}

void iv_links_build(iv_links *l, const iv_hier *h, float subdiv, int brute, int splat)
{
    l->stopped = 0;
    l->oom = !links_cover(l);
    if (l->oom)
        return;
    if (brute) {
        links_clear(l);
        for (uint32_t i = 0; i < h->elem_count && !l->stopped; i++) {
            if ((i & 63) == 63)
                l->stopped = iv_links_cancelled(l);
            for (uint32_t j = i + 1; j < h->elem_count; j++) {
                uint32_t A = h->elem_node[i], B = h->elem_node[j];
                gi_vec3 d = gi_v3_sub(gi_v3_load(&h->pos[3 * B]), gi_v3_load(&h->pos[3 * A]));
                float r2 = gi_v3_dot(d, d);
                l->tries++;
                uint32_t bins[2];
                bins[0] = iv_bin_pair(d, l->n, &bins[1]);
                if (r2 > 1e-20f)
                    insert(l, h, A, B, d, sqrtf(r2), bins, splat);
            }
        }
        return;
    }
    l->tries = l->created = 0;
    /* keep_pairs lists the pairs by top-level task, as the threaded build
     * does: on one thread too (the same links to the bit) */
    if ((l->threads > 1 || l->keep_pairs) &&
        iv_links_build_parallel(l, h, subdiv, splat, l->threads > 1 ? (int)l->threads : 1))
        return;     /* the writers emptied their nodes' bins first */
    links_clear(l); /* one thread (or the parallel build could not run) */
    link_ctx c = {l, h, subdiv, splat};
    for (uint32_t i = 0; i < h->root_count; i++)
        link_self(&c, i);
    for (uint32_t i = 0; i < h->root_count; i++)
        for (uint32_t j = i + 1; j < h->root_count; j++)
            link_pair(&c, i, j);
}

static int grow(uint32_t **a, uint32_t **b, size_t *cap, size_t need)
{
    if (need <= *cap)
        return 1;
    size_t n = *cap ? *cap : 1024;
    while (n < need)
        n *= 2;
    uint32_t *na = realloc(*a, n * sizeof **a);
    if (!na)
        return 0;
    *a = na;
    uint32_t *nb = realloc(*b, n * sizeof **b);
    if (!nb)
        return 0;
    *b = nb;
    *cap = n;
    return 1;
}

void iv_links_refine_push(iv_links *l, const iv_hier *h)
{
    uint32_t nb = l->bins;
    /* breadth-first: a parent is final before its children read it */
    for (uint32_t i = h->root_count; i < h->node_count; i++) {
        size_t p = (size_t)h->parent[i] * nb, c = (size_t)i * nb;
        const iv_cell *pc = &l->cell[p];
        iv_cell *cc = &l->cell[c];
        for (uint32_t b = 0; b < nb; b++) {
            /* the pairs linked higher up lie in this bin too (with
             * IV_WEIGHT_SURFACE: where they are of the nearer link's segment) */
            if (!l->cover)
                ;
            else if (l->weight != IV_WEIGHT_SURFACE || pc[b].other < 0 || cc[b].other < 0 ||
                     l->root[pc[b].other] == l->root[cc[b].other])
                l->cover[c + b] += l->cover[p + b];
            else if (pc[b].dist < cc[b].dist)
                l->cover[c + b] = l->cover[p + b];
            if (pc[b].dist < cc[b].dist)
                cc[b] = pc[b];
        }
    }
    /* emitting nodes: a node emits when one of its leaves does */
    uint8_t *emits = calloc(h->node_count, 1);
    if (emits) {
        for (uint32_t e = 0; e < h->elem_count; e++) {
            const float *le = &h->elem_emit[3 * e];
            emits[h->elem_node[e]] = le[0] > 0.0f || le[1] > 0.0f || le[2] > 0.0f;
        }
        for (uint32_t i = h->node_count; i-- > 0;)
            for (uint32_t k = 0; k < h->child_count[i]; k++)
                emits[i] |= emits[h->first_child[i] + k];
    }
    size_t nl = 0, nli = 0;
    for (uint32_t e = 0; e < h->elem_count; e++) {
        l->leaf_off[e] = (uint32_t)nl;
        l->light_off[e] = (uint32_t)nli;
        const iv_cell *c = &l->cell[(size_t)h->elem_node[e] * nb];
        for (uint32_t b = 0; b < nb; b++) {
            int32_t o = c[b].other;
            if (o < 0)
                continue;
            if (!grow(&l->leaf_bin, &l->leaf_src, &l->leaf_cap, nl + 1))
                break;
            l->leaf_bin[nl] = b;
            l->leaf_src[nl++] = (uint32_t)o;
            if (emits && emits[o]) {
                if (!grow(&l->light_bin, &l->light_src, &l->light_cap, nli + 1))
                    break;
                l->light_bin[nli] = b;
                l->light_src[nli++] = (uint32_t)o;
            }
        }
    }
    l->leaf_off[h->elem_count] = (uint32_t)nl;
    l->light_off[h->elem_count] = (uint32_t)nli;
    l->receiving = nl;
    free(emits);
}
