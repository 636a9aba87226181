/* Convex hulls by qhull and the GJK distance between two placed hulls
 * (gi/algo/hull.h): the overlap condition of moving objects in Ritschel et al.
 * 2008 §3.3. */
#include "gi/algo/hull.h"

#include <libqhull_r/qhull_ra.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void gi_hull_free(gi_hull *h)
{
    if (!h)
        return;
    free(h->vertices);
    free(h->planes);
    memset(h, 0, sizeof *h);
}

/* One qhull run with `flags`; 0 on success (hull filled), qhull's exit
 * code otherwise, -1 for no memory. */
static int run_qhull(coordT *pts, uint32_t count, const char *flags, gi_hull *out)
{
    qhT qh_qh;
    qhT *qh = &qh_qh;
    char cmd[64];
    snprintf(cmd, sizeof cmd, "%s", flags);
    FILE *quiet = fopen("/dev/null", "w"); /* qhull prints its errors; the caller reports them */
    qh_zero(qh, quiet ? quiet : stderr);
    int rc = qh_new_qhull(qh, 3, (int)count, pts, False, cmd, NULL, quiet ? quiet : stderr);
    if (rc == 0) {
        uint32_t nv = 0, nf = 0;
        vertexT *vertex;
        facetT *facet;
        FORALLvertices nv++;
        FORALLfacets nf++;
        out->vertices = malloc((size_t)nv * sizeof *out->vertices);
        out->planes = malloc((size_t)nf * 4 * sizeof *out->planes);
        if (!out->vertices || !out->planes) {
            rc = -1;
        } else {
            /* the input points, not joggled copies */
            FORALLvertices
            {
                int id = qh_pointid(qh, vertex->point);
                out->vertices[out->vertex_count++] =
                    gi_v3((float)pts[3 * id], (float)pts[3 * id + 1], (float)pts[3 * id + 2]);
            }
            FORALLfacets
            {
                float *p = &out->planes[4 * out->face_count++];
                for (int k = 0; k < 3; k++)
                    p[k] = (float)facet->normal[k];
                p[3] = (float)facet->offset;
            }
        }
    }
    int curlong, totlong;
    qh_freeqhull(qh, !qh_ALL);
    qh_memfreeshort(qh, &curlong, &totlong);
    if (quiet)
        fclose(quiet);
    if (rc != 0)
        gi_hull_free(out);
    return rc;
}

gi_result gi_hull_triangulate(const float *points, uint32_t count, uint32_t **tris,
                              uint32_t *tri_count, gi_error *err)
{
    *tris = NULL;
    *tri_count = 0;
    coordT *pts = calloc((size_t)count * 3 + 1, sizeof *pts);
    if (!pts)
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "hull: out of memory for %u points", count);
    for (size_t k = 0; k < (size_t)count * 3; k++)
        pts[k] = points[k];
    qhT qh_qh;
    qhT *qh = &qh_qh;
    qh_zero(qh, stderr);
    char flags[] = "qhull Qt";
    int rc = qh_new_qhull(qh, 3, (int)count, pts, False, flags, NULL, NULL);
    gi_result r = rc == 0 ? GI_OK : GI_ERR_INVALID_ARGUMENT;
    if (r == GI_OK) {
        facetT *facet;
        uint32_t n = 0;
        FORALLfacets n++;
        uint32_t *t = calloc((size_t)n * 3 + 1, sizeof *t);
        if (!t)
            r = GI_ERR_OUT_OF_MEMORY;
        uint32_t k = 0;
        FORALLfacets
        {
            if (r != GI_OK)
                break;
            vertexT *vertex, **vertexp;
            uint32_t nv = 0;
            FOREACHvertex_(facet->vertices)
            {
                if (nv < 3)
                    t[3 * k + nv] = (uint32_t)qh_pointid(qh, vertex->point);
                nv++;
            }
            if (nv != 3)
                r = GI_ERR_INVALID_ARGUMENT;
            k++;
        }
        if (r == GI_OK) {
            *tris = t;
            *tri_count = k;
        } else {
            free(t);
        }
    }
    int curlong, totlong;
    qh_freeqhull(qh, !qh_ALL);
    qh_memfreeshort(qh, &curlong, &totlong);
    free(pts);
    if (r == GI_ERR_OUT_OF_MEMORY)
        return gi_error_set(err, r, "hull: out of memory for the triangles of %u points", count);
    if (r != GI_OK)
        return gi_error_set(err, r, "hull: qhull could not triangulate %u points (code %d)", count,
                            rc);
    return GI_OK;
}

