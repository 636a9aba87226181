/* The direction set of the vlf method (paper §2.1): l bi-directional
 * directions by a spherical Fibonacci spiral, their antipodes, the
 * spherical triangulation of the 2l signed directions with each node's
 * solid angle, and the three nearest directions of any direction with
 * their barycentric weights (see vlf_field.h). */
#include "vlf_field.h"

#include "gi/algo/hull.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static int inv3(const float m[9], float out[9])
{
    float a = m[0], b = m[1], c = m[2], d = m[3], e = m[4], f = m[5], g = m[6], h = m[7], i = m[8];
    float A = e * i - f * h, B = -(d * i - f * g), C = d * h - e * g;
    float det = a * A + b * B + c * C;
    if (fabsf(det) < 1e-12f)
        return 0;
    float s = 1.0f / det;
    out[0] = A * s;
    out[1] = -(b * i - c * h) * s;
    out[2] = (b * f - c * e) * s;
    out[3] = B * s;
    out[4] = (a * i - c * g) * s;
    out[5] = -(a * f - c * d) * s;
    out[6] = C * s;
    out[7] = -(a * h - b * g) * s;
    out[8] = (a * e - b * d) * s;
    return 1;
}

static int grid_build(vlf_dirs *d);

/* Area of the spherical triangle a, b, c (van Oosterom and Strackee). */
static float spherical_area(gi_vec3 a, gi_vec3 b, gi_vec3 c)
{
    float num = gi_v3_dot(a, gi_v3_cross(b, c));
    float den = 1.0f + gi_v3_dot(a, b) + gi_v3_dot(b, c) + gi_v3_dot(c, a);
    return 2.0f * fabsf(atan2f(num, den));
}

gi_result vlf_dirs_build(vlf_dirs *d, uint32_t l, gi_error *err)
{
    memset(d, 0, sizeof *d);
    if (l < 4)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "vlf: l = %u directions, at least 4 needed", l);
    d->l = l;
    uint32_t n = 2 * l;
    d->signed_dirs = calloc(n, sizeof *d->signed_dirs);
    d->solid_angle = calloc(n, sizeof *d->solid_angle);
    float *pts = calloc((size_t)n * 3, sizeof *pts);
    if (!d->signed_dirs || !d->solid_angle || !pts) {
        free(pts);
        vlf_dirs_free(d);
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "vlf: out of memory for %u directions", l);
    }
    /* Spherical Fibonacci points on the upper hemisphere: equal-area bands in
     * z, golden-angle steps in phi. */
    const double golden = GI_PI * (3.0 - sqrt(5.0));
    for (uint32_t k = 0; k < l; k++) {
        double z = 1.0 - ((double)k + 0.5) / (double)l;
        double r = sqrt(fmax(0.0, 1.0 - z * z));
        double phi = golden * (double)k;
        gi_vec3 w = gi_v3((float)(r * cos(phi)), (float)(r * sin(phi)), (float)z);
        d->signed_dirs[k] = w;
        d->signed_dirs[k + l] = gi_v3_scale(w, -1.0f);
    }
    for (uint32_t k = 0; k < n; k++) {
        pts[3 * k + 0] = d->signed_dirs[k].x;
        pts[3 * k + 1] = d->signed_dirs[k].y;
        pts[3 * k + 2] = d->signed_dirs[k].z;
    }
    /* The convex hull of points on the sphere is their spherical Delaunay
     * triangulation (gi/algo/hull.h). */
    uint32_t *raw = NULL, count = 0;
    gi_error hull_err;
    gi_result r = gi_hull_triangulate(pts, n, &raw, &count, &hull_err);
    free(pts);
    if (r == GI_OK) {
        d->tris = calloc((size_t)count * 3, sizeof *d->tris);
        d->tri_inv = calloc((size_t)count * 9, sizeof *d->tri_inv);
        if (!d->tris || !d->tri_inv)
            r = gi_error_set(&hull_err, GI_ERR_OUT_OF_MEMORY, "out of memory");
    }
    uint32_t t = 0;
    for (; r == GI_OK && t < count; t++) {
        uint32_t v[3] = {raw[3 * t], raw[3 * t + 1], raw[3 * t + 2]};
        gi_vec3 a = d->signed_dirs[v[0]], b = d->signed_dirs[v[1]], c = d->signed_dirs[v[2]];
        gi_vec3 nrm = gi_v3_cross(gi_v3_sub(b, a), gi_v3_sub(c, a));
        if (gi_v3_dot(nrm, gi_v3_add(a, gi_v3_add(b, c))) < 0.0f) {
            uint32_t tmp = v[1];
            v[1] = v[2];
            v[2] = tmp;
            gi_vec3 tv = b;
            b = c;
            c = tv;
        }
        float m[9] = {a.x, b.x, c.x, a.y, b.y, c.y, a.z, b.z, c.z};
        if (!inv3(m, d->tri_inv + 9 * t)) {
            r = gi_error_set(&hull_err, GI_ERR_INVALID_ARGUMENT, "a degenerate spherical triangle");
            break;
        }
        memcpy(d->tris + 3 * t, v, sizeof v);
        float area = spherical_area(a, b, c);
        for (int j = 0; j < 3; j++)
            d->solid_angle[v[j]] += area / 3.0f;
    }
    d->tri_count = t;
    free(raw);
    if (r == GI_OK && !grid_build(d))
        r = gi_error_set(&hull_err, GI_ERR_OUT_OF_MEMORY, "out of memory for the search grid");
    if (r != GI_OK) {
        vlf_dirs_free(d);
        return gi_error_set(err, r, "vlf: could not triangulate %u directions: %s", l,
                            hull_err.text);
    }
    return GI_OK;
}

