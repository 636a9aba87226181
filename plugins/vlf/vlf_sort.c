/* Depth order of faces along a subfield direction (paper §3.2): Newell's
 * painter's ordering with splitting, and the BSP cut orthogonal to the
 * direction. See vlf_sort.h. */
#include "vlf_sort.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { MAX_VERTS = 32, SPLIT_MAX_VERTS = 24 };

/* Lengths are in the scene's unit sphere. */
static const float EPS = 1e-6f;       /* a vertex this close to a plane lies on it */
static const float AREA_EPS = 1e-10f; /* projections overlapping less than this do not overlap */

static int grow(void **p, uint32_t *cap, uint32_t need, size_t elem)
{
    if (need <= *cap)
        return 1;
    uint32_t c = *cap ? *cap : 256;
    while (c < need)
        c *= 2;
    void *q = realloc(*p, (size_t)c * elem);
    if (!q)
        return 0;
    *p = q;
    *cap = c;
    return 1;
}

static float side(const float *pl, gi_vec3 x)
{
    return pl[0] * x.x + pl[1] * x.y + pl[2] * x.z - pl[3];
}

/* Appends a piece of triangle tri with vertices v[0 .. count); returns its
 * index or UINT32_MAX when out of memory. */
static uint32_t add_piece(vlf_sorter *s, uint32_t tri, const gi_vec3 *v, uint32_t count)
{
    if (!grow((void **)&s->vert, &s->cap_v, s->nv + count, sizeof *s->vert) ||
        !grow((void **)&s->poly, &s->cap_p, s->np + 1, sizeof *s->poly))
        return UINT32_MAX;
    uint32_t cap = s->cap_state;
    if (!grow((void **)&s->state, &cap, s->np + 1, sizeof *s->state))
        return UINT32_MAX;
    cap = s->cap_state;
    if (!grow((void **)&s->chain_pos, &cap, s->np + 1, sizeof *s->chain_pos))
        return UINT32_MAX;
    cap = s->cap_state;
    if (!grow((void **)&s->chain, &cap, s->np + 1, sizeof *s->chain))
        return UINT32_MAX;
    cap = s->cap_state;
    if (!grow((void **)&s->stamp, &cap, s->np + 1, sizeof *s->stamp))
        return UINT32_MAX;
    s->cap_state = cap;
    vlf_piece *p = &s->poly[s->np];
    p->tri = tri;
    p->first = s->nv;
    p->count = count;
    for (int k = 0; k < 3; k++)
        p->lo[k] = INFINITY, p->hi[k] = -INFINITY;
    for (uint32_t k = 0; k < count; k++) {
        gi_vec3 x = v[k];
        s->vert[s->nv++] = x;
        float c[3] = {x.x, x.y, x.z};
        for (int a = 0; a < 3; a++)
            p->lo[a] = fminf(p->lo[a], c[a]), p->hi[a] = fmaxf(p->hi[a], c[a]);
    }
    s->state[s->np] = 0;
    s->chain_pos[s->np] = -1;
    s->stamp[s->np] = 0;
    return s->np++;
}

/* Cuts piece idx by plane pl into its parts on either side; 1 with the two
 * new pieces in *a (side < 0) and *b (side > 0) if it straddles the plane,
 * 0 if it lies on one side, -1 out of memory. */
static int split_piece(vlf_sorter *s, uint32_t idx, const float *pl, uint32_t *a, uint32_t *b)
{
    vlf_piece P = s->poly[idx];
    if (P.count > SPLIT_MAX_VERTS)
        return 0;
    gi_vec3 v[MAX_VERTS];
    float d[MAX_VERTS];
    int neg = 0, pos = 0;
    for (uint32_t k = 0; k < P.count; k++) {
        v[k] = s->vert[P.first + k];
        d[k] = side(pl, v[k]);
        neg |= d[k] < -EPS;
        pos |= d[k] > EPS;
    }
    if (!neg || !pos)
        return 0;
    gi_vec3 A[MAX_VERTS], B[MAX_VERTS];
    uint32_t na = 0, nb = 0;
    for (uint32_t k = 0; k < P.count; k++) {
        uint32_t j = (k + 1) % P.count;
        float dk = fabsf(d[k]) <= EPS ? 0.0f : d[k], dj = fabsf(d[j]) <= EPS ? 0.0f : d[j];
        if (dk <= 0.0f)
            A[na++] = v[k];
        if (dk >= 0.0f)
            B[nb++] = v[k];
        if ((dk < 0.0f && dj > 0.0f) || (dk > 0.0f && dj < 0.0f)) {
            float t = dk / (dk - dj);
            gi_vec3 x = gi_v3_add(v[k], gi_v3_scale(gi_v3_sub(v[j], v[k]), t));
            A[na++] = x;
            B[nb++] = x;
        }
    }
    uint32_t ia = add_piece(s, P.tri, A, na);
    uint32_t ib = ia == UINT32_MAX ? UINT32_MAX : add_piece(s, P.tri, B, nb);
    if (ib == UINT32_MAX)
        return -1;
    s->state[idx] = 2;
    *a = ia;
    *b = ib;
    return 1;
}