gi_result gi_hull_build(const float *points, uint32_t count, gi_hull *out, gi_error *err)
{
    memset(out, 0, sizeof *out);
    if (!count || !points) {
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "hull: no points");
    }
    coordT *pts = malloc((size_t)count * 3 * sizeof *pts);
    if (!pts) {
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "hull: out of memory for %u points", count);
    }
    int distinct = 0;
    for (uint32_t i = 0; i < 3 * count; i++) {
        if (!isfinite(points[i])) {
            free(pts);
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "hull: point %u is not finite",
                                i / 3);
        }
        pts[i] = points[i];
        distinct |= points[i] != points[i % 3];
    }
    int rc = 0;
    if (count < 4 || !distinct) {
        rc = 1; /* qhull needs 4 points; fewer ones stand for themselves below */
    } else {
        /* Qt: triangulated output; a flat or degenerate set fails, then QJ
         * joggles it into a thin solid */
        rc = run_qhull(pts, count, "qhull Qt", out);
        if (rc > 0)
            rc = run_qhull(pts, count, "qhull QJ", out);
    }
    if (rc > 0 && (count < 4 || !distinct)) {
        /* one to three points (or copies of one): the vertices are the points */
        uint32_t n = distinct ? count : 1;
        out->vertices = malloc((size_t)n * sizeof *out->vertices);
        if (out->vertices) {
            for (uint32_t i = 0; i < n; i++)
                out->vertices[i] = gi_v3(points[3 * i], points[3 * i + 1], points[3 * i + 2]);
            out->vertex_count = n;
            rc = 0;
        } else {
            rc = -1;
        }
    }
    free(pts);
    if (rc == -1) {
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY,
                            "hull: out of memory for the hull of %u points", count);
    }
    if (rc != 0) {
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "hull: qhull failed on %u points (exit code %d)", count, rc);
    }
    return GI_OK;
}

int gi_hull_contains(const gi_hull *h, gi_vec3 p, float margin)
{
    if (!h->face_count)
        return 0;
    for (uint32_t f = 0; f < h->face_count; f++) {
        const float *q = &h->planes[4 * f];
        if (q[0] * p.x + q[1] * p.y + q[2] * p.z + q[3] > margin)
            return 0;
    }
    return 1;
}

/* ------------------------------------------------------------------ GJK */

typedef struct dv3 {
    double x, y, z;
} dv3;

static dv3 d3(double x, double y, double z)
{
    dv3 r = {x, y, z};
    return r;
}
static dv3 dsub(dv3 a, dv3 b)
{
    return d3(a.x - b.x, a.y - b.y, a.z - b.z);
}
static dv3 dadd(dv3 a, dv3 b)
{
    return d3(a.x + b.x, a.y + b.y, a.z + b.z);
}
static dv3 dscale(dv3 a, double s)
{
    return d3(a.x * s, a.y * s, a.z * s);
}
static double ddot(dv3 a, dv3 b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
static dv3 dcross(dv3 a, dv3 b)
{
    return d3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}

static dv3 place(const float m[16], gi_vec3 p)
{
    if (!m)
        return d3(p.x, p.y, p.z);
    return d3((double)m[0] * p.x + (double)m[4] * p.y + (double)m[8] * p.z + m[12],
              (double)m[1] * p.x + (double)m[5] * p.y + (double)m[9] * p.z + m[13],
              (double)m[2] * p.x + (double)m[6] * p.y + (double)m[10] * p.z + m[14]);
}

/* The point of p[0 .. n) farthest along d. */
static dv3 support(const dv3 *p, uint32_t n, dv3 d)
{
    dv3 best = p[0];
    double bd = ddot(best, d);
    for (uint32_t i = 1; i < n; i++) {
        double v = ddot(p[i], d);
        if (v > bd)
            bd = v, best = p[i];
    }
    return best;
}

/* Closest point of triangle abc to the origin (Ericson, Real-Time
 * Collision Detection §5.1.5); the simplex is reduced to the feature that
 * holds it. */
static dv3 closest_triangle(dv3 *w, int *n)
{
    dv3 a = w[0], b = w[1], c = w[2];
    dv3 ab = dsub(b, a), ac = dsub(c, a), ap = dscale(a, -1.0);
    double d1 = ddot(ab, ap), d2 = ddot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) {
        *n = 1;
        return a;
    }
    dv3 bp = dscale(b, -1.0);
    double d3_ = ddot(ab, bp), d4 = ddot(ac, bp);
    if (d3_ >= 0.0 && d4 <= d3_) {
        w[0] = b, *n = 1;
        return b;
    }
    double vc = d1 * d4 - d3_ * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3_ <= 0.0) {
        double v = d1 / (d1 - d3_);
        *n = 2; /* a, b */
        return dadd(a, dscale(ab, v));
    }
    dv3 cp = dscale(c, -1.0);
    double d5 = ddot(ab, cp), d6 = ddot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6) {
        w[0] = c, *n = 1;
        return c;
    }
    double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
        double v = d2 / (d2 - d6);
        w[1] = c, *n = 2; /* a, c */
        return dadd(a, dscale(ac, v));
    }
    double va = d3_ * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3_) >= 0.0 && (d5 - d6) >= 0.0) {
        double v = (d4 - d3_) / ((d4 - d3_) + (d5 - d6));
        w[0] = b, w[1] = c, *n = 2; /* b, c */
        return dadd(b, dscale(dsub(c, b), v));
    }
    double den = 1.0 / (va + vb + vc);
    double v = vb * den, u = vc * den;
    *n = 3;
    return dadd(a, dadd(dscale(ab, v), dscale(ac, u)));
}

