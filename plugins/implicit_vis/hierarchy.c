/* The implicit_vis method's geometric hierarchy (Sec. 4.1, 4.2.1): a
 * quadtree of discs per segment (connected part of an object's surface),
 * stored breadth-first without pointers, built once; every frame the
 * discs placed at the frame's time and every parent recomputed from its
 * children. See iv.h. */
#include "iv_internal.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

gi_result iv_hier_fail(const char *reason, gi_error *err)
{
    return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                        "implicit_vis: cannot build the surface elements and their hierarchy (%s)",
                        reason);
}

static uint32_t uf_find(uint32_t *p, uint32_t x)
{
    while (p[x] != x) {
        p[x] = p[p[x]];
        x = p[x];
    }
    return x;
}

static const float *g_sort_pos; /* positions the comparator reads */
static int g_sort_axis;

static int cmp_axis(const void *a, const void *b)
{
    float x = g_sort_pos[3 * *(const uint32_t *)a + g_sort_axis],
          y = g_sort_pos[3 * *(const uint32_t *)b + g_sort_axis];
    return x < y ? -1
                 : (x > y ? 1
                          : (int)(*(const uint32_t *)a > *(const uint32_t *)b) -
                                (int)(*(const uint32_t *)a < *(const uint32_t *)b));
}

static void sort_range(uint32_t *perm, uint32_t lo, uint32_t hi, const float *pos, int axis)
{
    g_sort_pos = pos;
    g_sort_axis = axis;
    qsort(perm + lo, hi - lo, sizeof *perm, cmp_axis);
}

/* Segments (Sec. 4.1): the surface's edges join their points' elements;
 * seg[e] is the element that stands for e's segment. uf: scratch of
 * elem_count entries. */
static void find_segments(const iv_hier *h, uint32_t *uf, uint32_t *seg)
{
    uint32_t ne = h->elem_count;
    for (uint32_t e = 0; e < ne; e++)
        uf[e] = e;
    for (uint32_t t = 0; t < h->surf_count; t++) /* the surface's edges join its points' elements */
        for (int c = 0; c < 2; c++) {
            uint32_t a = uf_find(uf, h->samp_elem[h->surf_tri[3 * t + c]]);
            uint32_t b = uf_find(uf, h->samp_elem[h->surf_tri[3 * t + c + 1]]);
            if (a != b)
                uf[b] = a;
        }
    for (uint32_t e = 0; e < ne; e++)
        seg[e] = uf_find(uf, e);
}

/* The elements grouped by segment, in order of first appearance (perm),
 * and one root per segment holding its run perm[lo .. hi - 1]. uf: scratch
 * of elem_count entries. 0 when out of memory. */
static int make_roots(iv_hier *h, uint32_t *uf, const uint32_t *seg, uint32_t *perm, uint32_t *lo,
                      uint32_t *hi)
{
    uint32_t ne = h->elem_count;
    uint32_t *first = malloc(ne * sizeof *first);
    uint32_t *cnt = calloc(ne, sizeof *cnt);
    int ok = first && cnt;
    if (ok) {
        uint32_t nseg = 0;
        uint32_t *seg_id = uf; /* reuse: root -> segment index */
        for (uint32_t e = 0; e < ne; e++)
            if (seg[e] == e)
                seg_id[e] = nseg++;
        for (uint32_t e = 0; e < ne; e++)
            cnt[seg_id[seg[e]]]++;
        uint32_t run = 0;
        for (uint32_t k = 0; k < nseg; k++) {
            first[k] = run;
            run += cnt[k];
        }
        memset(cnt, 0, nseg * sizeof *cnt);
        for (uint32_t e = 0; e < ne; e++) {
            uint32_t k = seg_id[seg[e]];
            perm[first[k] + cnt[k]++] = e;
        }
        h->segment_count = h->root_count = nseg;
        for (uint32_t k = 0; k < nseg; k++) {
            lo[k] = first[k];
            hi[k] = first[k] + cnt[k];
            h->parent[k] = -1;
        }
    }
    free(first);
    free(cnt);
    return ok;
}