/* Area and centroid of the overlap of the projections (x, y) of pieces p
 * and q: p's polygon clipped by each edge of q's (Sutherland-Hodgman).
 * Each vertex's signed distance to the edge is computed once per edge; an
 * edge with every vertex strictly outside ends the clip (nothing is left)
 * and one with none outside leaves the polygon as it is, which is what the
 * clip itself would give, in fewer steps. */
static float overlap(const vlf_sorter *s, const vlf_piece *p, const vlf_piece *q, float *cx,
                     float *cy)
{
    enum { CAP = 2 * MAX_VERTS + 8 };
    float bx[2][CAP], by[2][CAP], d[CAP];
    float *x = bx[0], *y = by[0], *ox = bx[1], *oy = by[1];
    int n = (int)p->count;
    for (int k = 0; k < n; k++)
        x[k] = s->vert[p->first + (uint32_t)k].x, y[k] = s->vert[p->first + (uint32_t)k].y;
    const gi_vec3 *Q = s->vert + q->first;
    int m = (int)q->count;
    float orient = 0.0f;
    for (int k = 0; k < m; k++) {
        int j = (k + 1) % m;
        orient += Q[k].x * Q[j].y - Q[j].x * Q[k].y;
    }
    if (fabsf(orient) < 2.0f * AREA_EPS)
        return 0.0f;
    orient = orient > 0.0f ? 1.0f : -1.0f;
    for (int e = 0; e < m && n > 0; e++) {
        gi_vec3 e0 = Q[e], e1 = Q[(e + 1) % m];
        float ex = e1.x - e0.x, ey = e1.y - e0.y;
        int inside = 0, outside = 0;
        for (int k = 0; k < n; k++) {
            d[k] = orient * (ex * (y[k] - e0.y) - ey * (x[k] - e0.x));
            inside += d[k] >= 0.0f;
            outside += d[k] < 0.0f;
        }
        if (outside == n) {
            n = 0;
            break;
        }
        if (inside == n)
            continue;
        int o = 0;
        for (int k = 0; k < n; k++) {
            int j = k + 1 == n ? 0 : k + 1;
            float dk = d[k], dj = d[j];
            if (dk >= 0.0f && o < CAP)
                ox[o] = x[k], oy[o] = y[k], o++;
            if (((dk < 0.0f && dj > 0.0f) || (dk > 0.0f && dj < 0.0f)) && o < CAP) {
                float t = dk / (dk - dj);
                ox[o] = x[k] + t * (x[j] - x[k]), oy[o] = y[k] + t * (y[j] - y[k]), o++;
            }
        }
        n = o;
        float *tx = x, *ty = y;
        x = ox, y = oy, ox = tx, oy = ty;
    }
    double a = 0.0, sx = 0.0, sy = 0.0;
    for (int k = 0; k < n; k++) {
        int j = (k + 1) % n;
        double c = (double)x[k] * y[j] - (double)x[j] * y[k];
        a += c;
        sx += ((double)x[k] + x[j]) * c;
        sy += ((double)y[k] + y[j]) * c;
    }
    if (fabs(a) < 2.0 * AREA_EPS)
        return 0.0f;
    *cx = (float)(sx / (3.0 * a));
    *cy = (float)(sy / (3.0 * a));
    return (float)fabs(0.5 * a);
}

/* 1 if piece q may lie in front of piece p somewhere along the direction
 * (a ray meets q before p), so that q must come first; Newell's tests from
 * the cheapest, ending with the exact one: the depths of both planes at a
 * point of the overlap of their projections (non-intersecting faces keep
 * one order over the whole overlap). */
static int obstructs(vlf_sorter *s, uint32_t q, uint32_t p)
{
    const vlf_piece *P = &s->poly[p], *Q = &s->poly[q];
    s->tests++;
    if (Q->lo[2] >= P->hi[2])
        return 0; /* depth ranges apart */
    if (Q->hi[0] <= P->lo[0] || Q->lo[0] >= P->hi[0] || Q->hi[1] <= P->lo[1] ||
        Q->lo[1] >= P->hi[1])
        return 0; /* projected bounds apart */
    const float *pp = s->plane + 4 * (size_t)P->tri, *pq = s->plane + 4 * (size_t)Q->tri;
    if (pp[2] > 1e-4f) { /* q entirely behind p's plane */
        uint32_t k = 0;
        while (k < Q->count && side(pp, s->vert[Q->first + k]) >= -EPS)
            k++;
        if (k == Q->count)
            return 0;
    }
    if (pq[2] > 1e-4f) { /* p entirely in front of q's plane */
        uint32_t k = 0;
        while (k < P->count && side(pq, s->vert[P->first + k]) <= EPS)
            k++;
        if (k == P->count)
            return 0;
    }
    float cx, cy;
    if (overlap(s, P, Q, &cx, &cy) < AREA_EPS)
        return 0; /* projections apart */
    if (pp[2] < 1e-6f || pq[2] < 1e-6f)
        return 0; /* edge-on: covers no area */
    float zp = (pp[3] - pp[0] * cx - pp[1] * cy) / pp[2];
    float zq = (pq[3] - pq[0] * cx - pq[1] * cy) / pq[2];
    return zq < zp - EPS;
}