static dv3 closest_segment(dv3 *w, int *n)
{
    dv3 a = w[0], b = w[1], ab = dsub(b, a);
    double l = ddot(ab, ab), t = l > 0.0 ? -ddot(a, ab) / l : 0.0;
    if (t <= 0.0) {
        *n = 1;
        return a;
    }
    if (t >= 1.0) {
        w[0] = b, *n = 1;
        return b;
    }
    *n = 2;
    return dadd(a, dscale(ab, t));
}

/* Closest point of the simplex w[0..n) to the origin; reduces w. Sets
 * *inside when a tetrahedron holds the origin. */
static dv3 closest_simplex(dv3 *w, int *n, int *inside)
{
    *inside = 0;
    if (*n == 1)
        return w[0];
    if (*n == 2)
        return closest_segment(w, n);
    if (*n == 3)
        return closest_triangle(w, n);
    /* tetrahedron: each face whose plane has the origin on the side away
     * from the opposite vertex is a candidate */
    static const int faces[4][4] = {{0, 1, 2, 3}, {0, 1, 3, 2}, {0, 2, 3, 1}, {1, 2, 3, 0}};
    double best = HUGE_VAL;
    dv3 bestp = w[0], bestw[3];
    int bestn = 0, outside_any = 0;
    for (int f = 0; f < 4; f++) {
        dv3 a = w[faces[f][0]], b = w[faces[f][1]], c = w[faces[f][2]], d = w[faces[f][3]];
        dv3 nrm = dcross(dsub(b, a), dsub(c, a));
        double so = -ddot(nrm, a), sd = ddot(nrm, dsub(d, a));
        if (so * sd >= 0.0 && sd != 0.0)
            continue; /* origin on the opposite vertex's side of this face */
        outside_any = 1;
        dv3 tw[3] = {a, b, c};
        int tn = 3;
        dv3 p = closest_triangle(tw, &tn);
        double dd = ddot(p, p);
        if (dd < best) {
            best = dd, bestp = p, bestn = tn;
            memcpy(bestw, tw, sizeof bestw);
        }
    }
    if (!outside_any) {
        *inside = 1;
        return d3(0, 0, 0);
    }
    memcpy(w, bestw, sizeof bestw);
    *n = bestn;
    return bestp;
}

/* GJK on the placed vertex sets pa (na) and pb (nb). */
static double gjk(const dv3 *pa, uint32_t na, const dv3 *pb, uint32_t nb)
{
    dv3 w[4];
    int n = 0;
    dv3 v = dsub(pa[0], pb[0]);
    double scale = sqrt(ddot(v, v)) + 1e-30;
    w[n++] = v; /* v is a point of the difference: the first simplex */
    for (int iter = 0; iter < 128; iter++) {
        double vv = ddot(v, v);
        if (vv <= 1e-24 * scale * scale)
            return 0.0;
        dv3 p = dsub(support(pa, na, dscale(v, -1.0)), support(pb, nb, v));
        /* v.p is a lower bound of the distance times |v|; converged when
         * it meets |v|^2 */
        if (vv - ddot(v, p) <= 1e-12 * vv)
            return sqrt(vv);
        int dup = 0;
        for (int k = 0; k < n; k++)
            dup |= w[k].x == p.x && w[k].y == p.y && w[k].z == p.z;
        if (dup)
            return sqrt(vv);
        w[n++] = p;
        int inside;
        dv3 nv = closest_simplex(w, &n, &inside);
        if (inside)
            return 0.0;
        if (ddot(nv, nv) >= vv) /* no progress: v is as close as the numbers allow */
            return sqrt(vv);
        v = nv;
    }
    return sqrt(ddot(v, v));
}

double gi_hull_distance(const gi_hull *a, const float ma[16], const gi_hull *b, const float mb[16])
{
    if (!a->vertex_count || !b->vertex_count)
        return HUGE_VAL;
    dv3 *pa = malloc(((size_t)a->vertex_count + b->vertex_count) * sizeof *pa);
    if (!pa) /* no memory: nothing can be told apart, so call it overlapping */
        return 0.0;
    dv3 *pb = pa + a->vertex_count;
    for (uint32_t i = 0; i < a->vertex_count; i++)
        pa[i] = place(ma, a->vertices[i]);
    for (uint32_t i = 0; i < b->vertex_count; i++)
        pb[i] = place(mb, b->vertices[i]);
    double d = gjk(pa, a->vertex_count, pb, b->vertex_count);
    free(pa);
    return d;
}

int gi_hull_overlap(const gi_hull *a, const float ma[16], const gi_hull *b, const float mb[16],
                    float margin)
{
    double d = gi_hull_distance(a, ma, b, mb);
    /* touching within float precision of the placed coordinates counts */
    dv3 p = a->vertex_count ? place(ma, a->vertices[0]) : d3(0, 0, 0);
    return d <= (double)margin + 1e-6 * sqrt(ddot(p, p));
}
