/* The implicit_vis method's CPU side: surface elements and their hierarchy
 * (Sec. 4.1, 4.2.1), cube-map bins and hierarchical links with implicit
 * visibility (Sec. 4.2.2-4.2.4), gathering along the links (Sec. 4.3, 4.4).
 * See iv.h. */
#include "iv.h"

#include "gi/lights.h"
#include "gi/mesh.h"
#include "gi/algo/remesh.h"

#include <float.h>
#include <pthread.h>
#include <stdatomic.h>
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
    int col = (int)floorf((u + 1.0f) * 0.5f * (float)n),
        row = (int)floorf((v + 1.0f) * 0.5f * (float)n);
    col = col < 0 ? 0 : (col >= (int)n ? (int)n - 1 : col);
    row = row < 0 ? 0 : (row >= (int)n ? (int)n - 1 : row);
    return face * n * n + (uint32_t)row * n + (uint32_t)col;
}

/* Face, and the texel's square [u0, u1] x [v0, v1] on it. */
static void bin_square(uint32_t b, uint32_t n, uint32_t *face, float *u0, float *u1, float *v0,
                       float *v1)
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

static double texel_f(double x, double y)
{
    return atan2(x * y, sqrt(x * x + y * y + 1.0));
}

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

/* Subdivision of triangle t: its longest rest edge over the target edge
 * length, rounded up (1: the triangle as it is). */
static uint32_t tri_k(const gi_scene *s, uint32_t t, float target)
{
    if (!(target > 0.0f))
        return 1;
    gi_vec3 p[3];
    gi_scene_triangle_world(s, t, 0.0f, p);
    float e = 0.0f;
    for (int i = 0; i < 3; i++)
        e = fmaxf(e, gi_v3_length(gi_v3_sub(p[(i + 1) % 3], p[i])));
    float k = ceilf(e / target);
    return k < 1.0f ? 1u : (k > (float)IV_MAX_K ? IV_MAX_K : (uint32_t)k);
}

/* Rest position and normal (object-local) of a point of triangle t. */
static void rest_point(const gi_scene *s, uint32_t t, float b1, float b2, float p[3], gi_vec3 *n)
{
    const gi_vertex *v0 = &s->vertices[s->indices[3 * t]],
                    *v1 = &s->vertices[s->indices[3 * t + 1]],
                    *v2 = &s->vertices[s->indices[3 * t + 2]];
    float b0 = 1.0f - b1 - b2;
    for (int c = 0; c < 3; c++)
        p[c] = b0 * v0->position[c] + b1 * v1->position[c] + b2 * v2->position[c];
    *n = gi_v3_normalize(gi_v3_add(gi_v3_scale(gi_v3_load(v0->normal), b0),
                                   gi_v3_add(gi_v3_scale(gi_v3_load(v1->normal), b1),
                                             gi_v3_scale(gi_v3_load(v2->normal), b2))));
}

/* Hash of a quantised position cell. */
static uint64_t cell_hash(int64_t x, int64_t y, int64_t z, uint32_t object)
{
    uint64_t h = (uint64_t)x * 0x9E3779B97F4A7C15ull ^ (uint64_t)y * 0xC2B2AE3D27D4EB4Full ^
                 (uint64_t)z * 0x165667B19E3779F9ull ^ (uint64_t)object * 0x27D4EB2F165667C5ull;
    return h ^ (h >> 29);
}

/* Merging of points equal in position (within q per axis, the cells
 * around included) and normal (cos > 0.95) under one key (the object):
 * ids 0.. are added in order; pos, nrm, key are read per id. */
typedef struct welder {
    uint32_t hsize;
    int64_t *head, *next;
    double q;
    const float *pos, *nrm;
    const uint32_t *key;
} welder;

static int welder_init(welder *w, uint32_t n, double q, const float *pos, const float *nrm,
                       const uint32_t *key)
{
    w->hsize = 1;
    while (w->hsize < 2 * n)
        w->hsize <<= 1;
    w->head = malloc((size_t)w->hsize * sizeof *w->head);
    w->next = malloc(((size_t)n + 1) * sizeof *w->next);
    w->q = q;
    w->pos = pos, w->nrm = nrm, w->key = key;
    if (!w->head || !w->next)
        return 0;
    for (uint32_t i = 0; i < w->hsize; i++)
        w->head[i] = -1;
    return 1;
}

static void welder_free(welder *w)
{
    free(w->head), free(w->next);
}

/* The id merged with point (p, n, key), or the new id `fresh` added. */
static uint32_t welder_find_or_add(welder *w, const float p[3], gi_vec3 n, uint32_t key,
                                   uint32_t fresh)
{
    double q = w->q;
    int64_t cx = (int64_t)floor(p[0] / q), cy = (int64_t)floor(p[1] / q),
            cz = (int64_t)floor(p[2] / q);
    for (int dz = -1; dz <= 1; dz++)
        for (int dy = -1; dy <= 1; dy++)
            for (int dx = -1; dx <= 1; dx++) {
                uint64_t hh = cell_hash(cx + dx, cy + dy, cz + dz, key) & (w->hsize - 1);
                for (int64_t e = w->head[hh]; e >= 0; e = w->next[e]) {
                    const float *pr = &w->pos[3 * e];
                    if (w->key[e] == key && fabs(pr[0] - p[0]) <= q && fabs(pr[1] - p[1]) <= q &&
                        fabs(pr[2] - p[2]) <= q && gi_v3_dot(gi_v3_load(&w->nrm[3 * e]), n) > 0.95f)
                        return (uint32_t)e;
                }
            }
    uint64_t hh = cell_hash(cx, cy, cz, key) & (w->hsize - 1);
    w->next[fresh] = w->head[hh];
    w->head[hh] = fresh;
    return fresh;
}