/* Cell range of piece idx's projected bounds in the grid. */
static void grid_range(const vlf_sorter *s, uint32_t idx, uint32_t r[4])
{
    const vlf_piece *p = &s->poly[idx];
    float c[4] = {(p->lo[0] - s->gx0) * s->gsx, (p->lo[1] - s->gy0) * s->gsy,
                  (p->hi[0] - s->gx0) * s->gsx, (p->hi[1] - s->gy0) * s->gsy};
    for (int k = 0; k < 4; k++) {
        float v = floorf(c[k]);
        r[k] = v <= 0.0f ? 0u : v >= (float)(s->G - 1) ? s->G - 1 : (uint32_t)v;
    }
}

/* Registers piece idx in the grid cells its projection's bounds meet (in
 * the wide list if they are more than a quarter of the grid). */
static int grid_add(vlf_sorter *s, uint32_t idx)
{
    uint32_t r[4];
    grid_range(s, idx, r);
    uint64_t cells = (uint64_t)(r[2] - r[0] + 1) * (r[3] - r[1] + 1);
    if (cells * 4 > (uint64_t)s->G * s->G && cells > 4) {
        if (!grow((void **)&s->wide, &s->cap_wide, s->nwide + 1, sizeof *s->wide))
            return 0;
        s->wide[s->nwide++] = idx;
        return 1;
    }
    uint32_t cap = s->cap_node;
    if (!grow((void **)&s->node_piece, &cap, s->nnode + (uint32_t)cells, sizeof *s->node_piece))
        return 0;
    cap = s->cap_node;
    if (!grow((void **)&s->node_next, &cap, s->nnode + (uint32_t)cells, sizeof *s->node_next))
        return 0;
    s->cap_node = cap;
    for (uint32_t y = r[1]; y <= r[3]; y++)
        for (uint32_t x = r[0]; x <= r[2]; x++) {
            uint32_t c = y * s->G + x;
            s->node_piece[s->nnode] = idx;
            s->node_next[s->nnode] = s->cell_first[c];
            s->cell_first[c] = s->nnode++;
        }
    return 1;
}

/* A grid of about two pieces a cell over the projections of items. */
static int grid_build(vlf_sorter *s, const uint32_t *items, uint32_t n)
{
    float lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (uint32_t k = 0; k < n; k++)
        for (int a = 0; a < 2; a++)
            lo[a] = fminf(lo[a], s->poly[items[k]].lo[a]),
            hi[a] = fmaxf(hi[a], s->poly[items[k]].hi[a]);
    uint32_t G = (uint32_t)sqrtf((float)n * 0.5f);
    G = G < 1 ? 1 : G > 256 ? 256 : G;
    s->G = G;
    s->gx0 = lo[0], s->gy0 = lo[1];
    s->gsx = (float)G / fmaxf(hi[0] - lo[0], 1e-12f);
    s->gsy = (float)G / fmaxf(hi[1] - lo[1], 1e-12f);
    if (!grow((void **)&s->cell_first, &s->cap_cells, G * G, sizeof *s->cell_first))
        return 0;
    for (uint32_t c = 0; c < G * G; c++)
        s->cell_first[c] = UINT32_MAX;
    s->nnode = s->nwide = 0;
    for (uint32_t k = 0; k < n; k++)
        if (!grid_add(s, items[k]))
            return 0;
    return 1;
}

/* Visits a waiting piece q met by the scan for candidate cand: 1 if it
 * may lie in front of cand. */
static int scan_one(vlf_sorter *s, uint32_t q, uint32_t cand, float zmax)
{
    if (s->stamp[q] == s->scan)
        return 0;
    s->stamp[q] = s->scan;
    if (q == cand || s->state[q] != 0 || s->poly[q].lo[2] >= zmax)
        return 0;
    return obstructs(s, q, cand);
}

/* A waiting piece that may lie in front of cand, or UINT32_MAX: the pieces
 * of the grid cells cand's projection meets, and the wide ones. A piece
 * no longer waiting (placed or split; states only move away from waiting)
 * can obstruct nothing again, so the scan drops it from the wide list and
 * from each cell's list it walks (the order of the rest kept): late in a
 * sort most of the grid is placed pieces, and walking them again for every
 * candidate was most of the sort's time. */
