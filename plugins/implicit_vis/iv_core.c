/* The implicit_vis method's CPU side: surface elements and their hierarchy
 * (Sec. 4.1, 4.2.1), cube-map bins and hierarchical links with implicit
 * visibility (Sec. 4.2.2-4.2.4), gathering along the links (Sec. 4.3, 4.4).
 * See iv.h. */
#include "iv.h"

#include "gi/lights.h"
#include "gi/mesh.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------ bins */

uint32_t iv_bin_of(gi_vec3 d, uint32_t n)
{
    float a[3] = {d.x, d.y, d.z};
    int ax = 0;
    if (fabsf(a[1]) > fabsf(a[ax]))
        ax = 1;
    if (fabsf(a[2]) > fabsf(a[ax]))
        ax = 2;
    float m = fabsf(a[ax]);
    if (!(m > 0.0f))
        return 0;
    uint32_t face = 2u * (uint32_t)ax + (a[ax] < 0.0f ? 1u : 0u);
    float u = a[(ax + 1) % 3] / m, v = a[(ax + 2) % 3] / m;
    int col = (int)floorf((u + 1.0f) * 0.5f * (float)n), row = (int)floorf((v + 1.0f) * 0.5f * (float)n);
    col = col < 0 ? 0 : (col >= (int)n ? (int)n - 1 : col);
    row = row < 0 ? 0 : (row >= (int)n ? (int)n - 1 : row);
    return face * n * n + (uint32_t)row * n + (uint32_t)col;
}

/* Face, and the texel's square [u0, u1] x [v0, v1] on it. */
static void bin_square(uint32_t b, uint32_t n, uint32_t *face, float *u0, float *u1, float *v0, float *v1)
{
    *face = b / (n * n);
    uint32_t r = b % (n * n), row = r / n, col = r % n;
    *u0 = 2.0f * (float)col / (float)n - 1.0f;
    *u1 = 2.0f * (float)(col + 1) / (float)n - 1.0f;
    *v0 = 2.0f * (float)row / (float)n - 1.0f;
    *v1 = 2.0f * (float)(row + 1) / (float)n - 1.0f;
}

gi_vec3 iv_bin_centre(uint32_t b, uint32_t n)
{
    uint32_t face;
    float u0, u1, v0, v1;
    bin_square(b, n, &face, &u0, &u1, &v0, &v1);
    int ax = (int)face / 2;
    float a[3];
    a[ax] = (face & 1u) ? -1.0f : 1.0f;
    a[(ax + 1) % 3] = 0.5f * (u0 + u1);
    a[(ax + 2) % 3] = 0.5f * (v0 + v1);
    return gi_v3_normalize(gi_v3(a[0], a[1], a[2]));
}

static double texel_f(double x, double y) { return atan2(x * y, sqrt(x * x + y * y + 1.0)); }

float iv_bin_solid_angle(uint32_t b, uint32_t n)
{
    uint32_t face;
    float u0, u1, v0, v1;
    bin_square(b, n, &face, &u0, &u1, &v0, &v1);
    return (float)(texel_f(u1, v1) - texel_f(u0, v1) - texel_f(u1, v0) + texel_f(u0, v0));
}

/* ------------------------------------------------------- elements (4.1) */

static uint32_t uf_find(uint32_t *p, uint32_t x)
{
    while (p[x] != x) {
        p[x] = p[p[x]];
        x = p[x];
    }
    return x;
}

/* Model vertices as discs: scene vertices of one welded position whose
 * normals agree (cos > 0.95) are one element; a hard edge keeps two. */