static double weld_quantum(const gi_scene *s)
{
    float ext = 0.0f;
    for (int c = 0; c < 3; c++)
        ext = fmaxf(ext, s->bounds[3 + c] - s->bounds[c]);
    return 1e-5 * (ext > 0.0f ? ext : 1.0f);
}

/* Without re-meshing or with the grid: every point of each triangle's
 * k x k grid (k = 1: its corners) is a surface point, the sub-triangles
 * the surface, and the display grid the points themselves. */
static int samples_grid(iv_hier *h, const gi_scene *s, float target)
{
    uint32_t nt = s->triangle_count;
    uint64_t total = 0, subs = 0;
    for (uint32_t t = 0; t < nt; t++) {
        h->tri_k[t] = tri_k(s, t, target);
        h->tri_grid[t] = (uint32_t)total;
        uint64_t k = h->tri_k[t];
        total += (k + 1) * (k + 2) / 2;
        subs += k * k;
        if (total > IV_MAX_SAMPLES)
            return -1;
    }
    h->tri_grid[nt] = (uint32_t)total;
    h->sample_count = h->disp_count = (uint32_t)total;
    h->surf_count = (uint32_t)subs;
    uint32_t ns = h->sample_count;
    h->samp_tri = malloc((ns + 1) * sizeof *h->samp_tri);
    h->samp_b = malloc(((size_t)ns * 2 + 1) * sizeof *h->samp_b);
    h->surf_tri = malloc(((size_t)subs * 3 + 1) * sizeof *h->surf_tri);
    h->disp_elem = malloc(((size_t)ns * 3 + 1) * sizeof *h->disp_elem);
    h->disp_w = malloc(((size_t)ns * 3 + 1) * sizeof *h->disp_w);
    if (!h->samp_tri || !h->samp_b || !h->surf_tri || !h->disp_elem || !h->disp_w)
        return 0;
    size_t st = 0;
    for (uint32_t t = 0; t < nt; t++) {
        uint32_t k = h->tri_k[t], base = h->tri_grid[t];
        for (uint32_t j = 0; j <= k; j++)
            for (uint32_t i = 0; i + j <= k; i++) {
                uint32_t si = base + iv_grid_index(k, i, j);
                h->samp_tri[si] = t;
                h->samp_b[2 * si] = (float)i / (float)k;
                h->samp_b[2 * si + 1] = (float)j / (float)k;
                for (int c = 0; c < 3; c++) {
                    h->disp_elem[3 * si + c] =
                        si; /* the point itself (mapped to its element later) */
                    h->disp_w[3 * si + c] = c == 0 ? 1.0f : 0.0f;
                }
                if (i + j + 1 <= k) { /* lower sub-triangle (i,j) (i+1,j) (i,j+1) */
                    uint32_t *o = &h->surf_tri[3 * st++];
                    o[0] = si, o[1] = base + iv_grid_index(k, i + 1, j),
                    o[2] = base + iv_grid_index(k, i, j + 1);
                }
                if (i + j + 2 <= k) { /* upper sub-triangle (i+1,j) (i+1,j+1) (i,j+1) */
                    uint32_t *o = &h->surf_tri[3 * st++];
                    o[0] = base + iv_grid_index(k, i + 1, j),
                    o[1] = base + iv_grid_index(k, i + 1, j + 1);
                    o[2] = base + iv_grid_index(k, i, j + 1);
                }
            }
    }
    return 1;
}

/* Uniform scale of object o at t = 0 (cube root of its transform's
 * determinant), to turn a world edge length into the object's units. */
static float object_scale(const gi_scene *s, uint32_t o)
{
    float m[16];
    gi_scene_object_transform(s, o, 0.0f, m);
    double det = (double)m[0] * ((double)m[5] * m[10] - (double)m[6] * m[9]) -
                 (double)m[4] * ((double)m[1] * m[10] - (double)m[2] * m[9]) +
                 (double)m[8] * ((double)m[1] * m[6] - (double)m[2] * m[5]);
    double sc = cbrt(fabs(det));
    return sc > 1e-12 ? (float)sc : 1.0f;
}

static const uint32_t *g_group_key; /* keys the comparator reads */

static int cmp_group(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    uint32_t kx = g_group_key[x], ky = g_group_key[y];
    return kx != ky ? (kx < ky ? -1 : 1) : (x < y ? -1 : (x > y));
}

/* Isotropic re-meshing (Sec. 5.1) by CGAL, per object and material (an
 * emitter keeps its outline). Each patch is welded by position and
 * normal, so that a hard edge is a border, which keeps its vertices. The
 * new vertices are the surface points, each on the original triangle CGAL
 * projected it to; the display grid of every original triangle is located
 * on the re-meshed surface (triangle, barycentric weights). */
