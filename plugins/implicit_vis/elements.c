/* The implicit_vis method's surface elements (Sec. 4.1) and the
 * re-meshing that makes their points (Sec. 5.1): the surface points of
 * the model as it is, of a k x k grid per triangle, or of CGAL's
 * isotropic re-meshing embedded on the original triangles; points equal
 * in position and normal merged into one oriented disc each. See iv.h. */
#include "iv_internal.h"

#include "gi/mesh.h"
#include "gi/algo/remesh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

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

/* More surface points than IV_MAX_SAMPLES for the target edge length. */
static gi_result too_many_points(float target, gi_error *err)
{
    return gi_error_set(err, GI_ERR_UNSUPPORTED,
                        "implicit_vis: re-meshing to edge length %g gives more than %u surface "
                        "points: raise it",
                        target, (unsigned)IV_MAX_SAMPLES);
}

/* Without re-meshing or with the grid: every point of each triangle's
 * k x k grid (k = 1: its corners) is a surface point, the sub-triangles
 * the surface, and the display grid the points themselves. */
static gi_result samples_grid(iv_hier *h, const gi_scene *s, float target, gi_error *err)
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
            return too_many_points(target, err);
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
        return iv_hier_fail("out of memory", err);
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
    return GI_OK;
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

/* The isotropic re-meshing's working set: the triangles sorted into
 * patches (object and material), the corners of the patch being welded,
 * and CGAL's result for each patch. */
typedef struct patches {
    uint32_t nt;
    uint32_t *order, *key;
    gi_remeshed **rm; /* per patch, indexed by its first triangle in `order` */
    float *lp, *ln;
    uint32_t *lk, *lidx;
} patches;

static int patches_init(patches *P, uint32_t nt)
{
    P->nt = nt;
    P->order = malloc((nt + 1) * sizeof *P->order);
    P->key = malloc((nt + 1) * sizeof *P->key);
    P->rm = calloc(nt + 1, sizeof *P->rm);
    P->lp = malloc(((size_t)nt * 9 + 1) * sizeof(float));
    P->ln = malloc(((size_t)nt * 9 + 1) * sizeof(float));
    P->lk = calloc((size_t)nt * 3 + 1, sizeof *P->lk);
    P->lidx = malloc(((size_t)nt * 3 + 1) * sizeof *P->lidx);
    return P->order && P->key && P->rm && P->lp && P->ln && P->lk && P->lidx;
}

static void patches_free(patches *P)
{
    if (P->rm)
        for (uint32_t i = 0; i < P->nt; i++)
            gi_remeshed_free(P->rm[i]);
    free(P->order), free(P->key), free(P->rm), free(P->lp), free(P->ln), free(P->lk), free(P->lidx);
}

/* The end of the patch that starts at a in `order`. */
static uint32_t patch_end(const patches *P, uint32_t a)
{
    uint32_t b;
    for (b = a; b < P->nt && P->key[P->order[b]] == P->key[P->order[a]]; b++)
        ;
    return b;
}

/* Each triangle's patch key and its display grid (k as for the grid
 * re-meshing); too many grid points, or a target edge that would give
 * too many surface points, are refused before CGAL runs. */