static uint32_t find_obstruction(vlf_sorter *s, uint32_t cand)
{
    if (++s->scan == 0) {
        memset(s->stamp, 0, (size_t)s->np * sizeof *s->stamp);
        s->scan = 1;
    }
    float zmax = s->poly[cand].hi[2];
    uint32_t kept = 0, found = UINT32_MAX, k = 0;
    for (; k < s->nwide && found == UINT32_MAX; k++) {
        uint32_t q = s->wide[k];
        if (s->state[q] != 0)
            continue;
        s->wide[kept++] = q;
        if (scan_one(s, q, cand, zmax))
            found = q;
    }
    if (kept < k && k < s->nwide) /* the rest, not scanned, closes the gap */
        memmove(s->wide + kept, s->wide + k, (size_t)(s->nwide - k) * sizeof *s->wide);
    s->nwide = kept + (s->nwide - k);
    if (found != UINT32_MAX)
        return found;
    uint32_t r[4];
    grid_range(s, cand, r);
    for (uint32_t y = r[1]; y <= r[3]; y++)
        for (uint32_t x = r[0]; x <= r[2]; x++) {
            uint32_t *link = &s->cell_first[y * s->G + x];
            while (*link != UINT32_MAX) {
                uint32_t nd = *link, q = s->node_piece[nd];
                if (s->state[q] != 0) {
                    *link = s->node_next[nd];
                    continue;
                }
                if (scan_one(s, q, cand, zmax))
                    return q;
                link = &s->node_next[nd];
            }
        }
    return UINT32_MAX;
}

/* Inserts piece idx into the waiting list, kept ordered by nearest depth. */
static int list_insert(vlf_sorter *s, uint32_t idx)
{
    if (!grow((void **)&s->list, &s->cap_list, s->nlist + 1, sizeof *s->list))
        return 0;
    float z = s->poly[idx].lo[2];
    uint32_t lo = 0, hi = s->nlist;
    while (lo < hi) {
        uint32_t mid = (lo + hi) / 2;
        const vlf_piece *m = &s->poly[s->list[mid]];
        if (m->lo[2] < z || (m->lo[2] == z && s->list[mid] < idx))
            lo = mid + 1;
        else
            hi = mid;
    }
    memmove(s->list + lo + 1, s->list + lo, (size_t)(s->nlist - lo) * sizeof *s->list);
    s->list[lo] = idx;
    s->nlist++;
    return grid_add(s, idx);
}

static int emit(vlf_sorter *s, uint32_t idx)
{
    if (!grow((void **)&s->out, &s->cap_out, s->nout + 1, sizeof *s->out))
        return 0;
    s->out[s->nout++] = idx;
    s->state[idx] = 1;
    return 1;
}

/* Splits one piece of the cycle chain[start .. top] (each obstructed by the
 * next, the last by the first) by the plane of its neighbour in the cycle
 * where it straddles that plane; failing that, the widest piece of the
 * cycle is halved by a plane along the direction. 1 if a piece was split,
 * 0 if none could be, -1 out of memory. */
static int break_cycle(vlf_sorter *s, uint32_t start, uint32_t top)
{
    uint32_t len = top - start + 1;
    for (uint32_t j = 0; j < len; j++) {
        /* the closing pair first: chain[top] is obstructed by chain[start] */
        uint32_t a = s->chain[j == 0 ? top : start + j - 1],
                 b = s->chain[j == 0 ? start : start + j];
        uint32_t pa, pb;
        int r = split_piece(s, b, s->plane + 4 * (size_t)s->poly[a].tri, &pa, &pb);
        if (r == 0)
            r = split_piece(s, a, s->plane + 4 * (size_t)s->poly[b].tri, &pa, &pb);
        if (r < 0)
            return -1;
        if (r > 0)
            return list_insert(s, pa) && list_insert(s, pb) ? 1 : -1;
    }
    uint32_t widest = UINT32_MAX;
    float best = 0.0f;
    for (uint32_t j = start; j <= top; j++) {
        const vlf_piece *p = &s->poly[s->chain[j]];
        float w = fmaxf(p->hi[0] - p->lo[0], p->hi[1] - p->lo[1]);
        if (w > best && p->count <= SPLIT_MAX_VERTS)
            best = w, widest = s->chain[j];
    }
    if (widest == UINT32_MAX || best < 1e-4f)
        return 0;
    const vlf_piece *p = &s->poly[widest];
    int ax = p->hi[0] - p->lo[0] >= p->hi[1] - p->lo[1] ? 0 : 1;
    float pl[4] = {ax == 0 ? 1.0f : 0.0f, ax == 1 ? 1.0f : 0.0f, 0.0f,
                   0.5f * (p->lo[ax] + p->hi[ax])};
    uint32_t pa, pb;
    int r = split_piece(s, widest, pl, &pa, &pb);
    if (r <= 0)
        return r;
    return list_insert(s, pa) && list_insert(s, pb) ? 1 : -1;
}