static int samples_isotropic(iv_hier *h, const gi_scene *s, float target, gi_error *err)
{
    uint32_t nt = s->triangle_count;
    int ok = 0;
    uint32_t *order = malloc((nt + 1) * sizeof *order), *key = malloc((nt + 1) * sizeof *key);
    gi_remeshed **rm =
        calloc(nt + 1, sizeof *rm); /* per patch, indexed by its first triangle in `order` */
    float *lp = malloc(((size_t)nt * 9 + 1) * sizeof(float)),
          *ln = malloc(((size_t)nt * 9 + 1) * sizeof(float));
    uint32_t *lk = calloc((size_t)nt * 3 + 1, sizeof *lk),
             *lidx = malloc(((size_t)nt * 3 + 1) * sizeof *lidx);
    float *query = NULL, *qb = NULL;
    uint32_t *qf = NULL;
    welder w = {0};
    if (!order || !key || !rm || !lp || !ln || !lk || !lidx)
        goto done;
    uint64_t disp = 0;
    for (uint32_t t = 0; t < nt; t++) {
        order[t] = t;
        key[t] = s->vertices[s->indices[3 * t]].object * (s->material_count + 1) +
                 s->vertices[s->indices[3 * t]].material;
        h->tri_k[t] = tri_k(s, t, target);
        h->tri_grid[t] = (uint32_t)disp;
        disp += (uint64_t)(h->tri_k[t] + 1) * (h->tri_k[t] + 2) / 2;
        if (disp > IV_MAX_SAMPLES) {
            ok = -1;
            goto done;
        }
    }
    h->tri_grid[nt] = (uint32_t)disp;
    h->disp_count = (uint32_t)disp;
    /* refused before CGAL runs: about one vertex per two equilateral
     * triangles of the target edge (area sqrt(3)/4 e^2) */
    double area = 0.0;
    for (uint32_t t = 0; t < nt; t++) {
        gi_vec3 c[3];
        gi_scene_triangle_world(s, t, 0.0f, c);
        area += 0.5 * gi_v3_length(gi_v3_cross(gi_v3_sub(c[1], c[0]), gi_v3_sub(c[2], c[0])));
    }
    if (area / (0.866 * (double)target * (double)target) > (double)IV_MAX_SAMPLES) {
        ok = -1;
        goto done;
    }
    g_group_key = key;
    qsort(order, nt, sizeof *order, cmp_group);
    double q = weld_quantum(s);
    uint64_t total = 0, surf = 0;
    for (uint32_t a = 0, b; a < nt; a = b) {
        for (b = a; b < nt && key[order[b]] == key[order[a]]; b++)
            ;
        /* the patch's corners welded (object-local rest pose) */
        welder_free(&w);
        memset(&w, 0, sizeof w);
        if (!welder_init(&w, 3 * (b - a), q, lp, ln, lk))
            goto done;
        uint32_t nv = 0;
        for (uint32_t i = a; i < b; i++)
            for (int c = 0; c < 3; c++) {
                const gi_vertex *v = &s->vertices[s->indices[3 * order[i] + c]];
                memcpy(&lp[3 * nv], v->position, 3 * sizeof(float));
                memcpy(&ln[3 * nv], v->normal, 3 * sizeof(float));
                gi_vec3 n = gi_v3_normalize(gi_v3_load(v->normal));
                uint32_t id = welder_find_or_add(&w, v->position, n, 0, nv);
                nv += id == nv;
                lidx[3 * (i - a) + (uint32_t)c] = id;
            }
        uint32_t obj = s->vertices[s->indices[3 * order[a]]].object;
        rm[a] = gi_remesh_isotropic(lp, nv, lidx, b - a, target / object_scale(s, obj),
                                    IV_REMESH_ITERATIONS, err);
        if (!rm[a]) {
            ok = -2;
            goto done;
        }
        total += rm[a]->vertex_count;
        surf += rm[a]->triangle_count;
        if (total > IV_MAX_SAMPLES) {
            ok = -1;
            goto done;
        }
    }
    h->sample_count = (uint32_t)total;
    h->surf_count = (uint32_t)surf;
    h->samp_tri = malloc((total + 1) * sizeof *h->samp_tri);
    h->samp_b = malloc((total * 2 + 1) * sizeof *h->samp_b);
    h->surf_tri = malloc((surf * 3 + 1) * sizeof *h->surf_tri);
    h->disp_elem = malloc((disp * 3 + 1) * sizeof *h->disp_elem);
    h->disp_w = malloc((disp * 3 + 1) * sizeof *h->disp_w);
    uint32_t maxq = 0;
    for (uint32_t t = 0; t < nt; t++)
        maxq =
            h->tri_grid[t + 1] - h->tri_grid[t] > maxq ? h->tri_grid[t + 1] - h->tri_grid[t] : maxq;
    if (!h->samp_tri || !h->samp_b || !h->surf_tri || !h->disp_elem || !h->disp_w)
        goto done;
    uint32_t base = 0, sbase = 0;
    for (uint32_t a = 0, b; a < nt; a = b) {
        for (b = a; b < nt && key[order[b]] == key[order[a]]; b++)
            ;
        const gi_remeshed *r = rm[a];
        for (uint32_t v = 0; v < r->vertex_count; v++) {
            h->samp_tri[base + v] = order[a + r->face[v]];
            h->samp_b[2 * (base + v)] = r->bary[3 * v + 1];
            h->samp_b[2 * (base + v) + 1] = r->bary[3 * v + 2];
        }
        for (uint32_t f = 0; f < 3 * r->triangle_count; f++)
            h->surf_tri[3 * (size_t)sbase + f] = base + r->indices[f];
        /* the display grid of each of the patch's triangles, on the re-meshed surface */
        uint32_t nq = 0;
        for (uint32_t i = a; i < b; i++)
            nq += h->tri_grid[order[i] + 1] - h->tri_grid[order[i]];
        free(query), free(qb), free(qf);
        query = malloc(((size_t)nq * 3 + 1) * sizeof(float));
        qb = malloc(((size_t)nq * 3 + 1) * sizeof(float));
        qf = malloc(((size_t)nq + 1) * sizeof *qf);
        if (!query || !qb || !qf)
            goto done;
        uint32_t qi = 0;
        for (uint32_t i = a; i < b; i++) {
            uint32_t t = order[i], k = h->tri_k[t];
            for (uint32_t j = 0; j <= k; j++)
                for (uint32_t ii = 0; ii + j <= k; ii++) {
                    gi_vec3 n;
                    rest_point(s, t, (float)ii / (float)k, (float)j / (float)k, &query[3 * qi++],
                               &n);
                }
        }
        if (gi_mesh_locate(r->positions, r->vertex_count, r->indices, r->triangle_count, query, nq,
                           qf, qb, err) != GI_OK) {
            ok = -2;
            goto done;
        }
        qi = 0;
        for (uint32_t i = a; i < b; i++) {
            uint32_t t = order[i];
            for (uint32_t d = h->tri_grid[t]; d < h->tri_grid[t + 1]; d++, qi++)
                for (int c = 0; c < 3; c++) {
                    h->disp_elem[3 * d + c] =
                        base + r->indices[3 * qf[qi] + c]; /* a point (mapped later) */
                    h->disp_w[3 * d + c] = qb[3 * qi + c];
                }
        }
        base += r->vertex_count;
        sbase += r->triangle_count;
    }
    ok = 1;
done:
    if (rm)
        for (uint32_t i = 0; i < nt; i++)
            gi_remeshed_free(rm[i]);
    welder_free(&w);
    free(order), free(key), free(rm), free(lp), free(ln), free(lk), free(lidx), free(query),
        free(qb), free(qf);
    return ok;
}

