/* The faces the rasterised propagation sorts and draws (paper §3.2: "we
 * make the assumption that all faces are planar"; its Cornell box is 19
 * polygons): a face whose triangles tile one convex polygon is drawn as
 * that polygon, so a tessellated wall is one polygon instead of a thousand
 * triangles. The surface is the same (the polygon is the union of the
 * triangles: its area equals theirs), so the rays meet the same faces;
 * what changes is how many primitives the sort orders and the rasteriser
 * sets up per direction. Every path that sorts faces uses them (the C
 * sweeps too, so that a hardware GL's raster default and llvmpipe's cpu
 * default start from the same lists); order = rays and subdivide > 1
 * (whose point is more faces) keep the triangles. */
#define _POSIX_C_SOURCE 200809L
#include "field_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct pt2 {
    double x, y;
} pt2;

static int pt_cmp(const void *a, const void *b)
{
    const pt2 *p = a, *q = b;
    if (p->x != q->x)
        return p->x < q->x ? -1 : 1;
    return p->y < q->y ? -1 : (p->y > q->y);
}

static double cross(pt2 o, pt2 a, pt2 b)
{
    return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

/* Convex hull of p[0 .. n) (sorted in place), counter-clockwise, collinear
 * points dropped (Andrew's monotone chain) into h (2n); returns its size. */
static uint32_t hull(pt2 *p, uint32_t n, pt2 *h)
{
    qsort(p, n, sizeof *p, pt_cmp);
    uint32_t k = 0;
    for (uint32_t i = 0; i < n; i++) {
        while (k >= 2 && cross(h[k - 2], h[k - 1], p[i]) <= 1e-8)
            k--;
        h[k++] = p[i];
    }
    for (uint32_t i = n - 1, t = k + 1; i-- > 0;) {
        while (k >= t && cross(h[k - 2], h[k - 1], p[i]) <= 1e-8)
            k--;
        h[k++] = p[i];
    }
    return k > 1 ? k - 1 : k;
}

/* Face fc's triangles tris[0 .. n) as a convex polygon in out (3 corners
 * per fan triangle, VLF coordinates, wound counter-clockwise about fc->n);
 * returns the triangles written, 0 when they do not tile a convex polygon
 * (then the caller keeps them). pts, h: scratch of 3n and 6n points. */
static uint32_t merge_one(const vlf_field *f, const vlf_face *fc, const uint32_t *tris, uint32_t n,
                          pt2 *pts, pt2 *h, gi_vec3 *out)
{
    double area = 0.0;
    for (uint32_t k = 0; k < n; k++) {
        const gi_vec3 *p = f->tri_p + 3 * (size_t)tris[k];
        for (int c = 0; c < 3; c++) {
            gi_vec3 d = gi_v3_sub(p[c], fc->origin);
            pts[3 * k + (uint32_t)c] = (pt2){gi_v3_dot(d, fc->t), gi_v3_dot(d, fc->b)};
        }
        area += 0.5 * fabs(cross(pts[3 * k], pts[3 * k + 1], pts[3 * k + 2]));
    }
    uint32_t m = hull(pts, 3 * n, h);
    if (m < 3 || m - 2 >= n)
        return 0;
    double ha = 0.0;
    for (uint32_t k = 1; k + 1 < m; k++)
        ha += 0.5 * cross(h[0], h[k], h[k + 1]);
    if (!(fabs(ha - area) <= 1e-5 * area))
        return 0; /* not one convex polygon (holes, parts, overlaps) */
    /* counter-clockwise in (t, b) is about t x b; wind it about n */
    int flip = gi_v3_dot(gi_v3_cross(fc->t, fc->b), fc->n) < 0.0f;
    for (uint32_t k = 1; k + 1 < m; k++) {
        pt2 c[3] = {h[0], h[flip ? k + 1 : k], h[flip ? k : k + 1]};
        for (int a = 0; a < 3; a++)
            out[3 * (k - 1) + (uint32_t)a] =
                gi_v3_add(fc->origin, gi_v3_add(gi_v3_scale(fc->t, (float)c[a].x),
                                                gi_v3_scale(fc->b, (float)c[a].y)));
    }
    return m - 2;
}

/* Each face's triangles, grouped: the triangles of face fi are
 * order[first[fi] .. first[fi + 1]). 1, or 0 out of memory. */
static int by_face(const vlf_field *f, uint32_t **first, uint32_t **order)
{
    *first = calloc((size_t)f->face_count + 2, sizeof **first);
    *order = malloc(((size_t)f->tri_count + 1) * sizeof **order);
    if (!*first || !*order)
        return 0;
    for (uint32_t t = 0; t < f->tri_count; t++)
        (*first)[f->tri_face[t] + 1]++;
    for (uint32_t i = 0; i < f->face_count; i++)
        (*first)[i + 1] += (*first)[i];
    uint32_t *pos = malloc(((size_t)f->face_count + 1) * sizeof *pos);
    if (!pos)
        return 0;
    memcpy(pos, *first, (size_t)f->face_count * sizeof *pos);
    for (uint32_t t = 0; t < f->tri_count; t++)
        (*order)[pos[f->tri_face[t]]++] = t;
    free(pos);
    return 1;
}

gi_result vlf_merge_faces(vlf_field *f)
{
    f->sort_count = f->tri_count;
    f->sort_p = f->tri_p, f->sort_face = f->tri_face, f->sort_group = f->tri_group;
    if (f->prm.order == VLF_ORDER_RAYS || f->tri_sub > 1 || f->tri_count == 0)
        return GI_OK;
    uint32_t *first = NULL, *order = NULL;
    size_t T = f->tri_count;
    gi_vec3 *P = malloc(T * 3 * sizeof *P);
    uint32_t *F = malloc(T * sizeof *F), *G = malloc(T * sizeof *G);
    pt2 *pts = malloc(T * 3 * sizeof *pts), *h = malloc(T * 6 * sizeof *h);
    int ok = P && F && G && pts && h && by_face(f, &first, &order);
    uint32_t n = 0;
    for (uint32_t fi = 0; ok && fi < f->face_count; fi++) {
        const uint32_t *tris = order + first[fi];
        uint32_t c = first[fi + 1] - first[fi], g = c ? f->tri_group[tris[0]] : 0, m = 0;
        int one_group = 1;
        for (uint32_t k = 1; k < c; k++)
            one_group = one_group && f->tri_group[tris[k]] == g;
        if (c > 2 && one_group)
            m = merge_one(f, &f->faces[fi], tris, c, pts, h, P + 3 * (size_t)n);
        if (m == 0) /* kept as they are */
            for (uint32_t k = 0; k < c; k++, m++)
                memcpy(P + 3 * (size_t)(n + m), f->tri_p + 3 * (size_t)tris[k], 3 * sizeof *P);
        for (uint32_t k = 0; k < m; k++)
            F[n + k] = fi, G[n + k] = g;
        if (c == 0)
            continue;
        if (!one_group) /* kept triangles keep their own objects */
            for (uint32_t k = 0; k < c; k++)
                G[n + k] = f->tri_group[tris[k]];
        n += m;
    }
    free(first), free(order), free(pts), free(h);
    if (!ok) {
        free(P), free(F), free(G);
        return GI_ERR_OUT_OF_MEMORY;
    }
    f->sort_count = n, f->sort_p = P, f->sort_face = F, f->sort_group = G;
    return GI_OK;
}