typedef struct zkey {
    float z;
    uint32_t idx;
} zkey;

static int zkey_cmp(const void *a, const void *b)
{
    const zkey *x = a, *y = b;
    if (x->z != y->z)
        return x->z < y->z ? -1 : 1;
    return x->idx < y->idx ? -1 : (x->idx > y->idx);
}

/* Newell's ordering of pieces items[0 .. n), appended to s->out: the
 * waiting piece nearest in depth is the candidate; a waiting piece that may
 * lie in front of it (looked for among the pieces whose projections share
 * a grid cell with it) becomes the candidate in its place (a chain); a
 * piece met again on the chain closes a cycle, which is broken by a split. */
static int order_list(vlf_sorter *s, const uint32_t *items, uint32_t n, int mode,
                      uint32_t split_limit)
{
    zkey *keys = malloc((size_t)(n ? n : 1) * sizeof *keys);
    if (!keys || !grow((void **)&s->list, &s->cap_list, n, sizeof *s->list)) {
        free(keys);
        return -1;
    }
    for (uint32_t k = 0; k < n; k++)
        keys[k] = (zkey){s->poly[items[k]].lo[2], items[k]};
    qsort(keys, n, sizeof *keys, zkey_cmp);
    for (uint32_t k = 0; k < n; k++)
        s->list[k] = keys[k].idx;
    s->nlist = n;
    free(keys);
    if (mode != VLF_SORT_PLAIN && !grid_build(s, items, n))
        return -1;
    uint32_t head = 0, chain_len = 0;
    for (;;) {
        if (s->cancelled && (++s->polls & 1023u) == 0 && s->cancelled(s->cancel_user)) {
            s->stopped = 1;
            return -1;
        }
        while (head < s->nlist && s->state[s->list[head]] != 0)
            head++;
        if (head == s->nlist)
            break;
        if (chain_len == 0) {
            s->chain[0] = s->list[head];
            s->chain_pos[s->list[head]] = 0;
            chain_len = 1;
        }
        uint32_t cand = s->chain[chain_len - 1];
        uint32_t found = UINT32_MAX;
        if (mode != VLF_SORT_PLAIN)
            found = find_obstruction(s, cand);
        if (found == UINT32_MAX) {
            if (!emit(s, cand))
                return -1;
            s->chain_pos[cand] = -1;
            chain_len--;
            continue;
        }
        if (s->chain_pos[found] < 0) {
            s->chain_pos[found] = (int32_t)chain_len;
            s->chain[chain_len++] = found;
            continue;
        }
        /* a cycle: chain[pos(found) .. top] */
        int r = s->np < split_limit && mode == VLF_SORT_NEWELL
                    ? break_cycle(s, (uint32_t)s->chain_pos[found], chain_len - 1)
                    : 0;
        if (r < 0)
            return -1;
        if (r == 0) {
            s->unresolved++;
            if (!emit(s, cand))
                return -1;
            s->chain_pos[cand] = -1;
            chain_len--;
            continue;
        }
        s->splits++;
        for (uint32_t j = 0; j < chain_len; j++)
            s->chain_pos[s->chain[j]] = -1;
        chain_len = 0;
        head = 0;
    }
    return 0;
}

/* The BSP step: pieces items[0 .. n) cut at the depth of their centre of
 * mass (area-weighted) by a plane orthogonal to the direction, the front
 * list ordered before the back one. */