/* The surface points as discs (Sec. 4.1). Points of one object at one
 * rest position (within 1e-5 of the scene's size) whose normals agree
 * (cos > 0.95) are one element; a hard edge keeps two. Returns 1, 0 (out
 * of memory), -1 (too many points), -2 (re-meshing failed, err set). */
static int make_elements(iv_hier *h, const gi_scene *s, float target, int remesher, gi_error *err)
{
    uint32_t nt = s->triangle_count;
    h->tri_k = malloc((nt + 1) * sizeof *h->tri_k);
    h->tri_grid = malloc((nt + 1) * sizeof *h->tri_grid);
    if (!h->tri_k || !h->tri_grid)
        return 0;
    int r = target > 0.0f && remesher == IV_REMESH_ISOTROPIC ? samples_isotropic(h, s, target, err)
                                                             : samples_grid(h, s, target);
    if (r != 1)
        return r;
    uint32_t ns = h->sample_count;
    h->samp_elem = malloc((ns + 1) * sizeof *h->samp_elem);
    h->elem_rep = malloc((ns + 1) * sizeof *h->elem_rep);
    float *rest = malloc(((size_t)ns * 3 + 1) * sizeof(float));
    float *rn = malloc(((size_t)ns * 3 + 1) * sizeof(float));
    float *albedo_sum = calloc((size_t)ns * 3 + 1, sizeof(float));
    float *emit = calloc((size_t)ns * 3 + 1, sizeof(float));
    float *ep = malloc(((size_t)ns * 3 + 1) * sizeof(float)),
          *en = malloc(((size_t)ns * 3 + 1) * sizeof(float));
    uint32_t *ek = malloc(((size_t)ns + 1) * sizeof *ek);
    uint8_t *two = calloc(ns + 1, 1);
    uint32_t *count = calloc(ns + 1, sizeof *count);
    welder w = {0};
    int ok = h->samp_elem && h->elem_rep && rest && rn && albedo_sum && emit && ep && en && ek &&
             two && count && welder_init(&w, ns, weld_quantum(s), ep, en, ek);
    if (!ok)
        goto done;
    uint32_t ne = 0;
    for (uint32_t si = 0; si < ns; si++) {
        uint32_t t = h->samp_tri[si];
        float b1 = h->samp_b[2 * si], b2 = h->samp_b[2 * si + 1];
        uint32_t obj = s->vertices[s->indices[3 * t]].object,
                 mat = s->vertices[s->indices[3 * t]].material;
        const gi_material *m = &s->materials[mat];
        gi_vec3 n;
        rest_point(s, t, b1, b2, &rest[3 * si], &n);
        gi_v3_store(n, &rn[3 * si]);
        memcpy(&ep[3 * ne], &rest[3 * si], 3 * sizeof(float));
        gi_v3_store(n, &en[3 * ne]);
        ek[ne] = obj;
        uint32_t found = welder_find_or_add(&w, &rest[3 * si], n, obj, ne);
        if (found == ne)
            h->elem_rep[ne++] = si;
        h->samp_elem[si] = found;
        float uv[2];
        const gi_vertex *v0 = &s->vertices[s->indices[3 * t]],
                        *v1 = &s->vertices[s->indices[3 * t + 1]],
                        *v2 = &s->vertices[s->indices[3 * t + 2]];
        for (int c = 0; c < 2; c++)
            uv[c] = (1.0f - b1 - b2) * v0->uv[c] + b1 * v1->uv[c] + b2 * v2->uv[c];
        float al[3];
        gi_scene_albedo(s, mat, uv, al);
        for (int c = 0; c < 3; c++) {
            albedo_sum[3 * found + c] += al[c];
            emit[3 * found + c] = fmaxf(emit[3 * found + c], m->emission[c]);
        }
        two[found] |= (uint8_t)(m->double_sided != 0);
        count[found]++;
    }
    for (uint32_t e = 0; e < ne; e++)
        for (int c = 0; c < 3; c++)
            albedo_sum[3 * e + c] /= (float)count[e];
    for (size_t d = 0; d < (size_t)h->disp_count * 3; d++)
        h->disp_elem[d] = h->samp_elem[h->disp_elem[d]];
    h->elem_count = ne;
    h->elem_albedo = albedo_sum;
    h->elem_emit = emit;
    h->elem_two_sided_emit = two;
    h->rest = rest;
    albedo_sum = emit = rest = NULL;
    two = NULL;
    ok = ne > 0;
done:
    welder_free(&w);
    free(rn), free(albedo_sum), free(emit), free(two), free(count), free(rest), free(ep), free(en),
        free(ek);
    return ok;
}