static int make_elements(iv_hier *h, const gi_scene *s)
{
    gi_welded *w = gi_mesh_weld(s, 1e-5f);
    if (!w)
        return 0;
    uint32_t nv = s->vertex_count;
    int64_t *head = malloc(w->vertex_count * sizeof *head);
    int64_t *next = malloc(nv * sizeof *next);
    h->vert_elem = malloc(nv * sizeof *h->vert_elem);
    h->elem_rep = malloc(nv * sizeof *h->elem_rep);
    float *albedo_sum = calloc((size_t)nv * 3, sizeof(float));
    float *emit = calloc((size_t)nv * 3, sizeof(float));
    uint8_t *two = calloc(nv, 1);
    uint32_t *count = calloc(nv, sizeof *count);
    if (!head || !next || !h->vert_elem || !h->elem_rep || !albedo_sum || !emit || !two || !count) {
        free(head), free(next), free(albedo_sum), free(emit), free(two), free(count);
        gi_welded_free(w);
        return 0;
    }
    for (uint32_t i = 0; i < w->vertex_count; i++)
        head[i] = -1;
    uint32_t ne = 0;
    for (uint32_t v = 0; v < nv; v++) {
        uint32_t wv = w->remap[v];
        gi_vec3 nv3 = gi_v3_load(s->vertices[v].normal);
        int64_t e = head[wv];
        while (e >= 0 && gi_v3_dot(gi_v3_load(s->vertices[h->elem_rep[e]].normal), nv3) <= 0.95f)
            e = next[e];
        if (e < 0) {
            e = ne++;
            h->elem_rep[e] = v;
            next[e] = head[wv];
            head[wv] = e;
        }
        h->vert_elem[v] = (uint32_t)e;
        float a[3];
        const gi_material *m = &s->materials[s->vertices[v].material];
        gi_scene_albedo(s, s->vertices[v].material, s->vertices[v].uv, a);
        for (int c = 0; c < 3; c++) {
            albedo_sum[3 * e + c] += a[c];
            emit[3 * e + c] = fmaxf(emit[3 * e + c], m->emission[c]);
        }
        two[e] |= (uint8_t)(m->double_sided != 0);
        count[e]++;
    }
    for (uint32_t e = 0; e < ne; e++)
        for (int c = 0; c < 3; c++)
            albedo_sum[3 * e + c] /= (float)count[e];
    h->elem_count = ne;
    h->elem_albedo = albedo_sum;
    h->elem_emit = emit;
    h->elem_two_sided_emit = two;
    free(head), free(next), free(count);
    gi_welded_free(w);
    return ne > 0;
}

/* ------------------------------------------------------ hierarchy (4.1) */

static const float *g_sort_pos; /* positions the comparator reads */
static int g_sort_axis;

static int cmp_axis(const void *a, const void *b)
{
    float x = g_sort_pos[3 * *(const uint32_t *)a + g_sort_axis], y = g_sort_pos[3 * *(const uint32_t *)b + g_sort_axis];
    return x < y ? -1 : (x > y ? 1 : (int)(*(const uint32_t *)a > *(const uint32_t *)b) - (int)(*(const uint32_t *)a < *(const uint32_t *)b));
}

static void sort_range(uint32_t *perm, uint32_t lo, uint32_t hi, const float *pos, int axis)
{
    g_sort_pos = pos;
    g_sort_axis = axis;
    qsort(perm + lo, hi - lo, sizeof *perm, cmp_axis);
}

/* A quadtree per segment (connected part of an object's surface, the
 * stand-in for the paper's UV segments): a node's elements split at the
 * median of their widest axis, each half at the median of the second
 * widest, so that a node has up to four children. */
