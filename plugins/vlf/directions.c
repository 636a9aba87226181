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
    memset(d, 0, sizeof *d);
}

uint32_t vlf_dirs_locate(const vlf_dirs *d, gi_vec3 w, uint32_t node[3], float alpha[3])
{
    uint32_t best = 0;
    float best_min = -FLT_MAX;
    float bx[3] = {0, 0, 0};
    for (uint32_t t = 0; t < d->tri_count; t++) {
        const float *m = d->tri_inv + 9 * t;
        float x = m[0] * w.x + m[1] * w.y + m[2] * w.z;
        float y = m[3] * w.x + m[4] * w.y + m[5] * w.z;
        float z = m[6] * w.x + m[7] * w.y + m[8] * w.z;
        float mn = fminf(x, fminf(y, z));
        if (mn > best_min) {
            best_min = mn;
            best = t;
            bx[0] = x;
            bx[1] = y;
            bx[2] = z;
            if (mn >= 0.0f)
                break;
        }
    }
    float s = 0.0f;
    for (int j = 0; j < 3; j++) {
        bx[j] = fmaxf(bx[j], 0.0f);
        s += bx[j];
    }
    for (int j = 0; j < 3; j++) {
        node[j] = d->tris[3 * best + j];
        alpha[j] = s > 0.0f ? bx[j] / s : 1.0f / 3.0f;
    }
    return best;
}