/* ------------------------------------------------------ hierarchy (4.1) */

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
    int ok = uf && rest && perm && seg && lo && hi && h->first_child && h->child_count &&
             h->parent && h->node_elem && h->elem_node && lvl;
    if (ok) {
        for (uint32_t e = 0; e < ne; e++) {
            uf[e] = e;
            /* objects never share elements: each tree holds one object's */
            memcpy(&rest[3 * e], &h->rest[3 * h->elem_rep[e]], 3 * sizeof(float));
        }
        for (uint32_t t = 0; t < h->surf_count;
             t++) /* the surface's edges join its points' elements */
            for (int c = 0; c < 2; c++) {
                uint32_t a = uf_find(uf, h->samp_elem[h->surf_tri[3 * t + c]]);
                uint32_t b = uf_find(uf, h->samp_elem[h->surf_tri[3 * t + c + 1]]);
                if (a != b)
                    uf[b] = a;
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
                    float mn[3] = {FLT_MAX, FLT_MAX, FLT_MAX},
                          mx[3] = {-FLT_MAX, -FLT_MAX, -FLT_MAX};
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

iv_hier *iv_hier_create(const gi_scene *s, float target_edge, int remesher, gi_error *err)
{
    iv_hier *h = calloc(1, sizeof *h);
    int made = h && s->triangle_count > 0 ? make_elements(h, s, target_edge, remesher, err) : 0;
    if (made == -2) { /* err set by the re-meshing */
        iv_hier_free(h);
        return NULL;
    }
    if (made < 0) {
        gi_error_set(err, GI_ERR_UNSUPPORTED,
                     "implicit_vis: re-meshing to edge length %g gives more than %u surface "
                     "points: raise it",
                     target_edge, (unsigned)IV_MAX_SAMPLES);
        iv_hier_free(h);
        return NULL;
    }
    if (!made || !build_tree(h, s)) {
        gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                     "implicit_vis: cannot build the surface elements and their hierarchy (%s)",
                     s->triangle_count == 0 ? "no triangles" : "out of memory");
        iv_hier_free(h);
        return NULL;
    }
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
    if (!h->pos || !h->nrm || !h->area || !h->spos || !h->verts || !h->wpos || !h->wnrm) {
        gi_error_set(err, GI_ERR_OUT_OF_MEMORY,
                     "implicit_vis: out of memory for %u hierarchy nodes", h->node_count);
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
    l->cover = malloc(cells * sizeof *l->cover);
    l->bin_dir = malloc((size_t)l->bins * 3 * sizeof(float));
    l->bin_omega = malloc(l->bins * sizeof(float));
    l->leaf_off = calloc((size_t)h->elem_count + 1, sizeof *l->leaf_off);
    l->light_off = calloc((size_t)h->elem_count + 1, sizeof *l->light_off);
    if (!l->other || !l->dist || !l->cover || !l->bin_dir || !l->bin_omega || !l->leaf_off ||
        !l->light_off) {
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
    free(l->other), free(l->dist), free(l->cover), free(l->bin_dir), free(l->bin_omega);
    free(l->leaf_off), free(l->leaf_bin), free(l->leaf_src);
    free(l->light_off), free(l->light_bin), free(l->light_src);
    free(l);
}

/* Writes node B into bin b of node A where it is nearer than what the bin
 * holds (the implicit visibility), and adds its solid angle `omega` to the
 * bin's coverage. */
static void put(iv_links *l, uint32_t A, uint32_t b, uint32_t B, float r, float omega)
{
    size_t i = (size_t)A * l->bins + b;
    l->cover[i] += omega;
    if (r < l->dist[i]) {
        l->dist[i] = r;
        l->other[i] = (int32_t)B;
        l->created++;
    }
}

/* The link to B in the (up to) four bins of A around direction d, each
 * with its bilinear share of B's solid angle (texel-centre interpolation
 * on d's cube face): a node between bins covers part of each. */
static void put_bilinear(iv_links *l, uint32_t A, gi_vec3 d, uint32_t B, float r, float omega)
{
    float a[3] = {d.x, d.y, d.z};
    int ax = 0;
    if (fabsf(a[1]) > fabsf(a[ax]))
        ax = 1;
    if (fabsf(a[2]) > fabsf(a[ax]))
        ax = 2;
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
static void put_side(iv_links *l, const iv_hier *h, uint32_t A, uint32_t B, gi_vec3 d, float r,
                     int splat)
{
    uint32_t b = iv_bin_of(d, l->n);
    float cover = h->area[B] / (r * r) / l->bin_omega[b];
    /* B's solid angle seen from A: its area foreshortened by its mean
     * normal; a cluster whose discs face many ways (short mean normal)
     * shows more than its mean normal says */
    gi_vec3 n = gi_v3_load(&h->nrm[3 * B]);
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
                put(l, A, iv_bin_of(dq, l->n), B, rq, omega / (float)inside);
        }
}

/* Stores the link A-B in A's bin toward B and B's bin toward A. */
static void insert(iv_links *l, const iv_hier *h, uint32_t A, uint32_t B, gi_vec3 d, float r,
                   int splat)
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

/* What Sec. 4.2.2 does with the pair (A, B): nothing, link them, or try
 * B's children, or A's. Depends on the geometry only, never on the links
 * made so far, so pairs can be enumerated in any order or in parallel. */
enum { PAIR_NONE, PAIR_LINK, PAIR_SPLIT_B, PAIR_SPLIT_A };

static int pair_decide(const iv_links *l, const iv_hier *h, float subdiv, uint32_t A, uint32_t B,
                       gi_vec3 *dout, float *r2out)
{
    gi_vec3 d = gi_v3_sub(gi_v3_load(&h->pos[3 * B]), gi_v3_load(&h->pos[3 * A]));
    float r2 = gi_v3_dot(d, d);
    int leafA = iv_is_leaf(h, A), leafB = iv_is_leaf(h, B);
    int needA, needB;
    if (!(r2 > 1e-20f)) {
        needA = !leafA;
        needB = !leafB;
        if (!needA && !needB)
            return PAIR_NONE; /* two discs at one point: no direction to bin them in */
    } else {
        if (coplanar(h, A, B, d, r2))
            return PAIR_NONE;
        float oa = subdiv * l->bin_omega[iv_bin_of(gi_v3_scale(d, -1.0f), l->n)];
        float ob = subdiv * l->bin_omega[iv_bin_of(d, l->n)];
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
    return needB ? PAIR_SPLIT_B : (needA ? PAIR_SPLIT_A : PAIR_LINK);
}

/* Sec. 4.2.2: link A and B, or their children where one looks bigger than
 * a bin from the other. */
static void link_pair(link_ctx *c, uint32_t A, uint32_t B)
{
    const iv_hier *h = c->h;
    c->l->tries++;
    gi_vec3 d;
    float r2;
    switch (pair_decide(c->l, h, c->subdiv, A, B, &d, &r2)) {
    case PAIR_SPLIT_B:
        for (uint32_t k = 0; k < h->child_count[B]; k++)
            link_pair(c, A, h->first_child[B] + k);
        break;
    case PAIR_SPLIT_A:
        for (uint32_t k = 0; k < h->child_count[A]; k++)
            link_pair(c, h->first_child[A] + k, B);
        break;
    case PAIR_LINK:
        insert(c->l, h, A, B, d, sqrtf(r2), c->splat);
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

/* ---- link creation on several threads (README "Multi-threaded link creation") ----
 * 1. The recursion of link_self / link_pair is unrolled into an ordered
 *    list of tasks (calls in the order one thread would make them).
 * 2. Threads take tasks and list the pairs each task links, in order.
 * 3. Threads write the links: each owns the receiving nodes x with
 *    x mod threads = its index, and goes through all pairs in task order,
 *    writing only its own nodes' sides. Every node's bins see the same
 *    writes in the same order as on one thread, so the result (shortest
 *    links, ties, coverage sums) is the same to the bit. */

typedef struct link_task {
    uint32_t A, B;   /* B == UINT32_MAX: link_self(A) */
    uint32_t *pairs; /* 2 per pair linked, in order */
    size_t n, cap;
    uint64_t tries;
} link_task;

typedef struct link_par {
    iv_links *l;
    const iv_hier *h;
    float subdiv;
    int splat;
    link_task *tasks;
    size_t ntasks;
    atomic_size_t next;
    int threads;
    int fail;
} link_par;

static int task_push(link_task *t, uint32_t A, uint32_t B)
{
    if (t->n == t->cap) {
        size_t c = t->cap ? 2 * t->cap : 256;
        uint32_t *p = realloc(t->pairs, c * 2 * sizeof *p);
        if (!p)
            return 0;
        t->pairs = p;
        t->cap = c;
    }
    t->pairs[2 * t->n] = A;
    t->pairs[2 * t->n + 1] = B;
    t->n++;
    return 1;
}

static int collect_pair(link_par *p, link_task *t, uint32_t A, uint32_t B)
{
    const iv_hier *h = p->h;
    t->tries++;
    gi_vec3 d;
    float r2;
    switch (pair_decide(p->l, h, p->subdiv, A, B, &d, &r2)) {
    case PAIR_SPLIT_B:
        for (uint32_t k = 0; k < h->child_count[B]; k++)
            if (!collect_pair(p, t, A, h->first_child[B] + k))
                return 0;
        return 1;
    case PAIR_SPLIT_A:
        for (uint32_t k = 0; k < h->child_count[A]; k++)
            if (!collect_pair(p, t, h->first_child[A] + k, B))
                return 0;
        return 1;
    case PAIR_LINK:
        return task_push(t, A, B);
    default:
        return 1;
    }
}

static int collect_self(link_par *p, link_task *t, uint32_t A)
{
    const iv_hier *h = p->h;
    uint32_t f = h->first_child[A], n = h->child_count[A];
    for (uint32_t i = 0; i < n; i++)
        if (!collect_self(p, t, f + i))
            return 0;
    for (uint32_t i = 0; i < n; i++)
        for (uint32_t j = i + 1; j < n; j++)
            if (!collect_pair(p, t, f + i, f + j))
                return 0;
    return 1;
}

/* Replaces every task by the calls it makes (in order) until there are
 * at least `want` or none can be unrolled; a link found while unrolling
 * stays a one-pair task. tries counts the calls unrolled. */
static link_task *unroll_tasks(link_par *p, link_task *tasks, size_t *count, size_t want,
                               uint64_t *tries)
{
    const iv_hier *h = p->h;
    for (int pass = 0; pass < 12 && *count < want; pass++) {
        size_t n = *count, cap = 0, m = 0;
        for (size_t i = 0; i < n; i++) {
            uint32_t A = tasks[i].A, B = tasks[i].B;
            uint32_t ca = h->child_count[A];
            cap += B == UINT32_MAX ? ca + (size_t)ca * ca / 2 : 4;
        }
        link_task *out = calloc(cap + 1, sizeof *out);
        if (!out)
            return tasks;
        int grew = 0;
        for (size_t i = 0; i < n; i++) {
            uint32_t A = tasks[i].A, B = tasks[i].B;
            if (tasks[i].n > 0) { /* a link found while unrolling: kept as it is */
                out[m++] = tasks[i];
                continue;
            }
            if (B == UINT32_MAX) {
                uint32_t f = h->first_child[A], c = h->child_count[A];
                for (uint32_t k = 0; k < c; k++)
                    out[m++] = (link_task){.A = f + k, .B = UINT32_MAX};
                for (uint32_t x = 0; x < c; x++)
                    for (uint32_t y = x + 1; y < c; y++)
                        out[m++] = (link_task){.A = f + x, .B = f + y};
                grew = 1;
                continue;
            }
            (*tries)++;
            gi_vec3 d;
            float r2;
            int what = pair_decide(p->l, h, p->subdiv, A, B, &d, &r2);
            if (what == PAIR_SPLIT_B) {
                for (uint32_t k = 0; k < h->child_count[B]; k++)
                    out[m++] = (link_task){.A = A, .B = h->first_child[B] + k};
                grew = 1;
            } else if (what == PAIR_SPLIT_A) {
                for (uint32_t k = 0; k < h->child_count[A]; k++)
                    out[m++] = (link_task){.A = h->first_child[A] + k, .B = B};
                grew = 1;
            } else if (what == PAIR_LINK) {
                out[m] = (link_task){.A = A, .B = B};
                if (!task_push(&out[m], A, B)) {
                    free(out);
                    return tasks;
                }
                m++;
            }
        }
        free(tasks);
        tasks = out;
        *count = m;
        if (!grew)
            break;
    }
    return tasks;
}

static void *collect_worker(void *arg)
{
    link_par *p = arg;
    for (;;) {
        size_t i = atomic_fetch_add(&p->next, 1);
        if (i >= p->ntasks)
            break;
        link_task *t = &p->tasks[i];
        if (t->n > 0)
            continue; /* a link found while unrolling */
        int ok = t->B == UINT32_MAX ? collect_self(p, t, t->A) : collect_pair(p, t, t->A, t->B);
        if (!ok)
            p->fail = 1;
    }
    return NULL;
}

typedef struct write_arg {
    link_par *p;
    uint32_t index;
    uint64_t created;
} write_arg;

static void *write_worker(void *arg)
{
    write_arg *w = arg;
    link_par *p = w->p;
    const iv_hier *h = p->h;
    uint32_t T = (uint32_t)p->threads, me = w->index;
    /* a private copy of the counters: `created` is summed afterwards */
    iv_links mine = *p->l;
    mine.created = 0;
    for (uint32_t x = me; x < p->l->nodes; x += T) { /* its nodes' bins emptied */
        size_t base = (size_t)x * p->l->bins;
        for (uint32_t b = 0; b < p->l->bins; b++) {
            p->l->other[base + b] = -1;
            p->l->dist[base + b] = FLT_MAX;
            p->l->cover[base + b] = 0.0f;
        }
    }
    for (size_t i = 0; i < p->ntasks; i++) {
        const link_task *t = &p->tasks[i];
        for (size_t k = 0; k < t->n; k++) {
            uint32_t A = t->pairs[2 * k], B = t->pairs[2 * k + 1];
            int a = A % T == me, b = B % T == me;
            if (!a && !b)
                continue;
            gi_vec3 d = gi_v3_sub(gi_v3_load(&h->pos[3 * B]), gi_v3_load(&h->pos[3 * A]));
            float r = sqrtf(gi_v3_dot(d, d));
            if (a)
                put_side(&mine, h, A, B, d, r, p->splat);
            if (b)
                put_side(&mine, h, B, A, gi_v3_scale(d, -1.0f), r, p->splat);
        }
    }
    w->created = mine.created;
    return NULL;
}

/* The hierarchical links on `threads` threads; 0 when it could not (out
 * of memory, no thread), and the caller builds them on one. */
static int build_parallel(iv_links *l, const iv_hier *h, float subdiv, int splat, int threads)
{
    link_par p = {.l = l, .h = h, .subdiv = subdiv, .splat = splat, .threads = threads};
    size_t n = h->root_count + (size_t)h->root_count * (h->root_count - 1) / 2;
    link_task *tasks = calloc(n + 1, sizeof *tasks);
    if (!tasks)
        return 0;
    size_t m = 0;
    for (uint32_t i = 0; i < h->root_count; i++)
        tasks[m++] = (link_task){.A = i, .B = UINT32_MAX};
    for (uint32_t i = 0; i < h->root_count; i++)
        for (uint32_t j = i + 1; j < h->root_count; j++)
            tasks[m++] = (link_task){.A = i, .B = j};
    uint64_t tries = 0;
    tasks = unroll_tasks(&p, tasks, &m, (size_t)64 * (size_t)threads, &tries);
    p.tasks = tasks;
    p.ntasks = m;
    atomic_init(&p.next, 0);
    pthread_t *tid = malloc((size_t)threads * sizeof *tid);
    uint8_t *made = calloc((size_t)threads, 1);
    write_arg *wa = calloc((size_t)threads, sizeof *wa);
    int ok = tid && made && wa;
    if (ok) {
        /* this thread works too; a thread that cannot start is not needed */
        for (int i = 1; i < threads; i++)
            made[i] = pthread_create(&tid[i], NULL, collect_worker, &p) == 0;
        collect_worker(&p);
        for (int i = 1; i < threads; i++)
            if (made[i])
                pthread_join(tid[i], NULL);
        ok = !p.fail;
    }
    if (ok) {
        for (size_t i = 0; i < m; i++)
            tries += tasks[i].tries;
        /* each writer owns its nodes: one that cannot start runs here afterwards */
        for (int i = 0; i < threads; i++)
            wa[i] = (write_arg){.p = &p, .index = (uint32_t)i};
        for (int i = 1; i < threads; i++)
            made[i] = pthread_create(&tid[i], NULL, write_worker, &wa[i]) == 0;
        write_worker(&wa[0]);
        for (int i = 1; i < threads; i++) {
            if (made[i])
                pthread_join(tid[i], NULL);
            else
                write_worker(&wa[i]);
        }
        for (int i = 0; i < threads; i++)
            l->created += wa[i].created;
        l->tries = tries;
    }
    for (size_t i = 0; i < m; i++)
        free(tasks[i].pairs);
    free(tasks), free(tid), free(made), free(wa);
    return ok;
}

static void links_clear(iv_links *l)
{
    size_t cells = (size_t)l->bins * l->nodes;
    for (size_t i = 0; i < cells; i++) {
        l->other[i] = -1;
        l->dist[i] = FLT_MAX;
        l->cover[i] = 0.0f;
    }
    l->tries = l->created = 0;
}

void iv_links_build(iv_links *l, const iv_hier *h, float subdiv, int brute, int splat)
{
    if (brute) {
        links_clear(l);
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
    l->tries = l->created = 0;
    if (l->threads > 1 && build_parallel(l, h, subdiv, splat, (int)l->threads))
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
        for (uint32_t b = 0; b < nb; b++) {
            l->cover[c + b] += l->cover[p + b]; /* the pairs linked higher up lie in this bin too */
            if (l->dist[p + b] < l->dist[c + b]) {
                l->dist[c + b] = l->dist[p + b];
                l->other[c + b] = l->other[p + b];
            }
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

static float covered(const iv_links *l, uint32_t x, uint32_t b);

static uint32_t float_bits(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}

void iv_links_pack(const iv_links *l, const iv_hier *h, uint32_t *links, uint32_t *off)
{
    size_t light_base = l->leaf_off[h->elem_count];
    for (uint32_t e = 0; e <= h->elem_count; e++) {
        off[2 * e] = l->leaf_off[e];
        off[2 * e + 1] = l->light_off[e];
    }
    for (uint32_t e = 0; e < h->elem_count; e++) {
        uint32_t x = h->elem_node[e];
        for (int light = 0; light < 2; light++) {
            const uint32_t *o = light ? l->light_off : l->leaf_off;
            const uint32_t *bin = light ? l->light_bin : l->leaf_bin;
            const uint32_t *src = light ? l->light_src : l->leaf_src;
            for (uint32_t j = o[e]; j < o[e + 1]; j++) {
                uint32_t *w = &links[4 * ((light ? light_base : 0) + j)];
                w[0] = bin[j];
                w[1] = src[j];
                w[2] = float_bits(covered(l, x, bin[j]));
                w[3] = float_bits(l->dist[(size_t)x * l->bins + bin[j]]);
            }
        }
    }
}

/* Radiance a node sends toward point x: the side its mean normal faces x;
 * a cluster whose children face every way (mean normal shorter than 0.3)
 * sends the mean of both sides. */
static void node_radiance(const iv_hier *h, const float *sp, const float *sm, uint32_t src,
                          gi_vec3 x, float out[3])
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

/* Fraction of bin b of leaf x that its links cover (their solid angles
 * summed over the leaf's path to the root, at most the bin's). */
static float covered(const iv_links *l, uint32_t x, uint32_t b)
{
    if (!(l->coverage > 0.0f)) /* Eq. 5: the nearest element covers its bin */
        return l->other[(size_t)x * l->bins + b] >= 0 ? 1.0f : 0.0f;
    float f = l->cover[(size_t)x * l->bins + b] / (l->coverage * l->bin_omega[b]);
    return f < 1.0f ? f : 1.0f;
}

/* Adds radiance L arriving through the fraction `frac` of bin b to the
 * irradiance of the side of the disc (normal n) it falls on: the bin's
 * share of the hemisphere weighted by its cosine. With frac = 1 this is
 * Eq. 5 with the nearest element covering its bin. */
static void add_bin(const iv_links *l, uint32_t b, gi_vec3 n, float norm, float frac,
                    const float L[3], double ep[3], double em[3])
{
    float w = gi_v3_dot(n, gi_v3_load(&l->bin_dir[3 * b])) * l->bin_omega[b] * norm * frac;
    double *e = w >= 0.0f ? ep : em;
    w = fabsf(w);
    for (int c = 0; c < 3; c++)
        e[c] += (double)w * L[c];
}

/* Irradiance from the punctual lights at leaf x, each seen through the bin
 * toward it: blocked where the bin holds a link shorter than the light's
 * distance (a directional light: where the bin holds any link). */
static void punctual(const iv_links *l, const iv_hier *h, const iv_lights *li, uint32_t leaf,
                     double ep[3], double em[3])
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
                scale *= gi_spot_falloff(-gi_v3_dot(wl, gi_v3_normalize(f.direction)),
                                         cosf(lt->inner_cone), cosf(lt->outer_cone));
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

void iv_illuminate(const iv_links *l, iv_hier *h, const iv_lights *li, uint32_t bounces,
                   float *e_out)
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
                add_bin(l, bin[j], n, norm[e], covered(l, x, bin[j]), L, ep, em);
            }
            if (direct) {
                if (li->env) { /* Sec. 4.4: an empty bin (or what its links leave uncovered) sees
                                  the environment */
                    for (uint32_t b = 0; b < l->bins; b++) {
                        float open = 1.0f - covered(l, x, b);
                        if (open > 0.0f) {
                            float L[3];
                            gi_envmap_eval(li->env, gi_v3_load(&l->bin_dir[3 * b]), L);
                            add_bin(l, b, n, norm[e], open, L, ep, em);
                        }
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