static int build_tree(iv_hier *h, const gi_scene *s)
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
    int ok = uf && rest && perm && seg && lo && hi && h->first_child && h->child_count && h->parent && h->node_elem &&
             h->elem_node && lvl;
    if (ok) {
        for (uint32_t e = 0; e < ne; e++) {
            uf[e] = e;
            const gi_vertex *v = &s->vertices[h->elem_rep[e]];
            /* objects never share elements; the object index keeps them apart when sorting */
            memcpy(&rest[3 * e], v->position, 3 * sizeof(float));
        }
        for (uint32_t t = 0; t < s->triangle_count; t++) {
            uint32_t a = uf_find(uf, h->vert_elem[s->indices[3 * t]]);
            for (int c = 1; c < 3; c++) {
                uint32_t b = uf_find(uf, h->vert_elem[s->indices[3 * t + c]]);
                if (a != b)
                    uf[b] = a;
            }
        }
        for (uint32_t e = 0; e < ne; e++)
            seg[e] = uf_find(uf, e);
        /* elements grouped by segment, in order of first appearance */
        uint32_t *first = malloc(ne * sizeof *first);
        uint32_t *cnt = calloc(ne, sizeof *cnt);
        ok = first && cnt;
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
            uint32_t nn = nseg;
            for (uint32_t i = 0; i < nn; i++) {
                uint32_t n = hi[i] - lo[i];
                h->node_elem[i] = -1;
                if (n == 1) {
                    h->node_elem[i] = (int32_t)perm[lo[i]];
                    h->elem_node[perm[lo[i]]] = i;
                    continue;
                }
                uint32_t cut[5];
                uint32_t parts = 0;
                if (n <= 4) {
                    for (uint32_t k = 0; k <= n; k++)
                        cut[k] = lo[i] + k;
                    parts = n;
                } else {
                    float mn[3] = {FLT_MAX, FLT_MAX, FLT_MAX}, mx[3] = {-FLT_MAX, -FLT_MAX, -FLT_MAX};
                    for (uint32_t k = lo[i]; k < hi[i]; k++)
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
                    uint32_t mid = lo[i] + n / 2;
                    sort_range(perm, lo[i], hi[i], rest, a1);
                    sort_range(perm, lo[i], mid, rest, a2);
                    sort_range(perm, mid, hi[i], rest, a2);
                    cut[0] = lo[i];
                    cut[1] = lo[i] + (mid - lo[i]) / 2;
                    cut[2] = mid;
                    cut[3] = mid + (hi[i] - mid) / 2;
                    cut[4] = hi[i];
                    parts = 4;
                }
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
        free(first);
        free(cnt);
    }
    free(uf), free(rest), free(perm), free(seg), free(lo), free(hi), free(lvl);
    return ok;
}

iv_hier *iv_hier_create(const gi_scene *s, gi_error *err)
{
    iv_hier *h = calloc(1, sizeof *h);
    if (!h || s->vertex_count == 0 || !make_elements(h, s) || !build_tree(h, s)) {
        gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "implicit_vis: cannot build the surface elements and their hierarchy (%s)",
                     s->vertex_count == 0 ? "no vertices" : "out of memory");
        iv_hier_free(h);
        return NULL;
    }
    uint32_t maxv = 0;
    for (uint32_t o = 0; o < s->object_count; o++)
        maxv = s->objects[o].vertex_count > maxv ? s->objects[o].vertex_count : maxv;
    h->pos = calloc((size_t)h->node_count * 3, sizeof(float));
    h->nrm = calloc((size_t)h->node_count * 3, sizeof(float));
    h->area = calloc(h->node_count, sizeof(float));
    h->tri_area = calloc(s->triangle_count ? s->triangle_count : 1, sizeof(float));
    h->verts = calloc(maxv ? maxv : 1, sizeof(gi_vertex));
    if (!h->pos || !h->nrm || !h->area || !h->tri_area || !h->verts) {
        gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "implicit_vis: out of memory for %u hierarchy nodes", h->node_count);
        iv_hier_free(h);
        return NULL;
    }
    return h;
}

void iv_hier_free(iv_hier *h)
{
    if (!h)
        return;
    free(h->vert_elem), free(h->elem_rep), free(h->elem_albedo), free(h->elem_emit), free(h->elem_two_sided_emit);
    free(h->first_child), free(h->child_count), free(h->parent), free(h->node_elem), free(h->elem_node);
    free(h->pos), free(h->nrm), free(h->area), free(h->tri_area), free(h->verts);
    free(h);
}

void iv_hier_update(iv_hier *h, const gi_scene *s, float t)
{
    memset(h->nrm, 0, (size_t)h->node_count * 3 * sizeof(float));
    memset(h->area, 0, (size_t)h->node_count * sizeof(float));
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
            uint32_t v = ob->first_vertex + i, e = h->vert_elem[v], leaf = h->elem_node[e];
            if (h->elem_rep[e] == v)
                gi_v3_store(gi_mat4_point(m, gi_v3_load(vs[i].position)), &h->pos[3 * leaf]);
            gi_vec3 n = gi_v3_normalize(gi_mat4_dir(nm, gi_v3_load(vs[i].normal)));
            for (int c = 0; c < 3; c++)
                h->nrm[3 * leaf + c] += (&n.x)[c];
        }
    }
    gi_mesh_triangle_areas(s, t, h->tri_area);
    for (uint32_t t3 = 0; t3 < s->triangle_count; t3++)
        for (int c = 0; c < 3; c++)
            h->area[h->elem_node[h->vert_elem[s->indices[3 * t3 + c]]]] += h->tri_area[t3] / 3.0f;
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