/* The children of a node holding perm[lo .. hi - 1] (more than one
 * element): up to four elements one each; more are split at the median
 * of their widest axis and each half at the median of the second widest
 * (perm sorted so). cut: the parts' bounds. Returns the number of parts. */
static uint32_t split_node(uint32_t *perm, uint32_t lo, uint32_t hi, const float *rest,
                           uint32_t cut[5])
{
    uint32_t n = hi - lo;
    if (n <= 4) {
        for (uint32_t k = 0; k <= n; k++)
            cut[k] = lo + k;
        return n;
    }
    float mn[3] = {FLT_MAX, FLT_MAX, FLT_MAX}, mx[3] = {-FLT_MAX, -FLT_MAX, -FLT_MAX};
    for (uint32_t k = lo; k < hi; k++)
        for (int c = 0; c < 3; c++) {
            mn[c] = fminf(mn[c], rest[3 * perm[k] + c]);
            mx[c] = fmaxf(mx[c], rest[3 * perm[k] + c]);
        }
    int a1 = 0;
    for (int c = 1; c < 3; c++)
        if (mx[c] - mn[c] > mx[a1] - mn[a1])
            a1 = c;
    int a2 = (a1 + 1) % 3;
    for (int c = 0; c < 3; c++)
        if (c != a1 && mx[c] - mn[c] > mx[a2] - mn[a2])
            a2 = c;
    uint32_t mid = lo + n / 2;
    sort_range(perm, lo, hi, rest, a1);
    sort_range(perm, lo, mid, rest, a2);
    sort_range(perm, mid, hi, rest, a2);
    cut[0] = lo;
    cut[1] = lo + (mid - lo) / 2;
    cut[2] = mid;
    cut[3] = mid + (hi - mid) / 2;
    cut[4] = hi;
    return 4;
}

/* A quadtree per segment (connected part of an object's surface, the
 * stand-in for the paper's UV segments): a node's elements split at the
 * median of their widest axis, each half at the median of the second
 * widest, so that a node has up to four children. */
static gi_result build_tree(iv_hier *h, gi_error *err)
{
    uint32_t ne = h->elem_count;
    uint32_t *uf = malloc(ne * sizeof *uf);
    float *rest = malloc((size_t)ne * 3 * sizeof(float));
    uint32_t *perm = malloc(ne * sizeof *perm);
    uint32_t *seg = malloc(ne * sizeof *seg);
    uint32_t cap = 2 * ne + 4;
    uint32_t *lo = malloc(cap * sizeof *lo), *hi = malloc(cap * sizeof *hi);
    h->first_child = calloc(cap, sizeof *h->first_child);
    h->child_count = calloc(cap, 1);
    h->parent = malloc(cap * sizeof *h->parent);
    h->node_elem = malloc(cap * sizeof *h->node_elem);
    h->elem_node = malloc(ne * sizeof *h->elem_node);
    uint8_t *lvl = calloc(cap, 1);
    int ok = uf && rest && perm && seg && lo && hi && h->first_child && h->child_count &&
             h->parent && h->node_elem && h->elem_node && lvl;
    if (ok) {
        /* objects never share elements: each tree holds one object's */
        for (uint32_t e = 0; e < ne; e++)
            memcpy(&rest[3 * e], &h->rest[3 * h->elem_rep[e]], 3 * sizeof(float));
        find_segments(h, uf, seg);
        ok = make_roots(h, uf, seg, perm, lo, hi);
    }
    if (ok) {
        uint32_t nn = h->root_count;
        for (uint32_t i = 0; i < nn; i++) {
            h->node_elem[i] = -1;
            if (hi[i] - lo[i] == 1) {
                h->node_elem[i] = (int32_t)perm[lo[i]];
                h->elem_node[perm[lo[i]]] = i;
                continue;
            }
            uint32_t cut[5];
            uint32_t parts = split_node(perm, lo[i], hi[i], rest, cut);
            h->first_child[i] = nn;
            h->child_count[i] = (uint8_t)parts;
            for (uint32_t k = 0; k < parts; k++) {
                lo[nn] = cut[k];
                hi[nn] = cut[k + 1];
                h->parent[nn] = (int32_t)i;
                lvl[nn] = (uint8_t)(lvl[i] + 1);
                if (lvl[nn] + 1u > h->depth)
                    h->depth = lvl[nn] + 1u;
                nn++;
            }
        }
        h->node_count = nn;
        if (h->depth == 0)
            h->depth = 1;
    }
    free(uf), free(rest), free(perm), free(seg), free(lo), free(hi), free(lvl);
    return ok ? GI_OK : iv_hier_fail("out of memory", err);
}