static int order_bsp(vlf_sorter *s, uint32_t *items, uint32_t n, int mode, uint32_t level,
                     uint32_t levels, uint32_t bsp_min, uint32_t split_limit)
{
    if (level >= levels || n < bsp_min || n < 2)
        return order_list(s, items, n, mode, split_limit);
    double wz = 0.0, w = 0.0;
    for (uint32_t k = 0; k < n; k++) {
        const vlf_piece *p = &s->poly[items[k]];
        const gi_vec3 *v = s->vert + p->first;
        for (uint32_t j = 1; j + 1 < p->count; j++) {
            float a =
                0.5f * gi_v3_length(gi_v3_cross(gi_v3_sub(v[j], v[0]), gi_v3_sub(v[j + 1], v[0])));
            wz += (double)a * (v[0].z + v[j].z + v[j + 1].z) / 3.0;
            w += a;
        }
    }
    if (!(w > 0.0))
        return order_list(s, items, n, mode, split_limit);
    float zc = (float)(wz / w);
    float pl[4] = {0.0f, 0.0f, 1.0f, zc};
    uint32_t *front = malloc((size_t)n * 2 * sizeof *front),
             *back = malloc((size_t)n * 2 * sizeof *back);
    if (!front || !back) {
        free(front), free(back);
        return -1;
    }
    uint32_t nf = 0, nb = 0;
    for (uint32_t k = 0; k < n; k++) {
        uint32_t idx = items[k];
        if (s->poly[idx].hi[2] <= zc + EPS) {
            front[nf++] = idx;
        } else if (s->poly[idx].lo[2] >= zc - EPS) {
            back[nb++] = idx;
        } else {
            uint32_t a, b;
            int r = split_piece(s, idx, pl, &a, &b);
            if (r < 0) {
                free(front), free(back);
                return -1;
            }
            if (r == 0) {
                if (s->poly[idx].lo[2] + s->poly[idx].hi[2] < 2.0f * zc)
                    front[nf++] = idx;
                else
                    back[nb++] = idx;
            } else {
                front[nf++] = a;
                back[nb++] = b;
                s->bsp_cuts++;
            }
        }
    }
    int rc;
    if (nf == 0 || nb == 0)
        rc = order_list(s, nf ? front : back, nf ? nf : nb, mode, split_limit);
    else
        rc = order_bsp(s, front, nf, mode, level + 1, levels, bsp_min, split_limit) == 0 &&
                     order_bsp(s, back, nb, mode, level + 1, levels, bsp_min, split_limit) == 0
                 ? 0
                 : -1;
    free(front);
    free(back);
    return rc;
}

/* The triangles in the frame as pieces 0 .. tri_count - 1 (piece k is
 * triangle k) with their planes; 0, or -1 out of memory. extra: proxy
 * planes to leave room for. */
static int load_triangles(vlf_sorter *s, const gi_vec3 *tri_p, uint32_t tri_count, gi_vec3 u,
                          gi_vec3 v, gi_vec3 n, uint32_t extra)
{
    s->nv = s->np = s->nlist = s->nout = 0;
    uint32_t cap = s->cap_plane;
    if (!grow((void **)&s->plane, &cap, (tri_count + extra) * 4 + 4, sizeof *s->plane))
        return -1;
    s->cap_plane = cap;
    for (uint32_t t = 0; t < tri_count; t++) {
        gi_vec3 q[3];
        for (int k = 0; k < 3; k++) {
            gi_vec3 p = tri_p[3 * (size_t)t + (size_t)k];
            q[k] = gi_v3(gi_v3_dot(p, u), gi_v3_dot(p, v), gi_v3_dot(p, n));
        }
        gi_vec3 c = gi_v3_cross(gi_v3_sub(q[1], q[0]), gi_v3_sub(q[2], q[0]));
        float len = gi_v3_length(c);
        float *pl = s->plane + 4 * (size_t)t;
        if (len > 0.0f) {
            c = gi_v3_scale(c, (c.z < 0.0f ? -1.0f : 1.0f) / len);
            pl[0] = c.x, pl[1] = c.y, pl[2] = c.z, pl[3] = gi_v3_dot(c, q[0]);
        } else {
            pl[0] = pl[1] = pl[2] = pl[3] = 0.0f;
        }
        if (add_piece(s, t, q, 3) == UINT32_MAX)
            return -1;
    }
    return 0;
}

enum { MAX_GROUPS = 64 };

/* The groups of the hierarchical shortcut in one frame: every group's
 * triangle count and bounding box, and the candidates (groups of at least
 * hier_min triangles but not all, at most MAX_GROUPS): which group each
 * is, whether it is isolated, its stand-in and where its own order lies
 * in s->out. */
typedef struct hier_groups {
    uint32_t G, *gcount;
    float *gb;     /* 6 per group: lower and upper corner of its box in the frame */
    int32_t *cand; /* candidate slot of each group, -1 none */
    uint32_t nc, niso;
    uint32_t gid[MAX_GROUPS], proxy[MAX_GROUPS], first_out[MAX_GROUPS], end_out[MAX_GROUPS];
    uint8_t iso[MAX_GROUPS];
} hier_groups;

/* Every group's triangle count and bounding box (pieces 0 .. tri_count - 1
 * are the triangles in the frame). */
static void group_boxes(const vlf_sorter *s, hier_groups *h, uint32_t tri_count,
                        const uint32_t *group)
{
    for (uint32_t g = 0; g < h->G; g++)
        for (int a = 0; a < 3; a++)
            h->gb[6 * g + (uint32_t)a] = INFINITY, h->gb[6 * g + 3 + (uint32_t)a] = -INFINITY;
    for (uint32_t t = 0; t < tri_count; t++) {
        const vlf_piece *p = &s->poly[t];
        float *b = h->gb + 6 * (size_t)group[t];
        h->gcount[group[t]]++;
        for (int a = 0; a < 3; a++)
            b[a] = fminf(b[a], p->lo[a]), b[3 + a] = fmaxf(b[3 + a], p->hi[a]);
    }
}