void vlf_dirs_free(vlf_dirs *d)
{
    free(d->signed_dirs);
    free(d->solid_angle);
    free(d->tris);
    free(d->tri_inv);
    free(d->cell_start);
    free(d->cell_tris);
    memset(d, 0, sizeof *d);
}

/* fminf without the library call: the smaller of a and b, a NaN ignored
 * (the same answer as fminf, NaN included). */
static inline float min_nan(float a, float b)
{
    return (a < b || b != b) ? a : b;
}

/* The coordinates of w in the basis a, b, c of triangle t. */
static inline void tri_coords(const vlf_dirs *d, uint32_t t, gi_vec3 w, float b[3])
{
    const float *m = d->tri_inv + 9 * t;
    b[0] = m[0] * w.x + m[1] * w.y + m[2] * w.z;
    b[1] = m[3] * w.x + m[4] * w.y + m[5] * w.z;
    b[2] = m[6] * w.x + m[7] * w.y + m[8] * w.z;
}

/* The nodes of triangle t and the weights from its coordinates bx. */
static uint32_t locate_result(const vlf_dirs *d, uint32_t t, float bx[3], uint32_t node[3],
                              float alpha[3])
{
    float s = 0.0f;
    for (int j = 0; j < 3; j++) {
        bx[j] = fmaxf(bx[j], 0.0f);
        s += bx[j];
    }
    for (int j = 0; j < 3; j++) {
        node[j] = d->tris[3 * t + j];
        alpha[j] = s > 0.0f ? bx[j] / s : 1.0f / 3.0f;
    }
    return t;
}

uint32_t vlf_dirs_locate_all(const vlf_dirs *d, gi_vec3 w, uint32_t node[3], float alpha[3])
{
    /* The first triangle whose coordinates are all non-negative (it holds
     * w); failing one (w on a seam, rounding), the one nearest to holding it. */
    uint32_t best = 0;
    float best_min = -FLT_MAX;
    float bx[3] = {0, 0, 0};
    for (uint32_t t = 0; t < d->tri_count; t++) {
        float b[3];
        tri_coords(d, t, w, b);
        float mn = min_nan(b[0], min_nan(b[1], b[2]));
        if (mn > best_min) {
            best_min = mn;
            best = t;
            memcpy(bx, b, sizeof bx);
            if (mn >= 0.0f)
                break;
        }
    }
    return locate_result(d, best, bx, node, alpha);
}

/* Cell index of u in [-1, 1] on a face of n cells a side. */
static uint32_t grid_index(float u, uint32_t n)
{
    float f = (u + 1.0f) * 0.5f * (float)n;
    if (!(f > 0.0f))
        return 0;
    return f >= (float)n ? n - 1 : (uint32_t)f;
}

/* The cube-map cell of direction w (-1 for zero, infinite or NaN w): face
 * 2 axis + (negative), then rows and columns of the other two coordinates
 * divided by the largest. */
static int64_t grid_cell(uint32_t n, gi_vec3 w)
{
    float a[3] = {w.x, w.y, w.z};
    int ax = 0;
    for (int i = 1; i < 3; i++)
        if (fabsf(a[i]) > fabsf(a[ax]))
            ax = i;
    float m = fabsf(a[ax]);
    if (!(m > 0.0f) || !(m <= FLT_MAX))
        return -1;
    float u = a[(ax + 1) % 3] / m, v = a[(ax + 2) % 3] / m;
    if (u != u || v != v)
        return -1;
    int64_t face = 2 * ax + (a[ax] < 0.0f);
    return (face * n + grid_index(v, n)) * n + grid_index(u, n);
}