/* The arrays iv_hier_update fills every frame, and its scratch. */
static gi_result alloc_frame(iv_hier *h, const gi_scene *s, gi_error *err)
{
    uint32_t maxv = 0;
    for (uint32_t o = 0; o < s->object_count; o++)
        maxv = s->objects[o].vertex_count > maxv ? s->objects[o].vertex_count : maxv;
    h->pos = calloc((size_t)h->node_count * 3, sizeof(float));
    h->nrm = calloc((size_t)h->node_count * 3, sizeof(float));
    h->area = calloc(h->node_count, sizeof(float));
    h->spos = calloc((size_t)h->sample_count * 3 + 1, sizeof(float));
    h->verts = calloc(maxv ? maxv : 1, sizeof(gi_vertex));
    h->wpos = calloc((size_t)s->vertex_count * 3 + 1, sizeof(float));
    h->wnrm = calloc((size_t)s->vertex_count * 3 + 1, sizeof(float));
    if (!h->pos || !h->nrm || !h->area || !h->spos || !h->verts || !h->wpos || !h->wnrm)
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY,
                            "implicit_vis: out of memory for %u hierarchy nodes", h->node_count);
    return GI_OK;
}

iv_hier *iv_hier_create(const gi_scene *s, float target_edge, int remesher, gi_error *err)
{
    iv_hier *h = calloc(1, sizeof *h);
    gi_result r = !h || s->triangle_count == 0
                      ? iv_hier_fail(s->triangle_count == 0 ? "no triangles" : "out of memory", err)
                      : iv_elements_make(h, s, target_edge, remesher, err);
    if (r == GI_OK)
        r = build_tree(h, err);
    if (r == GI_OK)
        r = alloc_frame(h, s, err);
    if (r != GI_OK) {
        iv_hier_free(h);
        return NULL;
    }
    return h;
}

void iv_hier_free(iv_hier *h)
{
    if (!h)
        return;
    free(h->tri_k), free(h->tri_grid), free(h->samp_tri), free(h->samp_b), free(h->samp_elem);
    free(h->surf_tri), free(h->disp_elem), free(h->disp_w);
    free(h->rest), free(h->wpos), free(h->wnrm);
    free(h->elem_rep), free(h->elem_albedo), free(h->elem_emit), free(h->elem_two_sided_emit);
    free(h->first_child), free(h->child_count), free(h->parent), free(h->node_elem),
        free(h->elem_node);
    free(h->pos), free(h->nrm), free(h->area), free(h->spos), free(h->verts);
    free(h);
}