/* The candidates, isolated until shown otherwise. */
static void find_candidates(hier_groups *h, uint32_t tri_count, uint32_t hier_min)
{
    h->nc = 0;
    for (uint32_t g = 0; g < h->G; g++) {
        h->cand[g] = -1;
        if (h->gcount[g] >= hier_min && h->gcount[g] < tri_count && h->nc < MAX_GROUPS) {
            h->cand[g] = (int32_t)h->nc;
            h->gid[h->nc] = g;
            h->iso[h->nc++] = 1;
        }
    }
}

/* A candidate is isolated when no other group's triangle reaches into its
 * box; counts the isolated ones. */
static void isolate(const vlf_sorter *s, hier_groups *h, uint32_t tri_count, const uint32_t *group)
{
    for (uint32_t t = 0; t < tri_count; t++) {
        const vlf_piece *p = &s->poly[t];
        for (uint32_t c = 0; c < h->nc; c++) {
            if (!h->iso[c] || h->gid[c] == group[t])
                continue;
            const float *b = h->gb + 6 * (size_t)h->gid[c];
            int inside = 1;
            for (int a = 0; a < 3 && inside; a++)
                inside = p->lo[a] < b[3 + a] - EPS && p->hi[a] > b[a] + EPS;
            if (inside)
                h->iso[c] = 0;
        }
    }
    h->niso = 0;
    for (uint32_t c = 0; c < h->nc; c++)
        h->niso += h->iso[c];
}

/* The stand-ins: the isolated groups' front rectangles, planes z =
 * nearest depth (pieces of triangles tri_count + c). 0, or -1 out of
 * memory. */
static int add_stand_ins(vlf_sorter *s, hier_groups *h, uint32_t tri_count)
{
    for (uint32_t c = 0; c < h->nc; c++) {
        if (!h->iso[c])
            continue;
        const float *b = h->gb + 6 * (size_t)h->gid[c];
        gi_vec3 q[4] = {gi_v3(b[0], b[1], b[2]), gi_v3(b[3], b[1], b[2]), gi_v3(b[3], b[4], b[2]),
                        gi_v3(b[0], b[4], b[2])};
        float *pl = s->plane + 4 * (size_t)(tri_count + c);
        pl[0] = 0.0f, pl[1] = 0.0f, pl[2] = 1.0f, pl[3] = b[2];
        h->proxy[c] = add_piece(s, tri_count + c, q, 4);
        if (h->proxy[c] == UINT32_MAX)
            return -1;
    }
    return 0;
}

/* Each group's list spliced into the order s->out[global_first ..) at its
 * stand-in's place, the result becoming s->out. 0, 1 when a stand-in was
 * split by a cycle, -1 out of memory. */
static int splice_groups(vlf_sorter *s, const hier_groups *h, uint32_t tri_count,
                         uint32_t global_first)
{
    uint32_t *order = malloc(((size_t)s->nout + 1) * sizeof *order);
    if (!order)
        return -1;
    uint32_t no = 0;
    for (uint32_t k = global_first; k < s->nout; k++) {
        uint32_t idx = s->out[k], tri = s->poly[idx].tri;
        if (tri < tri_count) {
            order[no++] = idx;
            continue;
        }
        uint32_t c = tri - tri_count;
        if (idx != h->proxy[c]) {
            free(order);
            return 1; /* the stand-in was split by a cycle */
        }
        for (uint32_t j = h->first_out[c]; j < h->end_out[c]; j++)
            order[no++] = s->out[j];
    }
    memcpy(s->out, order, (size_t)no * sizeof *order);
    s->nout = no;
    s->groups += h->niso;
    free(order);
    return 0;
}

/* The hierarchical shortcut of §3.2: "objects enclosed by a bounding volume
 * not intersected by any other object in the scene can be taken out of the
 * scene and sorted separately", the volume sorted in their place, their
 * list inserted at its position. The volume is the group's bounding box in
 * this subfield's frame; no other triangle's bounds may reach into it
 * (a conservative test). Its front face, the rectangle at its nearest depth,
 * stands in the global order for it: any piece outside the box that
 * overlaps it in projection lies wholly in front of its front face or
 * wholly behind its back face there, so it is ordered against the
 * rectangle as against every triangle of the group. Returns 0 (s->out is
 * the order), 1 when the shortcut does not apply or a stand-in was split by
 * a cycle (the caller sorts without it), -1 out of memory. */