static gi_result isotropic_grids(iv_hier *h, const gi_scene *s, float target, patches *P,
                                 gi_error *err)
{
    uint32_t nt = s->triangle_count;
    uint64_t disp = 0;
    for (uint32_t t = 0; t < nt; t++) {
        P->order[t] = t;
        P->key[t] = s->vertices[s->indices[3 * t]].object * (s->material_count + 1) +
                    s->vertices[s->indices[3 * t]].material;
        h->tri_k[t] = tri_k(s, t, target);
        h->tri_grid[t] = (uint32_t)disp;
        disp += (uint64_t)(h->tri_k[t] + 1) * (h->tri_k[t] + 2) / 2;
        if (disp > IV_MAX_SAMPLES)
            return too_many_points(target, err);
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
    if (area / (0.866 * (double)target * (double)target) > (double)IV_MAX_SAMPLES)
        return too_many_points(target, err);
    return GI_OK;
}

/* The patch order[a .. b - 1]: its corners welded (object-local rest
 * pose), then re-meshed by CGAL into P->rm[a]. */
static gi_result remesh_patch(patches *P, const gi_scene *s, uint32_t a, uint32_t b, double q,
                              float target, gi_error *err)
{
    welder w = {0};
    if (!welder_init(&w, 3 * (b - a), q, P->lp, P->ln, P->lk)) {
        welder_free(&w);
        return iv_hier_fail("out of memory", err);
    }
    uint32_t nv = 0;
    for (uint32_t i = a; i < b; i++)
        for (int c = 0; c < 3; c++) {
            const gi_vertex *v = &s->vertices[s->indices[3 * P->order[i] + c]];
            memcpy(&P->lp[3 * nv], v->position, 3 * sizeof(float));
            memcpy(&P->ln[3 * nv], v->normal, 3 * sizeof(float));
            gi_vec3 n = gi_v3_normalize(gi_v3_load(v->normal));
            uint32_t id = welder_find_or_add(&w, v->position, n, 0, nv);
            nv += id == nv;
            P->lidx[3 * (i - a) + (uint32_t)c] = id;
        }
    welder_free(&w);
    uint32_t obj = s->vertices[s->indices[3 * P->order[a]]].object;
    P->rm[a] = gi_remesh_isotropic(P->lp, nv, P->lidx, b - a, target / object_scale(s, obj),
                                   IV_REMESH_ITERATIONS, err);
    return P->rm[a] ? GI_OK : GI_ERR_INVALID_ARGUMENT; /* err set by the re-meshing */
}

/* Every patch re-meshed; total and surf: the vertices and triangles of
 * all of them. */
static gi_result remesh_patches(patches *P, const gi_scene *s, float target, uint64_t *total,
                                uint64_t *surf, gi_error *err)
{
    g_group_key = P->key;
    qsort(P->order, P->nt, sizeof *P->order, cmp_group);
    double q = weld_quantum(s);
    for (uint32_t a = 0, b; a < P->nt; a = b) {
        b = patch_end(P, a);
        gi_result r = remesh_patch(P, s, a, b, q, target, err);
        if (r != GI_OK)
            return r;
        *total += P->rm[a]->vertex_count;
        *surf += P->rm[a]->triangle_count;
        if (*total > IV_MAX_SAMPLES)
            return too_many_points(target, err);
    }
    return GI_OK;
}

/* The display grid of each of the patch's triangles, located on the
 * re-meshed surface: per grid point the three re-meshed corners (points
 * from `base` on, mapped to elements later) and their weights. */
static gi_result patch_display_grid(iv_hier *h, const gi_scene *s, const patches *P, uint32_t a,
                                    uint32_t b, uint32_t base, gi_error *err)
{
    const gi_remeshed *r = P->rm[a];
    uint32_t nq = 0;
    for (uint32_t i = a; i < b; i++)
        nq += h->tri_grid[P->order[i] + 1] - h->tri_grid[P->order[i]];
    float *query = malloc(((size_t)nq * 3 + 1) * sizeof(float));
    float *qb = malloc(((size_t)nq * 3 + 1) * sizeof(float));
    uint32_t *qf = malloc(((size_t)nq + 1) * sizeof *qf);
    if (!query || !qb || !qf) {
        free(query), free(qb), free(qf);
        return iv_hier_fail("out of memory", err);
    }
    uint32_t qi = 0;
    for (uint32_t i = a; i < b; i++) {
        uint32_t t = P->order[i], k = h->tri_k[t];
        for (uint32_t j = 0; j <= k; j++)
            for (uint32_t ii = 0; ii + j <= k; ii++) {
                gi_vec3 n;
                rest_point(s, t, (float)ii / (float)k, (float)j / (float)k, &query[3 * qi++], &n);
            }
    }
    gi_result res = gi_mesh_locate(r->positions, r->vertex_count, r->indices, r->triangle_count,
                                   query, nq, qf, qb, err);
    if (res == GI_OK) {
        qi = 0;
        for (uint32_t i = a; i < b; i++) {
            uint32_t t = P->order[i];
            for (uint32_t d = h->tri_grid[t]; d < h->tri_grid[t + 1]; d++, qi++)
                for (int c = 0; c < 3; c++) {
                    h->disp_elem[3 * d + c] =
                        base + r->indices[3 * qf[qi] + c]; /* a point (mapped later) */
                    h->disp_w[3 * d + c] = qb[3 * qi + c];
                }
        }
    }
    free(query), free(qb), free(qf);
    return res;
}

/* The patch order[a .. b - 1]'s re-meshed vertices as surface points
 * (from `base` on), its triangles as the surface (from `sbase` on), and
 * its display grids. */
static gi_result patch_copy(iv_hier *h, const gi_scene *s, const patches *P, uint32_t a, uint32_t b,
                            uint32_t base, uint32_t sbase, gi_error *err)
{
    const gi_remeshed *r = P->rm[a];
    for (uint32_t v = 0; v < r->vertex_count; v++) {
        h->samp_tri[base + v] = P->order[a + r->face[v]];
        h->samp_b[2 * (base + v)] = r->bary[3 * v + 1];
        h->samp_b[2 * (base + v) + 1] = r->bary[3 * v + 2];
    }
    for (uint32_t f = 0; f < 3 * r->triangle_count; f++)
        h->surf_tri[3 * (size_t)sbase + f] = base + r->indices[f];
    return patch_display_grid(h, s, P, a, b, base, err);
}

/* Isotropic re-meshing (Sec. 5.1) by CGAL, per object and material (an
 * emitter keeps its outline). Each patch is welded by position and
 * normal, so that a hard edge is a border, which keeps its vertices. The
 * new vertices are the surface points, each on the original triangle CGAL
 * projected it to; the display grid of every original triangle is located
 * on the re-meshed surface (triangle, barycentric weights). */
static gi_result samples_isotropic(iv_hier *h, const gi_scene *s, float target, gi_error *err)
{
    patches P = {0};
    uint64_t total = 0, surf = 0;
    gi_result r = patches_init(&P, s->triangle_count) ? GI_OK : iv_hier_fail("out of memory", err);
    if (r == GI_OK)
        r = isotropic_grids(h, s, target, &P, err);
    if (r == GI_OK)
        r = remesh_patches(&P, s, target, &total, &surf, err);
    if (r == GI_OK) {
        uint64_t disp = h->disp_count;
        h->sample_count = (uint32_t)total;
        h->surf_count = (uint32_t)surf;
        h->samp_tri = malloc((total + 1) * sizeof *h->samp_tri);
        h->samp_b = malloc((total * 2 + 1) * sizeof *h->samp_b);
        h->surf_tri = malloc((surf * 3 + 1) * sizeof *h->surf_tri);
        h->disp_elem = malloc((disp * 3 + 1) * sizeof *h->disp_elem);
        h->disp_w = malloc((disp * 3 + 1) * sizeof *h->disp_w);
        if (!h->samp_tri || !h->samp_b || !h->surf_tri || !h->disp_elem || !h->disp_w)
            r = iv_hier_fail("out of memory", err);
    }
    for (uint32_t a = 0, b, base = 0, sbase = 0; r == GI_OK && a < P.nt; a = b) {
        b = patch_end(&P, a);
        r = patch_copy(h, s, &P, a, b, base, sbase, err);
        base += P.rm[a]->vertex_count;
        sbase += P.rm[a]->triangle_count;
    }
    patches_free(&P);
    return r;
}

/* The surface points as discs (Sec. 4.1). Points of one object at one
 * rest position (within 1e-5 of the scene's size) whose normals agree
 * (cos > 0.95) are one element; a hard edge keeps two. */
gi_result iv_elements_make(iv_hier *h, const gi_scene *s, float target, int remesher, gi_error *err)
{
    uint32_t nt = s->triangle_count;
    h->tri_k = malloc((nt + 1) * sizeof *h->tri_k);
    h->tri_grid = malloc((nt + 1) * sizeof *h->tri_grid);
    if (!h->tri_k || !h->tri_grid)
        return iv_hier_fail("out of memory", err);
    gi_result r = target > 0.0f && remesher == IV_REMESH_ISOTROPIC
                      ? samples_isotropic(h, s, target, err)
                      : samples_grid(h, s, target, err);
    if (r != GI_OK)
        return r;
    uint32_t ns = h->sample_count;
    h->samp_elem = malloc((ns + 1) * sizeof *h->samp_elem);
    h->elem_rep = malloc((ns + 1) * sizeof *h->elem_rep);
    float *rest = malloc(((size_t)ns * 3 + 1) * sizeof(float));
    float *albedo_sum = calloc((size_t)ns * 3 + 1, sizeof(float));
    float *emit = calloc((size_t)ns * 3 + 1, sizeof(float));
    float *ep = malloc(((size_t)ns * 3 + 1) * sizeof(float)),
          *en = malloc(((size_t)ns * 3 + 1) * sizeof(float));
    uint32_t *ek = malloc(((size_t)ns + 1) * sizeof *ek);
    uint8_t *two = calloc(ns + 1, 1);
    uint32_t *count = calloc(ns + 1, sizeof *count);
    welder w = {0};
    int ok = h->samp_elem && h->elem_rep && rest && albedo_sum && emit && ep && en && ek && two &&
             count && welder_init(&w, ns, weld_quantum(s), ep, en, ek);
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
    free(albedo_sum), free(emit), free(two), free(count), free(rest), free(ep), free(en), free(ek);
    return ok ? GI_OK : iv_hier_fail("out of memory", err);
}