/* ---------------------------------------------------------- links (4.2) */

iv_links *iv_links_create(const iv_hier *h, uint32_t n)
{
    iv_links *l = calloc(1, sizeof *l);
    if (!l)
        return NULL;
    l->n = n;
    l->bins = 6 * n * n;
    l->nodes = h->node_count;
    size_t cells = (size_t)l->bins * l->nodes;
    l->other = malloc(cells * sizeof *l->other);
    l->dist = malloc(cells * sizeof *l->dist);
    l->bin_dir = malloc((size_t)l->bins * 3 * sizeof(float));
    l->bin_omega = malloc(l->bins * sizeof(float));
    l->leaf_off = calloc((size_t)h->elem_count + 1, sizeof *l->leaf_off);
    l->light_off = calloc((size_t)h->elem_count + 1, sizeof *l->light_off);
    if (!l->other || !l->dist || !l->bin_dir || !l->bin_omega || !l->leaf_off || !l->light_off) {
        iv_links_free(l);
        return NULL;
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
    free(l->other), free(l->dist), free(l->bin_dir), free(l->bin_omega);
    free(l->leaf_off), free(l->leaf_bin), free(l->leaf_src);
    free(l->light_off), free(l->light_bin), free(l->light_src);
    free(l);
}

/* Writes node B into bin b of node A where it is nearer than what the bin
 * holds (the implicit visibility). */
static void put(iv_links *l, uint32_t A, uint32_t b, uint32_t B, float r)
{
    size_t i = (size_t)A * l->bins + b;
    if (r < l->dist[i]) {
        l->dist[i] = r;
        l->other[i] = (int32_t)B;
        l->created++;
    }
}

/* Receiver A's side of the link A-B, d = B - A. A disc B that covers more
 * than one of A's bins (only a leaf can: a bigger cluster is subdivided)
 * is written into every bin it covers when `splat` is on: its disc,
 * oriented by its normal, sampled on a grid as fine as a bin seen at its
 * distance, as a shadow map rasterises a near occluder. */
static void put_side(iv_links *l, const iv_hier *h, uint32_t A, uint32_t B, gi_vec3 d, float r, int splat)
{
    uint32_t b = iv_bin_of(d, l->n);
    float cover = h->area[B] / (r * r) / l->bin_omega[b];
    if (!splat || cover <= 1.0f || !iv_is_leaf(h, B)) {
        put(l, A, b, B, r);
        return;
    }
    gi_vec3 n = gi_v3_load(&h->nrm[3 * B]), pa = gi_v3_load(&h->pos[3 * A]), pb = gi_v3_load(&h->pos[3 * B]);
    gi_vec3 u = fabsf(n.x) < 0.9f ? gi_v3(1, 0, 0) : gi_v3(0, 1, 0);
    u = gi_v3_normalize(gi_v3_cross(n, u));
    gi_vec3 v = gi_v3_cross(n, u);
    float rad = sqrtf(h->area[B] / (float)GI_PI);
    int g = (int)ceilf(2.0f * sqrtf(cover)) + 1;
    g = g > 16 ? 16 : g;
    put(l, A, b, B, r);
    for (int j = 0; j < g; j++)
        for (int i = 0; i < g; i++) {
            float x = (2.0f * ((float)i + 0.5f) / (float)g - 1.0f), y = (2.0f * ((float)j + 0.5f) / (float)g - 1.0f);
            if (x * x + y * y > 1.0f)
                continue;
            gi_vec3 q = gi_v3_add(pb, gi_v3_add(gi_v3_scale(u, x * rad), gi_v3_scale(v, y * rad)));
            gi_vec3 dq = gi_v3_sub(q, pa);
            float rq = gi_v3_length(dq);
            if (rq > 1e-10f)
                put(l, A, iv_bin_of(dq, l->n), B, rq);
        }
}

/* Stores the link A-B in A's bin toward B and B's bin toward A. */
static void insert(iv_links *l, const iv_hier *h, uint32_t A, uint32_t B, gi_vec3 d, float r, int splat)
{
    put_side(l, h, A, B, d, r, splat);
    put_side(l, h, B, A, gi_v3_scale(d, -1.0f), r, splat);
}

typedef struct link_ctx {
    iv_links *l;
    const iv_hier *h;
    float subdiv;
    int splat;
} link_ctx;

/* Sec. 4.2.2: link A and B, or their children where one looks bigger than
 * a bin from the other. */
static void link_pair(link_ctx *c, uint32_t A, uint32_t B)
{
    const iv_hier *h = c->h;
    c->l->tries++;
    gi_vec3 d = gi_v3_sub(gi_v3_load(&h->pos[3 * B]), gi_v3_load(&h->pos[3 * A]));
    float r2 = gi_v3_dot(d, d);
    int leafA = iv_is_leaf(h, A), leafB = iv_is_leaf(h, B);
    int needA, needB;
    if (!(r2 > 1e-20f)) {
        needA = !leafA;
        needB = !leafB;
        if (!needA && !needB)
            return; /* two discs at one point: no direction to bin them in */
    } else {
        float oa = c->subdiv * c->l->bin_omega[iv_bin_of(gi_v3_scale(d, -1.0f), c->l->n)];
        float ob = c->subdiv * c->l->bin_omega[iv_bin_of(d, c->l->n)];
        needB = !leafB && h->area[B] / r2 > ob;
        needA = !leafA && h->area[A] / r2 > oa;
    }
    if (needA && needB) {
        if (h->area[A] > h->area[B])
            needB = 0;
        else
            needA = 0;
    }
    if (needB) {
        for (uint32_t k = 0; k < h->child_count[B]; k++)
            link_pair(c, A, h->first_child[B] + k);
    } else if (needA) {
        for (uint32_t k = 0; k < h->child_count[A]; k++)
            link_pair(c, h->first_child[A] + k, B);
    } else {
        insert(c->l, h, A, B, d, sqrtf(r2), c->splat);
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

void iv_links_build(iv_links *l, const iv_hier *h, float subdiv, int brute, int splat)
{
    size_t cells = (size_t)l->bins * l->nodes;
    for (size_t i = 0; i < cells; i++) {
        l->other[i] = -1;
        l->dist[i] = FLT_MAX;
    }
    l->tries = l->created = 0;
    if (brute) {
        for (uint32_t i = 0; i < h->elem_count; i++)
            for (uint32_t j = i + 1; j < h->elem_count; j++) {
                uint32_t A = h->elem_node[i], B = h->elem_node[j];
                gi_vec3 d = gi_v3_sub(gi_v3_load(&h->pos[3 * B]), gi_v3_load(&h->pos[3 * A]));
                float r2 = gi_v3_dot(d, d);
                l->tries++;
                if (r2 > 1e-20f)
                    insert(l, h, A, B, d, sqrtf(r2), splat);
            }
        return;
    }
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
        for (uint32_t b = 0; b < nb; b++)
            if (l->dist[p + b] < l->dist[c + b]) {
                l->dist[c + b] = l->dist[p + b];
                l->other[c + b] = l->other[p + b];
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
        size_t c = (size_t)h->elem_node[e] * nb;
        for (uint32_t b = 0; b < nb; b++) {
            int32_t o = l->other[c + b];
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

/* -------------------------------------------------- illumination (4.3) */

/* Radiance a node sends toward point x: the side its mean normal faces x;
 * a cluster whose children face every way (mean normal shorter than 0.3)
 * sends the mean of both sides. */
static void node_radiance(const iv_hier *h, const float *sp, const float *sm, uint32_t src, gi_vec3 x, float out[3])
{
    gi_vec3 ns = gi_v3_load(&h->nrm[3 * src]);
    float len2 = gi_v3_dot(ns, ns);
    if (len2 < 0.09f) {
        for (int c = 0; c < 3; c++)
            out[c] = 0.5f * (sp[3 * src + c] + sm[3 * src + c]);
        return;
    }
    const float *L = gi_v3_dot(ns, gi_v3_sub(x, gi_v3_load(&h->pos[3 * src]))) >= 0.0f ? sp : sm;
    for (int c = 0; c < 3; c++)
        out[c] = L[3 * src + c];
}

/* Area-weighted pull-up of the leaves' radiance to every node (Sec. 4.3). */
static void pull_up(const iv_hier *h, float *sp, float *sm)
{
    for (uint32_t i = h->node_count; i-- > 0;) {
        if (iv_is_leaf(h, i))
            continue;
        double a = 0.0, p[3] = {0, 0, 0}, m[3] = {0, 0, 0};
        for (uint32_t k = 0; k < h->child_count[i]; k++) {
            uint32_t c = h->first_child[i] + k;
            double w = h->area[c];
            a += w;
            for (int j = 0; j < 3; j++) {
                p[j] += w * sp[3 * c + j];
                m[j] += w * sm[3 * c + j];
            }
        }
        for (int j = 0; j < 3; j++) {
            sp[3 * i + j] = a > 0.0 ? (float)(p[j] / a) : 0.0f;
            sm[3 * i + j] = a > 0.0 ? (float)(m[j] / a) : 0.0f;
        }
    }
}

/* Adds radiance L arriving from bin b to the irradiance of the side of
 * the disc (normal n) it falls on, the bin's share of the hemisphere
 * weighted by its cosine (Eq. 5 with the linked node covering its bin). */
static void add_bin(const iv_links *l, uint32_t b, gi_vec3 n, float norm, const float L[3], double ep[3], double em[3])
{
    float w = gi_v3_dot(n, gi_v3_load(&l->bin_dir[3 * b])) * l->bin_omega[b] * norm;
    double *e = w >= 0.0f ? ep : em;
    w = fabsf(w);
    for (int c = 0; c < 3; c++)
        e[c] += (double)w * L[c];
}

/* Irradiance from the punctual lights at leaf x, each seen through the bin
 * toward it: blocked where the bin holds a link shorter than the light's
 * distance (a directional light: where the bin holds any link). */
static void punctual(const iv_links *l, const iv_hier *h, const iv_lights *li, uint32_t leaf, double ep[3], double em[3])
{
    const gi_scene *s = li->scene;
    gi_vec3 x = gi_v3_load(&h->pos[3 * leaf]), n = gi_v3_load(&h->nrm[3 * leaf]);
    size_t base = (size_t)leaf * l->bins;
    for (uint32_t i = 0; i < s->light_count; i++) {
        const gi_light *lt = &s->lights[i];
        gi_light_frame f = gi_scene_light_at(s, i, li->t);
        gi_vec3 wl;
        float scale, r = FLT_MAX;
        if (lt->type == GI_LIGHT_DIRECTIONAL) {
            wl = gi_v3_normalize(gi_v3_scale(f.direction, -1.0f));
            scale = 1.0f;
        } else {
            gi_vec3 d = gi_v3_sub(f.position, x);
            r = gi_v3_length(d);
            if (!(r > 0.0f))
                continue;
            wl = gi_v3_scale(d, 1.0f / r);
            scale = gi_range_window(r, lt->range) / (r * r);
            if (lt->type == GI_LIGHT_SPOT)
                scale *= gi_spot_falloff(-gi_v3_dot(wl, gi_v3_normalize(f.direction)), cosf(lt->inner_cone),
                                         cosf(lt->outer_cone));
        }
        size_t k = base + iv_bin_of(wl, l->n);
        if (l->other[k] >= 0 && l->dist[k] < r)
            continue;
        float c = gi_v3_dot(n, wl);
        double *e = c >= 0.0f ? ep : em;
        for (int j = 0; j < 3; j++)
            e[j] += (double)(fabsf(c) * scale * lt->intensity[j]);
    }
}

void iv_illuminate(const iv_links *l, iv_hier *h, const iv_lights *li, uint32_t bounces, float *e_out)
{
    uint32_t nn = h->node_count, ne = h->elem_count;
    float *sp = calloc((size_t)nn * 3, sizeof(float)), *sm = calloc((size_t)nn * 3, sizeof(float));
    float *norm = malloc(ne * sizeof(float));
    double *ek = malloc((size_t)ne * 6 * sizeof(double));
    if (!sp || !sm || !norm || !ek) {
        memset(e_out, 0, (size_t)ne * 6 * sizeof(float));
        free(sp), free(sm), free(norm), free(ek);
        return;
    }
    memset(e_out, 0, (size_t)ne * 6 * sizeof(float));
    /* each disc's bins, cosine-weighted, sum to pi over a hemisphere */
    for (uint32_t e = 0; e < ne; e++) {
        gi_vec3 n = gi_v3_load(&h->nrm[3 * h->elem_node[e]]);
        double s = 0.0;
        for (uint32_t b = 0; b < l->bins; b++)
            s += fabs((double)gi_v3_dot(n, gi_v3_load(&l->bin_dir[3 * b]))) * l->bin_omega[b];
        norm[e] = s > 0.0 ? (float)(2.0 * GI_PI / s) : 0.0f;
    }
    /* bounce 0: emission */
    for (uint32_t e = 0; e < ne; e++) {
        uint32_t x = h->elem_node[e];
        for (int c = 0; c < 3; c++) {
            sp[3 * x + c] = h->elem_emit[3 * e + c];
            sm[3 * x + c] = h->elem_two_sided_emit[e] ? h->elem_emit[3 * e + c] : 0.0f;
        }
    }
    pull_up(h, sp, sm);
    for (uint32_t k = 0; k <= bounces; k++) {
        int direct = k == 0;
        const uint32_t *off = direct ? l->light_off : l->leaf_off;
        const uint32_t *bin = direct ? l->light_bin : l->leaf_bin;
        const uint32_t *src = direct ? l->light_src : l->leaf_src;
        for (uint32_t e = 0; e < ne; e++) {
            uint32_t x = h->elem_node[e];
            gi_vec3 p = gi_v3_load(&h->pos[3 * x]), n = gi_v3_load(&h->nrm[3 * x]);
            double ep[3] = {0, 0, 0}, em[3] = {0, 0, 0};
            for (uint32_t j = off[e]; j < off[e + 1]; j++) {
                float L[3];
                node_radiance(h, sp, sm, src[j], p, L);
                add_bin(l, bin[j], n, norm[e], L, ep, em);
            }
            if (direct) {
                if (li->env) { /* Sec. 4.4: an empty bin sees the environment */
                    size_t base = (size_t)x * l->bins;
                    for (uint32_t b = 0; b < l->bins; b++)
                        if (l->other[base + b] < 0) {
                            float L[3];
                            gi_envmap_eval(li->env, gi_v3_load(&l->bin_dir[3 * b]), L);
                            add_bin(l, b, n, norm[e], L, ep, em);
                        }
                }
                if (li->scene && li->scene->light_count)
                    punctual(l, h, li, x, ep, em);
            }
            for (int c = 0; c < 3; c++) {
                ek[6 * e + c] = ep[c];
                ek[6 * e + 3 + c] = em[c];
            }
        }
        /* the gathered light, reflected: the next bounce's source */
        for (uint32_t e = 0; e < ne; e++) {
            uint32_t x = h->elem_node[e];
            for (int c = 0; c < 3; c++) {
                e_out[6 * e + c] += (float)ek[6 * e + c];
                e_out[6 * e + 3 + c] += (float)ek[6 * e + 3 + c];
                float rho = h->elem_albedo[3 * e + c] / (float)GI_PI;
                sp[3 * x + c] = rho * (float)ek[6 * e + c];
                sm[3 * x + c] = rho * (float)ek[6 * e + 3 + c];
            }
        }
        if (k < bounces)
            pull_up(h, sp, sm);
    }
    free(sp), free(sm), free(norm), free(ek);
}