static int sort_hier(vlf_sorter *s, const gi_vec3 *tri_p, uint32_t tri_count, const uint32_t *group,
                     uint32_t hier_min, gi_vec3 u, gi_vec3 v, gi_vec3 n, int mode,
                     uint32_t bsp_levels, uint32_t bsp_min)
{
    hier_groups h;
    h.G = 0;
    for (uint32_t t = 0; t < tri_count; t++)
        if (group[t] + 1 > h.G)
            h.G = group[t] + 1;
    h.gcount = calloc((size_t)h.G + 1, sizeof *h.gcount);
    h.gb = malloc(((size_t)h.G + 1) * 6 * sizeof *h.gb);
    h.cand = malloc(((size_t)h.G + 1) * sizeof *h.cand);
    uint32_t *items = malloc(((size_t)tri_count + MAX_GROUPS + 1) * sizeof *items);
    int rc = -1;
    if (!h.gcount || !h.gb || !h.cand || !items)
        goto done;
    if (load_triangles(s, tri_p, tri_count, u, v, n, MAX_GROUPS) != 0)
        goto done;
    group_boxes(s, &h, tri_count, group);
    find_candidates(&h, tri_count, hier_min);
    rc = 1;
    if (h.nc == 0)
        goto done;
    isolate(s, &h, tri_count, group);
    if (h.niso == 0)
        goto done;
    rc = -1;
    if (add_stand_ins(s, &h, tri_count) != 0)
        goto done;
    uint32_t split_limit = tri_count > UINT32_MAX / 8 - 4096 ? UINT32_MAX : 8 * tri_count + 4096;
    /* each isolated group on its own */
    for (uint32_t c = 0; c < h.nc; c++) {
        if (!h.iso[c])
            continue;
        uint32_t ni = 0;
        for (uint32_t t = 0; t < tri_count; t++)
            if (group[t] == h.gid[c])
                items[ni++] = t;
        h.first_out[c] = s->nout;
        if (order_bsp(s, items, ni, mode, 0, bsp_levels, bsp_min ? bsp_min : 2, split_limit) != 0)
            goto done;
        h.end_out[c] = s->nout;
    }
    /* the rest with the stand-ins */
    uint32_t ni = 0;
    for (uint32_t t = 0; t < tri_count; t++)
        if (h.cand[group[t]] < 0 || !h.iso[h.cand[group[t]]])
            items[ni++] = t;
    for (uint32_t c = 0; c < h.nc; c++)
        if (h.iso[c])
            items[ni++] = h.proxy[c];
    uint32_t global_first = s->nout;
    if (order_bsp(s, items, ni, mode, 0, bsp_levels, bsp_min ? bsp_min : 2, split_limit) != 0)
        goto done;
    rc = splice_groups(s, &h, tri_count, global_first);
done:
    free(h.gcount), free(h.gb), free(h.cand), free(items);
    return rc;
}

gi_result vlf_sort_faces(vlf_sorter *s, const gi_vec3 *tri_p, uint32_t tri_count,
                         const uint32_t *group, uint32_t hier_min, gi_vec3 u, gi_vec3 v, gi_vec3 n,
                         int mode, uint32_t bsp_levels, uint32_t bsp_min)
{
    s->tests = 0;
    s->splits = s->bsp_cuts = s->unresolved = 0;
    s->groups = s->hier_fallbacks = 0;
    s->stopped = 0;
    if (group && hier_min > 0) {
        int r = sort_hier(s, tri_p, tri_count, group, hier_min, u, v, n, mode, bsp_levels, bsp_min);
        if (r <= 0)
            return r == 0 ? GI_OK : s->stopped ? GI_ERR_CANCELLED : GI_ERR_OUT_OF_MEMORY;
        if (s->nout > 0) /* it ran and a stand-in was split: again without the shortcut */
            s->hier_fallbacks++;
        s->tests = 0;
        s->splits = s->bsp_cuts = s->unresolved = 0;
        s->groups = 0;
    }
    if (load_triangles(s, tri_p, tri_count, u, v, n, 0) != 0)
        return GI_ERR_OUT_OF_MEMORY;
    uint32_t *items = malloc((size_t)(tri_count ? tri_count : 1) * sizeof *items);
    if (!items)
        return GI_ERR_OUT_OF_MEMORY;
    for (uint32_t t = 0; t < tri_count; t++)
        items[t] = t;
    /* splitting stops at 8 pieces per triangle on average (cycles then
     * stay, counted in unresolved) */
    uint32_t split_limit = tri_count > UINT32_MAX / 8 - 4096 ? UINT32_MAX : 8 * tri_count + 4096;
    int rc =
        order_bsp(s, items, tri_count, mode, 0, bsp_levels, bsp_min ? bsp_min : 2, split_limit);
    free(items);
    return rc == 0 ? GI_OK : s->stopped ? GI_ERR_CANCELLED : GI_ERR_OUT_OF_MEMORY;
}

void vlf_sorter_free(vlf_sorter *s)
{
    free(s->vert);
    free(s->poly);
    free(s->plane);
    free(s->list);
    free(s->out);
    free(s->chain_pos);
    free(s->chain);
    free(s->state);
    free(s->stamp);
    free(s->cell_first);
    free(s->node_piece);
    free(s->node_next);
    free(s->wide);
    memset(s, 0, sizeof *s);
}