/* The unit direction of point (u, v) of cube face f. */
static void grid_point(int f, double u, double v, double p[3])
{
    int ax = f / 2;
    p[ax] = (f & 1) ? -1.0 : 1.0;
    p[(ax + 1) % 3] = u;
    p[(ax + 2) % 3] = v;
    double len = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    for (int i = 0; i < 3; i++)
        p[i] /= len;
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* Centre of cell c and the largest angle from a cell's centre to its
 * corners over all cells (a cell lies in the cap of its centre and the
 * angle to its farthest corner: its edges are great-circle arcs). */
static double grid_cell_centre(uint32_t n, uint32_t c, double ctr[3])
{
    uint32_t i = c % n, j = (c / n) % n;
    int f = (int)(c / (n * n));
    double h = 2.0 / n, u0 = -1.0 + h * i, v0 = -1.0 + h * j;
    grid_point(f, u0 + 0.5 * h, v0 + 0.5 * h, ctr);
    double r = 0.0;
    for (int k = 0; k < 4; k++) {
        double p[3];
        grid_point(f, u0 + h * (k & 1), v0 + h * (k >> 1), p);
        r = fmax(r, acos(fmin(1.0, dot3(ctr, p))));
    }
    return r;
}

/* Fills the cells' lists, in two passes (count, then fill): triangle t is
 * listed in a cell when its bounding cap (centre the normalised sum of its
 * corners, radius the angle to the farthest) meets the cell's, with a
 * margin far above the rounding of the coordinates. A triangle holding w
 * by tri_coords (all >= 0) lies within the margin of w, so it is in w's
 * cell's list, and the first such in index order is the brute force's. */
static int grid_fill(vlf_dirs *d, const double *tc, const double *tcos, const double *cc,
                     uint32_t cells)
{
    for (int pass = 0; pass < 2; pass++) {
        uint32_t k = 0;
        for (uint32_t c = 0; c < cells; c++) {
            if (pass == 1 && d->cell_start[c] != k)
                return 0;
            for (uint32_t t = 0; t < d->tri_count; t++)
                if (dot3(cc + 3 * c, tc + 3 * t) >= tcos[t]) {
                    if (pass == 1)
                        d->cell_tris[k] = t;
                    k++;
                }
            if (pass == 0)
                d->cell_start[c + 1] = k;
        }
        if (pass == 0 && !(d->cell_tris = malloc(((size_t)k + 1) * sizeof *d->cell_tris)))
            return 0;
    }
    return 1;
}

/* Builds the search grid of vlf_dirs_locate (0 out of memory). */
static int grid_build(vlf_dirs *d)
{
    uint32_t n = (uint32_t)ceil(sqrt((double)d->tri_count / 12.0));
    n = n < 1 ? 1 : n > 32 ? 32 : n;
    uint32_t cells = 6 * n * n;
    const double margin = 1e-3; /* radians; coordinates round at ~1e-6 */
    double *tc = malloc((size_t)d->tri_count * 3 * sizeof *tc);
    double *tcos = malloc((size_t)d->tri_count * sizeof *tcos);
    double *cc = malloc((size_t)cells * 3 * sizeof *cc);
    d->grid_n = n;
    d->cell_start = calloc((size_t)cells + 1, sizeof *d->cell_start);
    int ok = tc && tcos && cc && d->cell_start;
    double cell_r = 0.0;
    for (uint32_t c = 0; ok && c < cells; c++)
        cell_r = fmax(cell_r, grid_cell_centre(n, c, cc + 3 * c));
    for (uint32_t t = 0; ok && t < d->tri_count; t++) {
        double v[3][3], *ctr = tc + 3 * t, r = 0.0;
        for (int j = 0; j < 3; j++) {
            gi_vec3 p = d->signed_dirs[d->tris[3 * t + j]];
            v[j][0] = p.x, v[j][1] = p.y, v[j][2] = p.z;
        }
        for (int i = 0; i < 3; i++)
            ctr[i] = v[0][i] + v[1][i] + v[2][i];
        double len = sqrt(dot3(ctr, ctr));
        for (int i = 0; i < 3; i++)
            ctr[i] /= len;
        for (int j = 0; j < 3; j++)
            r = fmax(r, acos(fmin(1.0, dot3(ctr, v[j]))));
        /* A cap of 90 degrees or more does not hold its triangle for sure:
         * then the triangle is in every cell. */
        double reach = r + margin >= 0.5 * GI_PI ? GI_PI : r + cell_r + margin;
        tcos[t] = reach >= GI_PI ? -2.0 : cos(reach);
    }
    ok = ok && grid_fill(d, tc, tcos, cc, cells);
    free(tc);
    free(tcos);
    free(cc);
    return ok;
}

uint32_t vlf_dirs_locate(const vlf_dirs *d, gi_vec3 w, uint32_t node[3], float alpha[3])
{
    int64_t c = d->grid_n ? grid_cell(d->grid_n, w) : -1;
    for (uint32_t k = c >= 0 ? d->cell_start[c] : 0; c >= 0 && k < d->cell_start[c + 1]; k++) {
        uint32_t t = d->cell_tris[k];
        float b[3];
        tri_coords(d, t, w, b);
        if (min_nan(b[0], min_nan(b[1], b[2])) >= 0.0f)
            return locate_result(d, t, b, node, alpha);
    }
    /* No triangle holds w by its rounded coordinates (or no grid): the
     * brute force's nearest one. */
    return vlf_dirs_locate_all(d, w, node, alpha);
}