void iv_hier_update(iv_hier *h, const gi_scene *s, float t)
{
    memset(h->nrm, 0, (size_t)h->node_count * 3 * sizeof(float));
    memset(h->area, 0, (size_t)h->node_count * sizeof(float));
    /* the model's vertices at t (rigid motion, morph targets), world space */
    for (uint32_t o = 0; o < s->object_count; o++) {
        const gi_object *ob = &s->objects[o];
        float m[16], inv[16], nm[16];
        gi_scene_object_transform(s, o, t, m);
        if (!gi_mat4_invert(inv, m))
            gi_mat4_identity(inv);
        gi_mat4_transpose(nm, inv);
        const gi_vertex *vs = s->vertices + ob->first_vertex;
        if (ob->morph_count > 0) {
            gi_scene_object_vertices(s, o, t, h->verts);
            vs = h->verts;
        }
        for (uint32_t i = 0; i < ob->vertex_count; i++) {
            size_t v = ob->first_vertex + i;
            gi_v3_store(gi_mat4_point(m, gi_v3_load(vs[i].position)), &h->wpos[3 * v]);
            gi_v3_store(gi_v3_normalize(gi_mat4_dir(nm, gi_v3_load(vs[i].normal))),
                        &h->wnrm[3 * v]);
        }
    }
    /* the discs: points of the triangles, areas a third of the surface's triangles around them */
    for (uint32_t si = 0; si < h->sample_count; si++) {
        uint32_t tr = h->samp_tri[si], e = h->samp_elem[si], leaf = h->elem_node[e];
        const uint32_t *ix = &s->indices[3 * tr];
        float b1 = h->samp_b[2 * si], b2 = h->samp_b[2 * si + 1], b0 = 1.0f - b1 - b2;
        float *p = &h->spos[3 * si];
        for (int c = 0; c < 3; c++)
            p[c] = b0 * h->wpos[3 * ix[0] + c] + b1 * h->wpos[3 * ix[1] + c] +
                   b2 * h->wpos[3 * ix[2] + c];
        if (h->elem_rep[e] == si)
            memcpy(&h->pos[3 * leaf], p, 3 * sizeof(float));
        for (int c = 0; c < 3; c++)
            h->nrm[3 * leaf + c] += b0 * h->wnrm[3 * ix[0] + c] + b1 * h->wnrm[3 * ix[1] + c] +
                                    b2 * h->wnrm[3 * ix[2] + c];
    }
    for (uint32_t f = 0; f < h->surf_count; f++) {
        const uint32_t *v = &h->surf_tri[3 * f];
        gi_vec3 p0 = gi_v3_load(&h->spos[3 * v[0]]), p1 = gi_v3_load(&h->spos[3 * v[1]]),
                p2 = gi_v3_load(&h->spos[3 * v[2]]);
        float a = gi_v3_length(gi_v3_cross(gi_v3_sub(p1, p0), gi_v3_sub(p2, p0))) / 6.0f;
        for (int c = 0; c < 3; c++)
            h->area[h->elem_node[h->samp_elem[v[c]]]] += a;
    }
    for (uint32_t e = 0; e < h->elem_count; e++) {
        float *n = &h->nrm[3 * h->elem_node[e]];
        gi_v3_store(gi_v3_normalize(gi_v3_load(n)), n);
    }
    /* Sec. 4.2.1: parents from their children, bottom-up */
    for (uint32_t i = h->node_count; i-- > 0;) {
        if (iv_is_leaf(h, i))
            continue;
        double p[3] = {0, 0, 0}, n[3] = {0, 0, 0}, a = 0.0;
        for (uint32_t k = 0; k < h->child_count[i]; k++) {
            uint32_t c = h->first_child[i] + k;
            double w = h->area[c] > 0.0f ? h->area[c] : 1e-30;
            for (int j = 0; j < 3; j++) {
                p[j] += w * h->pos[3 * c + j];
                n[j] += w * h->nrm[3 * c + j];
            }
            a += w;
        }
        for (int j = 0; j < 3; j++) {
            h->pos[3 * i + j] = (float)(p[j] / a);
            h->nrm[3 * i + j] = (float)(n[j] / a);
        }
        h->area[i] = (float)a;
    }
}

void iv_hier_edge_stats(const iv_hier *h, const gi_scene *s, double *mean, double *cv)
{
    double sum = 0.0, sum2 = 0.0;
    size_t n = 0;
    for (uint32_t t = 0; t < h->surf_count; t++) {
        gi_vec3 p[3];
        for (int c = 0; c < 3; c++) {
            uint32_t si = h->surf_tri[3 * t + c];
            float m[16];
            gi_scene_object_transform(s, s->vertices[s->indices[3 * h->samp_tri[si]]].object, 0.0f,
                                      m);
            p[c] = gi_mat4_point(m, gi_v3_load(&h->rest[3 * si]));
        }
        for (int c = 0; c < 3; c++) {
            double e = gi_v3_length(gi_v3_sub(p[(c + 1) % 3], p[c]));
            sum += e;
            sum2 += e * e;
            n++;
        }
    }
    double mu = n ? sum / (double)n : 0.0, var = n ? sum2 / (double)n - mu * mu : 0.0;
    *mean = mu;
    *cv = mu > 0.0 ? sqrt(var > 0.0 ? var : 0.0) / mu : 0.0;
}
