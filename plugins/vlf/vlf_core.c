/* The CPU side of the vlf method: directions, subfields, depth order,
 * storage and propagation (see vlf_core.h and plugins/vlf/README.md). */
#define _POSIX_C_SOURCE 200809L
#include "vlf_core.h"

#include "gi/algo/hull.h"

#include <float.h>
#include <stdint.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <pthread.h>

#include "gi/envmap.h"
#include "gi/lights.h"
#include "gi/raytrace.h"
#include "vlf_sort.h"

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ---- Directions (§2.1) ---------------------------------------------------- */

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

int vlf_dirs_build(vlf_dirs *d, uint32_t l, char *err, size_t err_size)
{
    memset(d, 0, sizeof *d);
    if (l < 4) {
        snprintf(err, err_size, "vlf: l = %u directions, at least 4 needed", l);
        return -1;
    }
    d->l = l;
    uint32_t n = 2 * l;
    d->signed_dirs = calloc(n, sizeof *d->signed_dirs);
    d->solid_angle = calloc(n, sizeof *d->solid_angle);
    float *pts = calloc((size_t)n * 3, sizeof *pts);
    if (!d->signed_dirs || !d->solid_angle || !pts) {
        free(pts);
        vlf_dirs_free(d);
        snprintf(err, err_size, "vlf: out of memory for %u directions", l);
        return -1;
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
    int ok = gi_hull_triangulate(pts, n, &raw, &count, &hull_err) == GI_OK;
    free(pts);
    if (ok) {
        d->tris = calloc((size_t)count * 3, sizeof *d->tris);
        d->tri_inv = calloc((size_t)count * 9, sizeof *d->tri_inv);
        ok = d->tris && d->tri_inv;
        if (!ok)
            snprintf(hull_err.text, sizeof hull_err.text, "out of memory");
    }
    uint32_t t = 0;
    for (; ok && t < count; t++) {
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
            ok = 0;
            snprintf(hull_err.text, sizeof hull_err.text, "a degenerate spherical triangle");
            break;
        }
        memcpy(d->tris + 3 * t, v, sizeof v);
        float area = spherical_area(a, b, c);
        for (int j = 0; j < 3; j++)
            d->solid_angle[v[j]] += area / 3.0f;
    }
    d->tri_count = t;
    free(raw);
    if (!ok) {
        vlf_dirs_free(d);
        snprintf(err, err_size, "vlf: could not triangulate %u directions: %s", l, hull_err.text);
        return -1;
    }
    return 0;
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

/* ---- Storage precision (§3.1, §6) ----------------------------------------- */

size_t vlf_precision_bytes(uint32_t prec)
{
    return prec == VLF_PREC_16F ? 8 : prec == VLF_PREC_RGB9E5 ? 4 : 12;
}

/* IEEE half from float, rounding to nearest even; beyond the largest half
 * (65504) the largest half (a GPU would store infinity). */
static uint16_t float_to_half(float f)
{
    uint32_t x;
    memcpy(&x, &f, sizeof x);
    uint32_t sign = (x >> 16) & 0x8000u, ax = x & 0x7fffffffu;
    if (ax > 0x7f800000u)
        return 0; /* NaN: stored as 0 (values here are never NaN) */
    if (ax >= 0x477fe000u)
        return (uint16_t)(sign | 0x7bffu);
    if (ax < 0x38800000u) { /* below 2^-14: subnormal half or zero */
        if (ax < 0x33000000u)
            return (uint16_t)sign;
        uint32_t e = ax >> 23, m = (ax & 0x7fffffu) | 0x800000u, shift = 126 - e;
        uint32_t h = m >> shift, rem = m & ((1u << shift) - 1), halfway = 1u << (shift - 1);
        if (rem > halfway || (rem == halfway && (h & 1u)))
            h++;
        return (uint16_t)(sign | h);
    }
    uint32_t h = (ax - 0x38000000u) >> 13, rem = ax & 0x1fffu;
    if (rem > 0x1000u || (rem == 0x1000u && (h & 1u)))
        h++;
    if (h >= 0x7c00u)
        h = 0x7bffu;
    return (uint16_t)(sign | h);
}

static float half_to_float(uint16_t h)
{
    uint32_t e = (h >> 10) & 0x1fu, m = h & 0x3ffu;
    float f = e == 0 ? ldexpf((float)m, -24) : ldexpf((float)(m | 0x400u), (int)e - 25);
    return (h & 0x8000u) ? -f : f;
}

/* RGB9E5 as the GL spec (EXT_texture_shared_exponent) packs it: 9-bit
 * mantissas, one 5-bit exponent (bias 15), negative values as 0. */
static uint32_t pack_9e5(const float *c)
{
    const float maxv = 511.0f / 512.0f * 65536.0f;
    float v[3];
    for (int k = 0; k < 3; k++)
        v[k] = c[k] > 0.0f ? fminf(c[k], maxv) : 0.0f;
    float mx = fmaxf(v[0], fmaxf(v[1], v[2]));
    int e2 = -16;
    if (mx > 0.0f) {
        int ex;
        frexpf(mx, &ex);
        e2 = ex - 1 > -16 ? ex - 1 : -16; /* floor(log2 mx), at least -16 */
    }
    int es = e2 + 1 + 15;
    float scale = ldexpf(1.0f, es - 15 - 9);
    if ((int)floorf(mx / scale + 0.5f) == 512)
        es++, scale *= 2.0f;
    uint32_t m[3];
    for (int k = 0; k < 3; k++) {
        int q = (int)floorf(v[k] / scale + 0.5f);
        m[k] = (uint32_t)(q > 511 ? 511 : q);
    }
    return m[0] | m[1] << 9 | m[2] << 18 | (uint32_t)es << 27;
}

static void unpack_9e5(uint32_t x, float *c)
{
    float scale = ldexpf(1.0f, (int)(x >> 27) - 24);
    c[0] = (float)(x & 511u) * scale;
    c[1] = (float)((x >> 9) & 511u) * scale;
    c[2] = (float)((x >> 18) & 511u) * scale;
}

void vlf_pack(uint32_t prec, const float *rgb, size_t count, void *out)
{
    if (prec == VLF_PREC_16F) {
        uint16_t *h = out;
        for (size_t i = 0; i < count; i++) {
            for (int k = 0; k < 3; k++)
                h[4 * i + (size_t)k] = float_to_half(rgb[3 * i + (size_t)k]);
            h[4 * i + 3] = 0;
        }
    } else if (prec == VLF_PREC_RGB9E5) {
        uint32_t *w = out;
        for (size_t i = 0; i < count; i++)
            w[i] = pack_9e5(rgb + 3 * i);
    } else {
        memcpy(out, rgb, count * 3 * sizeof(float));
    }
}

void vlf_unpack(uint32_t prec, const void *in, size_t count, float *rgb)
{
    if (prec == VLF_PREC_16F) {
        const uint16_t *h = in;
        for (size_t i = 0; i < count; i++)
            for (int k = 0; k < 3; k++)
                rgb[3 * i + (size_t)k] = half_to_float(h[4 * i + (size_t)k]);
    } else if (prec == VLF_PREC_RGB9E5) {
        const uint32_t *w = in;
        for (size_t i = 0; i < count; i++)
            unpack_9e5(w[i], rgb + 3 * i);
    } else {
        memcpy(rgb, in, count * 3 * sizeof(float));
    }
}

void vlf_quantise(uint32_t prec, float *rgb, size_t count)
{
    if (prec == VLF_PREC_16F) {
        for (size_t i = 0; i < 3 * count; i++)
            rgb[i] = half_to_float(float_to_half(rgb[i]));
    } else if (prec == VLF_PREC_RGB9E5) {
        for (size_t i = 0; i < count; i++)
            unpack_9e5(pack_9e5(rgb + 3 * i), rgb + 3 * i);
    }
}

/* ---- Glossy albedo -------------------------------------------------------- */

double vlf_phong_albedo(float n, float cos_t)
{
    /* (n + 2) / (2 pi) * integral over the hemisphere of cos^n(alpha)
     * cos(theta_o) d omega_o, alpha the angle to the reflected direction:
     * with u = cos^(n+1) alpha, (n + 2) / (n + 1) times the mean of
     * max(0, cos theta_o) over u in [0, 1] and phi (a 64 x 64 midpoint rule) */
    const int K = 64;
    double ct = fmin(1.0, fabs((double)cos_t)), st = sqrt(fmax(0.0, 1.0 - ct * ct)), sum = 0.0;
    for (int a = 0; a < K; a++) {
        double ca = pow(((double)a + 0.5) / K, 1.0 / ((double)n + 1.0)),
               sa = sqrt(fmax(0.0, 1.0 - ca * ca));
        for (int b = 0; b < K; b++) {
            double co = ca * ct + sa * st * cos(2.0 * GI_PI * ((double)b + 0.5) / K);
            if (co > 0.0)
                sum += co;
        }
    }
    return ((double)n + 2.0) / ((double)n + 1.0) * sum / (double)(K * K);
}

float vlf_phong_albedo_at(const vlf_face *fc, float cos_t)
{
    float x = fminf(1.0f, fmaxf(0.0f, cos_t)) * (float)(VLF_ALBEDO_TABLE - 1);
    int k = (int)x;
    if (k >= VLF_ALBEDO_TABLE - 1)
        return fc->albedo[VLF_ALBEDO_TABLE - 1];
    float t = x - (float)k;
    return fc->albedo[k] * (1.0f - t) + fc->albedo[k + 1] * t;
}

/* ---- Subfields ------------------------------------------------------------ */

gi_vec3 vlf_to_vlf(const vlf_field *f, gi_vec3 world)
{
    return gi_v3_scale(gi_v3_sub(world, f->centre), 1.0f / f->radius);
}

void vlf_psf_project(const vlf_field *f, uint32_t i, gi_vec3 q, float *x, float *y, float *depth)
{
    const vlf_psf *p = &f->psf[i];
    float N = (float)f->prm.N;
    *x = (gi_v3_dot(q, p->u) + 1.0f) * 0.5f * N;
    *y = (gi_v3_dot(q, p->v) + 1.0f) * 0.5f * N;
    *depth = gi_v3_dot(q, p->n);
}

/* Elements: texels of the face's chart, density per unit length. */
uint32_t vlf_element_at(const vlf_field *f, const vlf_face *fc, gi_vec3 q)
{
    gi_vec3 d = gi_v3_sub(q, fc->origin);
    float x = gi_v3_dot(d, fc->t) * f->prm.density, y = gi_v3_dot(d, fc->b) * f->prm.density;
    int ix = (int)floorf(x), iy = (int)floorf(y);
    ix = ix < 0 ? 0 : ix >= (int)fc->W ? (int)fc->W - 1 : ix;
    iy = iy < 0 ? 0 : iy >= (int)fc->H ? (int)fc->H - 1 : iy;
    return fc->first_elem + (uint32_t)iy * fc->W + (uint32_t)ix;
}

typedef struct frag_tmp {
    uint32_t cell;
    float depth;
    uint32_t rank; /* 0; 1 for the second side of a double-sided face (after the first at the same
                      depth) */
    uint32_t elem;
} frag_tmp;

typedef struct frag_buf {
    frag_tmp *v;
    size_t n, cap;
} frag_buf;

static int frag_push(frag_buf *b, uint32_t cell, float depth, uint32_t rank, uint32_t elem)
{
    if (b->n == b->cap) {
        size_t cap = b->cap ? b->cap * 2 : 4096;
        frag_tmp *v = realloc(b->v, cap * sizeof *v);
        if (!v)
            return 0;
        b->v = v;
        b->cap = cap;
    }
    b->v[b->n++] = (frag_tmp){cell, depth, rank, elem};
    return 1;
}

/* Rasterises face fi orthographically into subfield i (cell centres inside
 * the projected triangle). Calls emit for each covered cell. */
typedef int (*cell_fn)(void *user, uint32_t cx, uint32_t cy, float depth);

static int raster_tri(const vlf_field *f, const vlf_psf *fr, const gi_vec3 *p, cell_fn emit,
                      void *user)
{
    float x[3], y[3], z[3];
    float NS = (float)(f->prm.N * f->prm.S);
    for (int k = 0; k < 3; k++) {
        x[k] = (gi_v3_dot(p[k], fr->u) + 1.0f) * 0.5f * NS;
        y[k] = (gi_v3_dot(p[k], fr->v) + 1.0f) * 0.5f * NS;
        z[k] = gi_v3_dot(p[k], fr->n);
    }
    float area2 = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
    if (fabsf(area2) < 1e-9f)
        return 1;
    int N = (int)(f->prm.N * f->prm.S);
    int x0 = (int)floorf(fminf(x[0], fminf(x[1], x[2])) - 0.5f),
        x1 = (int)ceilf(fmaxf(x[0], fmaxf(x[1], x[2])));
    int y0 = (int)floorf(fminf(y[0], fminf(y[1], y[2])) - 0.5f),
        y1 = (int)ceilf(fmaxf(y[0], fmaxf(y[1], y[2])));
    if (x0 < 0)
        x0 = 0;
    if (y0 < 0)
        y0 = 0;
    if (x1 > N - 1)
        x1 = N - 1;
    if (y1 > N - 1)
        y1 = N - 1;
    float inv = 1.0f / area2;
    for (int cy = y0; cy <= y1; cy++) {
        float py = (float)cy + 0.5f;
        for (int cx = x0; cx <= x1; cx++) {
            float px = (float)cx + 0.5f;
            float w1 = ((px - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (py - y[0])) * inv;
            float w2 = ((x[1] - x[0]) * (py - y[0]) - (px - x[0]) * (y[1] - y[0])) * inv;
            float w0 = 1.0f - w1 - w2;
            if (w0 < 0.0f || w1 < 0.0f || w2 < 0.0f)
                continue;
            float depth = w0 * z[0] + w1 * z[1] + w2 * z[2];
            if (!emit(user, (uint32_t)cx, (uint32_t)cy, depth))
                return 0;
        }
    }
    return 1;
}

typedef struct sort_ctx {
    frag_buf *buf;
    const vlf_field *f;
    const vlf_psf *psf;
    const vlf_face *face;
    uint32_t N;
    int32_t *bbox; /* minx, miny, maxx, maxy of the face in this subfield */
} sort_ctx;

static int emit_frag(void *user, uint32_t cx, uint32_t cy, float depth)
{
    sort_ctx *c = user;
    int32_t *bb = c->bbox;
    int32_t X = (int32_t)(cx / c->f->prm.S),
            Y = (int32_t)(cy / c->f->prm.S); /* the subfield's cell */
    if (X < bb[0])
        bb[0] = X;
    if (Y < bb[1])
        bb[1] = Y;
    if (X > bb[2])
        bb[2] = X;
    if (Y > bb[3])
        bb[3] = Y;
    float U = ((float)cx + 0.5f) / (float)c->N * 2.0f - 1.0f,
          V = ((float)cy + 0.5f) / (float)c->N * 2.0f - 1.0f;
    gi_vec3 q = gi_v3_add(gi_v3_add(gi_v3_scale(c->psf->u, U), gi_v3_scale(c->psf->v, V)),
                          gi_v3_scale(c->psf->n, depth));
    uint32_t e = vlf_element_at(c->f, c->face, q);
    if (c->face->twin < 0)
        return frag_push(c->buf, cy * c->N + cx, depth, 0, e);
    /* A double-sided face (§3.1: values for both sides): two fragments at
     * the same depth, first the side facing against +w (the receiver of the
     * sweep along +w), then the side facing along +w; the sweep along -w
     * walks them the other way, so each sweep meets its receiver first and
     * its sender second. The two charts are the same, so the element index
     * differs by the charts' offset. */
    const vlf_face *tw = &c->f->faces[c->face->twin];
    uint32_t e2 = tw->first_elem + (e - c->face->first_elem);
    int own_first = gi_v3_dot(c->face->n, c->psf->n) < 0.0f;
    return frag_push(c->buf, cy * c->N + cx, depth, 0, own_first ? e : e2) &&
           frag_push(c->buf, cy * c->N + cx, depth, 1, own_first ? e2 : e);
}

static int frag_cmp(const void *a, const void *b)
{
    const frag_tmp *x = a, *y = b;
    if (x->cell != y->cell)
        return x->cell < y->cell ? -1 : 1;
    if (x->depth != y->depth)
        return x->depth < y->depth ? -1 : 1;
    if (x->rank != y->rank)
        return x->rank < y->rank ? -1 : 1;
    return x->elem < y->elem ? -1 : (x->elem > y->elem);
}

/* Sort counters of one thread. */
typedef struct sort_counts {
    uint64_t pieces, splits, bsp_cuts, unresolved, tests, groups, fallbacks;
} sort_counts;

/* The fragments of every face along subfield frame fr, in buf, grouped by
 * ray (interface cell) and front to back along fr->n within each ray
 * (§3.2). Faces order: the faces sorted by vlf_sort_faces and rasterised in
 * that order, each ray's fragments then kept in the order they came
 * (a stable bucket sort by cell); rays order: all fragments sorted by cell
 * and depth. bbox (4 per face, may be NULL) grows by the subfield cells
 * each face covers. */
static int list_fragments(const vlf_field *f, const vlf_psf *fr, frag_buf *buf, frag_buf *tmp,
                          vlf_sorter *so, int32_t *bbox, sort_counts *cnt)
{
    uint32_t N = f->prm.N * f->prm.S;
    int32_t dummy[4];
    buf->n = 0;
    if (f->prm.order == VLF_ORDER_RAYS) {
        for (uint32_t ti = 0; ti < f->tri_count; ti++) {
            uint32_t fi = f->tri_face[ti];
            sort_ctx c = {buf, f, fr, &f->faces[fi], N, bbox ? bbox + 4 * fi : dummy};
            if (!raster_tri(f, fr, f->tri_p + 3 * (size_t)ti, emit_frag, &c))
                return 0;
        }
        qsort(buf->v, buf->n, sizeof *buf->v, frag_cmp);
        return 1;
    }
    int mode = f->prm.order == VLF_ORDER_PLAIN     ? VLF_SORT_PLAIN
               : f->prm.order == VLF_ORDER_NOSPLIT ? VLF_SORT_NOSPLIT
                                                   : VLF_SORT_NEWELL;
    if (vlf_sort_faces(so, f->tri_p, f->tri_count, f->tri_group, f->prm.hier_min, fr->u, fr->v,
                       fr->n, mode, f->prm.bsp_levels, f->prm.bsp_min) != 0)
        return 0;
    cnt->pieces += so->nout;
    cnt->splits += so->splits;
    cnt->bsp_cuts += so->bsp_cuts;
    cnt->unresolved += so->unresolved;
    cnt->tests += so->tests;
    cnt->groups += so->groups;
    cnt->fallbacks += so->hier_fallbacks;
    for (uint32_t k = 0; k < so->nout; k++) {
        const vlf_piece *pc = &so->poly[so->out[k]];
        uint32_t fi = f->tri_face[pc->tri];
        sort_ctx c = {buf, f, fr, &f->faces[fi], N, bbox ? bbox + 4 * fi : dummy};
        /* back from the frame to VLF coordinates; a fan over the convex piece */
        gi_vec3 q[3];
        const gi_vec3 *v = so->vert + pc->first;
        for (uint32_t j = 1; j + 1 < pc->count; j++) {
            const gi_vec3 *w[3] = {&v[0], &v[j], &v[j + 1]};
            for (int a = 0; a < 3; a++)
                q[a] =
                    gi_v3_add(gi_v3_add(gi_v3_scale(fr->u, w[a]->x), gi_v3_scale(fr->v, w[a]->y)),
                              gi_v3_scale(fr->n, w[a]->z));
            if (!raster_tri(f, fr, q, emit_frag, &c))
                return 0;
        }
    }
    /* stable bucket sort by cell: each ray keeps the faces' order */
    uint32_t *start = calloc((size_t)N * N + 1, sizeof *start);
    if (!start)
        return 0;
    if (tmp->cap < buf->n) {
        frag_tmp *t = realloc(tmp->v, (buf->n ? buf->n : 1) * sizeof *t);
        if (!t) {
            free(start);
            return 0;
        }
        tmp->v = t;
        tmp->cap = buf->n ? buf->n : 1;
    }
    for (size_t k = 0; k < buf->n; k++)
        start[buf->v[k].cell + 1]++;
    for (uint32_t c = 0; c < N * N; c++)
        start[c + 1] += start[c];
    for (size_t k = 0; k < buf->n; k++)
        tmp->v[start[buf->v[k].cell]++] = buf->v[k];
    free(start);
    tmp->n = buf->n;
    frag_buf sw = *buf;
    *buf = *tmp;
    *tmp = sw;
    return 1;
}

/* Depth order of subfield i (the "sort" stage, §3.2): the fragments of
 * every face on the N S x N S rays, each ray's front to back
 * (list_fragments); the tile rectangles of non-diffuse faces recorded on
 * the way. Writes only psf[i] and the rectangles of subfield i. */
static int build_psf(vlf_field *f, uint32_t i, frag_buf *buf, frag_buf *tmp, vlf_sorter *so,
                     sort_counts *cnt)
{
    vlf_rect *rects = f->rects;
    vlf_psf *p = &f->psf[i];
    gi_vec3 w = f->dirs.signed_dirs[i];
    p->n = w;
    gi_onb(w, &p->u, &p->v);
    uint32_t N = f->prm.N * f->prm.S, m = f->prm.m;
    int32_t *bbox = malloc(((size_t)f->face_count * 4 + 4) * sizeof *bbox);
    if (!bbox)
        return 0;
    for (uint32_t fi = 0; fi < f->face_count; fi++) {
        bbox[4 * fi] = bbox[4 * fi + 1] = INT32_MAX;
        bbox[4 * fi + 2] = bbox[4 * fi + 3] = -1;
    }
    if (!list_fragments(f, p, buf, tmp, so, bbox, cnt)) {
        free(bbox);
        return 0;
    }
    for (uint32_t fi = 0; fi < f->face_count; fi++) /* a back side covers the cells of its front */
        if (f->faces[fi].back)
            memcpy(bbox + 4 * fi, bbox + 4 * (size_t)f->faces[fi].twin, 4 * sizeof *bbox);
    for (uint32_t fi = 0; fi < f->face_count; fi++) {
        if (f->faces[fi].nd < 0)
            continue;
        vlf_rect *r = &rects[(size_t)f->faces[fi].nd * f->prm.l + i];
        const int32_t *bb = bbox + 4 * fi;
        if (bb[2] < 0) {
            *r = (vlf_rect){0, 0, 0, 0, 0};
        } else {
            int32_t tx0 = bb[0] / (int32_t)m, ty0 = bb[1] / (int32_t)m;
            int32_t tx1 = bb[2] / (int32_t)m, ty1 = bb[3] / (int32_t)m;
            *r = (vlf_rect){tx0 * (int32_t)m, ty0 * (int32_t)m, (uint32_t)(tx1 - tx0 + 1) * m,
                            (uint32_t)(ty1 - ty0 + 1) * m, 0};
        }
    }
    free(bbox);
    p->cell_start = calloc((size_t)N * N + 1, sizeof *p->cell_start);
    p->frag = malloc((buf->n ? buf->n : 1) * sizeof *p->frag);
    if (!p->cell_start || !p->frag)
        return 0;
    p->frag_count = (uint32_t)buf->n;
    for (size_t k = 0; k < buf->n; k++) {
        p->cell_start[buf->v[k].cell + 1]++;
        p->frag[k] = buf->v[k].elem;
    }
    for (uint32_t c = 0; c < N * N; c++)
        p->cell_start[c + 1] += p->cell_start[c];
    return 1;
}

/* One thread of the sort stage: subfields t, t + T, t + 2T, ... (each
 * subfield's order depends on nothing else, so any thread count gives the
 * same field). */
typedef struct sort_job {
    vlf_field *f;
    uint32_t t, T;
    int ok;
    sort_counts cnt;
} sort_job;

static void *sort_thread(void *arg)
{
    sort_job *j = arg;
    frag_buf buf = {0}, tmp = {0};
    vlf_sorter so;
    memset(&so, 0, sizeof so);
    j->ok = 1;
    for (uint32_t i = j->t; i < j->f->prm.l && j->ok; i += j->T)
        j->ok = build_psf(j->f, i, &buf, &tmp, &so, &j->cnt);
    free(buf.v);
    free(tmp.v);
    vlf_sorter_free(&so);
    return NULL;
}

/* The sort stage on p->threads threads (the calling one among them). */
static int build_all_psf(vlf_field *f)
{
    uint32_t T = f->prm.threads < 1 ? 1 : f->prm.threads;
    if (T > f->prm.l)
        T = f->prm.l;
    sort_job *jobs = calloc(T, sizeof *jobs);
    pthread_t *th = calloc(T, sizeof *th);
    uint8_t *started = calloc(T, 1);
    if (!jobs || !th || !started) {
        free(jobs), free(th), free(started);
        return 0;
    }
    for (uint32_t t = 0; t < T; t++) {
        jobs[t] = (sort_job){f, t, T, 0, {0, 0, 0, 0, 0, 0, 0}};
        if (t > 0)
            started[t] = pthread_create(&th[t], NULL, sort_thread, &jobs[t]) == 0;
    }
    sort_thread(&jobs[0]);
    int ok = jobs[0].ok;
    for (uint32_t t = 1; t < T; t++) {
        if (started[t])
            pthread_join(th[t], NULL);
        else
            sort_thread(&jobs[t]); /* no thread to be had: do its share here */
        ok = ok && jobs[t].ok;
    }
    for (uint32_t t = 0; t < T; t++) {
        f->st.sort_pieces += jobs[t].cnt.pieces;
        f->st.sort_splits += jobs[t].cnt.splits;
        f->st.sort_bsp_cuts += jobs[t].cnt.bsp_cuts;
        f->st.sort_unresolved += jobs[t].cnt.unresolved;
        f->st.sort_tests += jobs[t].cnt.tests;
        f->st.sort_groups += jobs[t].cnt.groups;
        f->st.sort_hier_fallbacks += jobs[t].cnt.fallbacks;
    }
    free(jobs), free(th), free(started);
    return ok;
}

static size_t rect_slot(const vlf_rect *r, uint32_t cx, uint32_t cy)
{
    return r->offset + (size_t)((int32_t)cy - r->y0) * r->w + (size_t)((int32_t)cx - r->x0);
}

typedef struct tri_key {
    uint32_t tri, material;
    int32_t nx, ny, nz, d;
} tri_key;

static int key_cmp(const void *a, const void *b)
{
    const tri_key *x = a, *y = b;
    const int32_t kx[5] = {(int32_t)x->material, x->nx, x->ny, x->nz, x->d};
    const int32_t ky[5] = {(int32_t)y->material, y->nx, y->ny, y->nz, y->d};
    for (int k = 0; k < 5; k++)
        if (kx[k] != ky[k])
            return kx[k] < ky[k] ? -1 : 1;
    return x->tri < y->tri ? -1 : (x->tri > y->tri);
}

/* Faces: the scene's triangles grouped by material and plane (normal and
 * offset to 1e-3), each group one face with a chart of density texels per
 * unit length over its bounding rectangle in the plane (§3.1: one
 * irradiance texture per face; the charts are the atlas). */
static int group_faces(vlf_field *f, const gi_scene *s, float t)
{
    uint32_t T = s->triangle_count;
    f->tri_count = T;
    f->tri_face = malloc((size_t)T * sizeof *f->tri_face);
    f->tri_group = malloc((size_t)T * sizeof *f->tri_group);
    f->tri_p = malloc((size_t)T * 3 * sizeof *f->tri_p);
    tri_key *keys = malloc((size_t)T * sizeof *keys);
    gi_vec3 *nrm = malloc((size_t)T * sizeof *nrm);
    f->faces = calloc((size_t)T * 2, sizeof *f->faces); /* double-sided faces take two */
    if (!f->tri_face || !f->tri_group || !f->tri_p || !keys || !nrm || !f->faces) {
        free(keys);
        free(nrm);
        return 0;
    }
    for (uint32_t ti = 0; ti < T; ti++) {
        gi_vec3 w[3];
        gi_scene_triangle_world(s, ti, t, w);
        gi_vec3 *p = f->tri_p + 3 * (size_t)ti;
        for (int k = 0; k < 3; k++)
            p[k] = vlf_to_vlf(f, w[k]);
        f->tri_group[ti] = s->vertices[s->indices[3 * ti]].object;
        gi_vec3 n = gi_v3_normalize(gi_v3_cross(gi_v3_sub(p[1], p[0]), gi_v3_sub(p[2], p[0])));
        nrm[ti] = n;
        keys[ti] = (tri_key){ti,
                             s->vertices[s->indices[3 * ti]].material,
                             (int32_t)lrintf(n.x * 1000.0f),
                             (int32_t)lrintf(n.y * 1000.0f),
                             (int32_t)lrintf(n.z * 1000.0f),
                             (int32_t)lrintf(gi_v3_dot(n, p[0]) * 1000.0f)};
    }
    qsort(keys, T, sizeof *keys, key_cmp);
    uint32_t nf = 0;
    for (uint32_t a = 0; a < T;) {
        uint32_t b = a + 1;
        while (b < T && key_cmp(&(tri_key){0, keys[a].material, keys[a].nx, keys[a].ny, keys[a].nz,
                                           keys[a].d},
                                &(tri_key){0, keys[b].material, keys[b].nx, keys[b].ny, keys[b].nz,
                                           keys[b].d}) == 0)
            b++;
        vlf_face *fc = &f->faces[nf];
        uint32_t t0 = keys[a].tri;
        gi_vec3 n = gi_v3(0, 0, 0);
        for (uint32_t k = a; k < b; k++) {
            const gi_vec3 *p = f->tri_p + 3 * (size_t)keys[k].tri;
            gi_vec3 c = gi_v3_cross(gi_v3_sub(p[1], p[0]), gi_v3_sub(p[2], p[0]));
            n = gi_v3_add(n, c);
            fc->area += 0.5f * gi_v3_length(c);
            f->tri_face[keys[k].tri] = nf;
        }
        fc->n = gi_v3_length(n) > 0.0f ? gi_v3_normalize(n) : nrm[t0];
        gi_onb(fc->n, &fc->t, &fc->b);
        float lo[2] = {FLT_MAX, FLT_MAX}, hi[2] = {-FLT_MAX, -FLT_MAX};
        gi_vec3 p0 = f->tri_p[3 * (size_t)t0];
        for (uint32_t k = a; k < b; k++)
            for (int c = 0; c < 3; c++) {
                gi_vec3 d = gi_v3_sub(f->tri_p[3 * (size_t)keys[k].tri + (size_t)c], p0);
                float x = gi_v3_dot(d, fc->t), y = gi_v3_dot(d, fc->b);
                lo[0] = fminf(lo[0], x), lo[1] = fminf(lo[1], y);
                hi[0] = fmaxf(hi[0], x), hi[1] = fmaxf(hi[1], y);
            }
        fc->origin = gi_v3_add(p0, gi_v3_add(gi_v3_scale(fc->t, lo[0]), gi_v3_scale(fc->b, lo[1])));
        float W = ceilf((hi[0] - lo[0]) * f->prm.density),
              H = ceilf((hi[1] - lo[1]) * f->prm.density);
        fc->W = W < 1.0f ? 1u : W > 1024.0f ? 1024u : (uint32_t)W;
        fc->H = H < 1.0f ? 1u : H > 1024.0f ? 1024u : (uint32_t)H;
        const gi_material *mt = &s->materials[keys[a].material];
        memcpy(fc->kd, mt->albedo, sizeof fc->kd);
        memcpy(fc->ks, mt->ks, sizeof fc->ks);
        fc->exponent = mt->exponent;
        fc->material = keys[a].material;
        fc->textured = mt->albedo_texture >= 0 && (uint32_t)mt->albedo_texture < s->texture_count;
        fc->mirror = mt->mirror || mt->exponent >= GI_MIRROR_EXPONENT;
        for (int k = 0; k < VLF_ALBEDO_TABLE; k++)
            fc->albedo[k] = fc->mirror
                                ? 1.0f
                                : (float)vlf_phong_albedo(fc->exponent,
                                                          (float)k / (float)(VLF_ALBEDO_TABLE - 1));
        const float *le = gi_scene_triangle_emission(s, t0);
        for (int k = 0; k < 3; k++)
            fc->emission[k] = le ? le[k] : 0.0f;
        fc->twin = -1;
        if (mt->double_sided) {
            /* the back side (§3.1: receiver faces store values for both
             * sides): the same plane and chart, the normal reversed; it
             * emits too (glTF doubleSided) */
            vlf_face *bk = &f->faces[nf + 1];
            *bk = *fc;
            bk->n = gi_v3_scale(fc->n, -1.0f);
            bk->back = 1;
            fc->twin = (int32_t)nf + 1;
            bk->twin = (int32_t)nf;
            nf++;
        }
        nf++;
        a = b;
    }
    f->face_count = nf;
    free(keys);
    free(nrm);
    return 1;
}

/* Clips polygon (x, y)[n] to the half-plane s * (coord k) <= c; returns
 * the new count (Sutherland-Hodgman). */
static int clip_poly(float *x, float *y, int n, int k, float s, float c)
{
    float ox[16], oy[16];
    int m = 0;
    for (int i = 0; i < n; i++) {
        int j = (i + 1) % n;
        float vi = s * (k ? y[i] : x[i]) - c, vj = s * (k ? y[j] : x[j]) - c;
        if (vi <= 0.0f && m < 16)
            ox[m] = x[i], oy[m] = y[i], m++;
        if ((vi < 0.0f && vj > 0.0f) || (vi > 0.0f && vj < 0.0f)) {
            float t = vi / (vi - vj);
            if (m < 16)
                ox[m] = x[i] + t * (x[j] - x[i]), oy[m] = y[i] + t * (y[j] - y[i]), m++;
        }
    }
    memcpy(x, ox, (size_t)m * sizeof *x);
    memcpy(y, oy, (size_t)m * sizeof *y);
    return m;
}

/* Area of each element inside its face: every triangle clipped exactly
 * against the texels of its bounding box. */
static void element_areas(vlf_field *f, const gi_scene *s)
{
    float texel = 1.0f / (f->prm.density * f->prm.density);
    for (uint32_t ti = 0; ti < f->tri_count; ti++) {
        const vlf_face *fc = &f->faces[f->tri_face[ti]];
        const gi_vec3 *p = f->tri_p + 3 * (size_t)ti;
        float x[3], y[3];
        for (int k = 0; k < 3; k++) {
            gi_vec3 d = gi_v3_sub(p[k], fc->origin);
            x[k] = gi_v3_dot(d, fc->t) * f->prm.density;
            y[k] = gi_v3_dot(d, fc->b) * f->prm.density;
        }
        int x0 = (int)floorf(fminf(x[0], fminf(x[1], x[2]))),
            x1 = (int)floorf(fmaxf(x[0], fmaxf(x[1], x[2])));
        int y0 = (int)floorf(fminf(y[0], fminf(y[1], y[2]))),
            y1 = (int)floorf(fmaxf(y[0], fmaxf(y[1], y[2])));
        for (int ty = y0; ty <= y1; ty++)
            for (int tx = x0; tx <= x1; tx++) {
                float px[16] = {x[0], x[1], x[2]}, py[16] = {y[0], y[1], y[2]};
                int n = 3;
                n = clip_poly(px, py, n, 0, 1.0f, (float)tx + 1.0f);
                n = clip_poly(px, py, n, 0, -1.0f, -(float)tx);
                n = clip_poly(px, py, n, 1, 1.0f, (float)ty + 1.0f);
                n = clip_poly(px, py, n, 1, -1.0f, -(float)ty);
                float a = 0.0f, mx = 0.0f, my = 0.0f;
                for (int i = 0; i < n; i++) {
                    int j = (i + 1) % n;
                    float c = px[i] * py[j] - px[j] * py[i];
                    a += c;
                    mx += (px[i] + px[j]) * c;
                    my += (py[i] + py[j]) * c;
                }
                int cx = tx < 0 ? 0 : tx >= (int)fc->W ? (int)fc->W - 1 : tx;
                int cy = ty < 0 ? 0 : ty >= (int)fc->H ? (int)fc->H - 1 : ty;
                uint32_t e = fc->first_elem + (uint32_t)cy * fc->W + (uint32_t)cx;
                float ar = 0.5f * fabsf(a) * texel;
                f->elem_area[e] += ar;
                if (fc->textured && a != 0.0f) {
                    /* textured albedo: the texture at the part's centroid
                     * (barycentric in the triangle), weighted by its area */
                    float qx = mx / (3.0f * a), qy = my / (3.0f * a);
                    float d2 = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
                    if (d2 != 0.0f) {
                        float w1 = ((qx - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (qy - y[0])) / d2;
                        float w2 = ((x[1] - x[0]) * (qy - y[0]) - (qx - x[0]) * (y[1] - y[0])) / d2;
                        float w0 = 1.0f - w1 - w2, uv[2] = {0.0f, 0.0f}, alb[3];
                        const float w[3] = {w0, w1, w2};
                        for (int k = 0; k < 3; k++)
                            for (int c = 0; c < 2; c++)
                                uv[c] += w[k] *
                                         s->vertices[s->indices[3 * (size_t)ti + (size_t)k]].uv[c];
                        gi_scene_albedo(s, fc->material, uv, alb);
                        for (int c = 0; c < 3; c++)
                            f->elem_kd[3 * (size_t)e + (size_t)c] += ar * alb[c];
                    }
                }
                if (a != 0.0f) { /* area-weighted centroid of the part on the face, texel units */
                    f->elem_c[2 * (size_t)e] += ar * mx / (3.0f * a);
                    f->elem_c[2 * (size_t)e + 1] += ar * my / (3.0f * a);
                }
            }
    }
}

/* Cuts every triangle into k^2 (a regular grid of its barycentric
 * coordinates, the winding kept): the same surfaces as more faces, for the
 * paper's claim that propagation is linear in the number of faces. */
static int subdivide_triangles(vlf_field *f, uint32_t k)
{
    f->tri_sub = k * k;
    if (k <= 1)
        return 1;
    size_t T = (size_t)f->tri_count * k * k;
    gi_vec3 *P = malloc(T * 3 * sizeof *P);
    uint32_t *F = malloc(T * sizeof *F), *Gr = malloc(T * sizeof *Gr);
    if (!P || !F || !Gr) {
        free(P), free(F), free(Gr);
        return 0;
    }
    size_t n = 0;
    float inv = 1.0f / (float)k;
    for (uint32_t ti = 0; ti < f->tri_count; ti++) {
        const gi_vec3 *p = f->tri_p + 3 * (size_t)ti;
        gi_vec3 e1 = gi_v3_sub(p[1], p[0]), e2 = gi_v3_sub(p[2], p[0]);
#define GRID(a, b)                                                                                 \
    gi_v3_add(p[0], gi_v3_add(gi_v3_scale(e1, (float)(a)*inv), gi_v3_scale(e2, (float)(b)*inv)))
        for (uint32_t a = 0; a < k; a++)
            for (uint32_t b = 0; a + b < k; b++) {
                gi_vec3 *q = P + 3 * n;
                q[0] = GRID(a, b), q[1] = GRID(a + 1, b), q[2] = GRID(a, b + 1);
                Gr[n] = f->tri_group[ti];
                F[n++] = f->tri_face[ti];
                if (a + b + 2 <= k) {
                    q = P + 3 * n;
                    q[0] = GRID(a + 1, b), q[1] = GRID(a + 1, b + 1), q[2] = GRID(a, b + 1);
                    Gr[n] = f->tri_group[ti];
                    F[n++] = f->tri_face[ti];
                }
            }
#undef GRID
    }
    free(f->tri_p);
    free(f->tri_face);
    free(f->tri_group);
    f->tri_p = P;
    f->tri_face = F;
    f->tri_group = Gr;
    f->tri_count = (uint32_t)n;
    return 1;
}

int vlf_field_build(vlf_field *f, const gi_scene *s, float t, const vlf_params *p, char *err,
                    size_t err_size)
{
    memset(f, 0, sizeof *f);
    f->prm = *p;
    double t0 = now_s();
    if (p->precision > VLF_PREC_RGB9E5) {
        snprintf(err, err_size, "vlf: storage precision %u unknown", p->precision);
        return -1;
    }
    if (p->S < 1 || p->S > 8) {
        snprintf(err, err_size, "vlf: supersampling S = %u outside 1..8", p->S);
        return -1;
    }
    if (p->N < 4 || p->m < 1 || p->N % p->m != 0) {
        snprintf(err, err_size, "vlf: N = %u must be a multiple of the tile size m = %u", p->N,
                 p->m);
        return -1;
    }
    double ray_bytes =
        (double)p->l * (double)(p->N * p->S) * (double)(p->N * p->S) * sizeof(uint32_t);
    if (ray_bytes > 2.0 * 1024 * 1024 * 1024) {
        snprintf(err, err_size,
                 "vlf: l (N S)^2 = %.3g rays need %.1f GB of depth lists alone; lower l, N or S",
                 ray_bytes / sizeof(uint32_t), ray_bytes / (1024.0 * 1024 * 1024));
        return -1;
    }
    if (vlf_dirs_build(&f->dirs, p->l, err, err_size) != 0)
        return -1;
    if (s->triangle_count == 0) {
        snprintf(err, err_size, "vlf: the scene has no triangles");
        return -1;
    }
    float b[6];
    gi_scene_bounds_at(s, t, b);
    f->centre = gi_v3(0.5f * (b[0] + b[3]), 0.5f * (b[1] + b[4]), 0.5f * (b[2] + b[5]));
    f->radius = 0.5f * sqrtf((b[3] - b[0]) * (b[3] - b[0]) + (b[4] - b[1]) * (b[4] - b[1]) +
                             (b[5] - b[2]) * (b[5] - b[2]));
    f->radius *= 1.001f;
    if (!(f->radius > 0.0f) || !isfinite(f->radius)) {
        snprintf(err, err_size, "vlf: the scene's bounds are empty or not finite");
        return -1;
    }
    f->env = s->envmap;
    /* Directional lights (not in the paper, which has emissive faces and
     * sky): parallel light, so it enters like the sky of Fig. 6, into the
     * interfaces of the three directions around the light's with their
     * barycentric weights, radiance alpha E / dOmega, so that each carries
     * alpha E through a unit of area across it. */
    f->sun = calloc((size_t)p->l * 2 * 3, sizeof *f->sun);
    if (!f->sun)
        goto oom;
    for (uint32_t li = 0; li < s->light_count; li++) {
        if (s->lights[li].type != GI_LIGHT_DIRECTIONAL)
            continue;
        gi_light_frame fr = gi_scene_light_at(s, li, t);
        float len = gi_v3_length(fr.direction);
        if (!(len > 0.0f))
            continue;
        uint32_t node[3];
        float al[3];
        vlf_dirs_locate(&f->dirs, gi_v3_scale(fr.direction, 1.0f / len), node, al);
        for (int k = 0; k < 3; k++)
            for (int q = 0; q < 3; q++)
                f->sun[3 * node[k] + (uint32_t)q] +=
                    al[k] * s->lights[li].intensity[q] / f->dirs.solid_angle[node[k]];
        f->sun_count++;
    }
    /* Point and spot lights: a first shot by shadow rays (punctual_first_shot). */
    for (uint32_t li = 0; li < s->light_count; li++)
        f->punctual_count += s->lights[li].type != GI_LIGHT_DIRECTIONAL;
    if (f->punctual_count) {
        f->punctual = calloc(f->punctual_count, sizeof *f->punctual);
        if (!f->punctual)
            goto oom;
        uint32_t k = 0;
        for (uint32_t li = 0; li < s->light_count; li++) {
            const gi_light *L = &s->lights[li];
            if (L->type == GI_LIGHT_DIRECTIONAL)
                continue;
            gi_light_frame fr = gi_scene_light_at(s, li, t);
            vlf_punctual *P = &f->punctual[k++];
            P->spot = L->type == GI_LIGHT_SPOT;
            P->pos = fr.position;
            P->dir = fr.direction;
            memcpy(P->I, L->intensity, sizeof P->I);
            P->range = L->range;
            P->cos_inner = cosf(L->inner_cone);
            P->cos_outer = cosf(L->outer_cone);
        }
        gi_error e;
        if (gi_rt_create(s, t, &f->rt, &e) != GI_OK) {
            snprintf(err, err_size, "vlf: shadow rays for the point lights: %s", e.text);
            return -1;
        }
    }
    if (!group_faces(f, s, t))
        goto oom;
    uint32_t elems = 0;
    for (uint32_t fi = 0; fi < f->face_count; fi++) {
        vlf_face *fc = &f->faces[fi];
        fc->first_elem = elems;
        elems += fc->W * fc->H;
        fc->nd = (fc->ks[0] > 0.0f || fc->ks[1] > 0.0f || fc->ks[2] > 0.0f) ? (int32_t)f->nd_count++
                                                                            : -1;
        /* Diffuse emission normalised so that the discrete directions carry
         * exactly pi L per unit area out of the face. */
        double sum = 0.0;
        for (uint32_t sd = 0; sd < 2 * p->l; sd++) {
            float c2 = gi_v3_dot(fc->n, f->dirs.signed_dirs[sd]);
            if (c2 > 0.0f)
                sum += c2 * f->dirs.solid_angle[sd];
        }
        fc->send_scale = sum > 0.0 ? (float)(GI_PI / sum) : 1.0f;
    }
    f->elem_count = elems;
    f->elem_face = malloc((size_t)elems * sizeof *f->elem_face);
    f->elem_area = calloc((size_t)elems, sizeof *f->elem_area);
    f->elem_c = calloc((size_t)elems * 2 + 2, sizeof *f->elem_c);
    f->E_tot = calloc((size_t)elems * 3, sizeof(float));
    f->E_next = calloc((size_t)elems * 3, sizeof(float));
    f->L_cur = calloc((size_t)elems * 3, sizeof(float));
    f->psf = calloc(p->l, sizeof *f->psf);
    f->rects = calloc((size_t)f->nd_count * p->l + 1, sizeof *f->rects);
    if (!f->elem_face || !f->elem_area || !f->elem_c || !f->E_tot || !f->E_next || !f->L_cur ||
        !f->psf || !f->rects)
        goto oom;
    for (uint32_t fi = 0; fi < f->face_count; fi++) {
        vlf_face *fc = &f->faces[fi];
        for (uint32_t e = 0; e < fc->W * fc->H; e++)
            f->elem_face[fc->first_elem + e] = fi;
    }
    f->elem_kd = calloc((size_t)elems * 3 + 3, sizeof *f->elem_kd);
    if (!f->elem_kd)
        goto oom;
    element_areas(f, s);
    /* a back side's elements are its front's texels: the same areas,
     * centroids and (textured) albedo sums */
    for (uint32_t fi = 0; fi < f->face_count; fi++) {
        const vlf_face *fc = &f->faces[fi];
        if (!fc->back)
            continue;
        const vlf_face *fr = &f->faces[fc->twin];
        for (uint32_t e = 0; e < fc->W * fc->H; e++) {
            size_t d = fc->first_elem + e, o = fr->first_elem + e;
            f->elem_area[d] = f->elem_area[o];
            memcpy(f->elem_c + 2 * d, f->elem_c + 2 * o, 2 * sizeof *f->elem_c);
            memcpy(f->elem_kd + 3 * d, f->elem_kd + 3 * o, 3 * sizeof *f->elem_kd);
        }
    }
    /* each element's albedo: the material's, or on textured faces the
     * texture averaged over the element's part of the face */
    for (uint32_t e = 0; e < elems; e++) {
        const vlf_face *fc = &f->faces[f->elem_face[e]];
        for (int c = 0; c < 3; c++) {
            float *kd = &f->elem_kd[3 * (size_t)e + (size_t)c];
            *kd = fc->textured && f->elem_area[e] > 0.0f ? *kd / f->elem_area[e] : fc->kd[c];
        }
    }
    for (uint32_t e = 0; e < elems; e++) {
        if (f->elem_area[e] > 0.0f) {
            f->elem_c[2 * (size_t)e] /= f->elem_area[e];
            f->elem_c[2 * (size_t)e + 1] /= f->elem_area[e];
        }
    }
    if ((uint64_t)s->triangle_count * p->subdivide * p->subdivide > 50000000u) {
        snprintf(err, err_size, "vlf: %u triangles cut into %u^2 each are too many",
                 s->triangle_count, p->subdivide);
        return -1;
    }
    if (!subdivide_triangles(f, p->subdivide < 1 ? 1 : p->subdivide) || !build_all_psf(f))
        goto oom;
    /* Tile storage offsets, then coverage of each stored cell. */
    size_t cells = 0;
    uint32_t tiles = 0;
    for (size_t r = 0; r < (size_t)f->nd_count * p->l; r++) {
        f->rects[r].offset = (uint32_t)cells;
        cells += (size_t)f->rects[r].w * f->rects[r].h;
        tiles += f->rects[r].w * f->rects[r].h / (p->m * p->m);
    }
    if (cells > 0x7fffffffu) {
        snprintf(err, err_size, "vlf: %zu non-diffuse cells do not fit (lower N or l)", cells);
        return -1;
    }
    f->nd_cells = (uint32_t)cells;
    size_t nc = cells ? cells : 1;
    f->nd_cover = calloc(nc, 1);
    f->out_cur = calloc(nc * 3, sizeof(float));
    f->out_next = calloc(nc * 3, sizeof(float));
    f->out_tot = calloc(nc * 3, sizeof(float));
    f->in = calloc(nc * 3, sizeof(float));
    if (!f->nd_cover || !f->out_cur || !f->out_next || !f->out_tot || !f->in)
        goto oom;
    size_t frags = 0;
    for (uint32_t i = 0; i < p->l; i++) {
        const vlf_psf *ps = &f->psf[i];
        frags += ps->frag_count;
        uint32_t NS = p->N * p->S;
        for (uint32_t c = 0; c < NS * NS; c++)
            for (uint32_t k = ps->cell_start[c]; k < ps->cell_start[c + 1]; k++) {
                const vlf_face *fc = &f->faces[f->elem_face[ps->frag[k]]];
                if (fc->nd >= 0)
                    f->nd_cover[rect_slot(&f->rects[(size_t)fc->nd * p->l + i], (c % NS) / p->S,
                                          (c / NS) / p->S)] = 1;
            }
    }
    uint32_t ndel = 0;
    for (size_t c = 0; c < cells; c++)
        ndel += f->nd_cover[c];
    f->st.diffuse_elements = elems;
    f->st.nondiffuse_elements = ndel;
    f->st.tiles = tiles;
    /* Memory as the paper counts it: current, next and total ir/radiance
     * maps in the storage format for both kinds (and the incoming tiles),
     * plus the depth order; rendering keeps the totals and the tile index
     * only (vlf.c uploads exactly these maps). */
    size_t bpv = vlf_precision_bytes(p->precision);
    f->st.bytes_maps_render = ((size_t)elems + cells) * bpv;
    f->st.bytes_propagate =
        (size_t)elems * bpv * 3 + cells * bpv * 4 + cells + frags * sizeof(uint32_t) +
        (size_t)p->l * ((size_t)p->N * p->S * p->N * p->S + 1) * sizeof(uint32_t);
    f->st.bytes_render = f->st.bytes_maps_render + (size_t)f->nd_count * p->l * sizeof(vlf_rect);
    f->st.sort_s = now_s() - t0;
    return 0;
oom:
    snprintf(err, err_size, "vlf: out of memory building the light field (N = %u, l = %u)", p->N,
             p->l);
    return -1;
}

/* ---- Propagation (§3.2-§3.4) --------------------------------------------- */

/* Fragments of all faces along a perturbed direction (frame fr), sorted
 * per ray front to back; kept with their depths (§3.5: perturbed
 * directions are sorted like fixed ones, used for transport, discarded). */
static int perturbed_list(vlf_field *f, const vlf_psf *fr, frag_buf *buf, frag_buf *tmp,
                          vlf_sorter *so)
{
    sort_counts cnt = {0, 0, 0, 0, 0, 0, 0};
    return list_fragments(f, fr, buf, tmp, so, NULL, &cnt);
}

/* The tile slot of non-diffuse face fc in fixed subfield i holding VLF
 * point q, or SIZE_MAX where q's cell is outside the face there. */
static size_t slot_at(const vlf_field *f, const vlf_face *fc, uint32_t i, gi_vec3 q)
{
    float x, y, z;
    vlf_psf_project(f, i, q, &x, &y, &z);
    const vlf_rect *r = &f->rects[(size_t)fc->nd * f->prm.l + i];
    int cx = (int)floorf(x) - r->x0, cy = (int)floorf(y) - r->y0;
    if (cx < 0 || cy < 0 || cx >= (int)r->w || cy >= (int)r->h)
        return SIZE_MAX;
    size_t slot = r->offset + (size_t)cy * r->w + (size_t)cx;
    return f->nd_cover[slot] ? slot : SIZE_MAX;
}

/* A sweep along a perturbed direction fr->n (sign: +n or -n) standing in
 * for fixed direction i with weight dW: as sweep() below, but non-diffuse
 * faces read and write the tiles of fixed subfield i at each fragment's
 * point. */
static void sweep_perturbed(vlf_field *f, uint32_t i, const vlf_psf *fr, const frag_buf *buf,
                            int sign, float dW, int first_iteration)
{
    uint32_t S = f->prm.S, N = f->prm.N * S;
    float inv_s2 = 1.0f / (float)(S * S);
    gi_vec3 t = gi_v3_scale(fr->n, (float)sign);
    float cell_area = (2.0f / (float)N) * (2.0f / (float)N);
    float min_area = 1.0f / (64.0f * f->prm.density * f->prm.density);
    float sky[3] = {0, 0, 0};
    if (first_iteration && f->env)
        gi_envmap_eval(f->env, gi_v3_scale(t, -1.0f), sky);
    if (first_iteration)
        for (int q = 0; q < 3; q++)
            sky[q] += f->sun[3 * (sign > 0 ? i : i + f->prm.l) + (uint32_t)q];
    double shot = 0, recv = 0, back = 0, esc = 0;
    size_t a = 0;
    while (a < buf->n) {
        size_t e = a;
        while (e < buf->n && buf->v[e].cell == buf->v[a].cell)
            e++;
        uint32_t c = buf->v[a].cell;
        float U = ((float)(c % N) + 0.5f) / (float)N * 2.0f - 1.0f,
              V = ((float)(c / N) + 0.5f) / (float)N * 2.0f - 1.0f;
        gi_vec3 o = gi_v3_add(gi_v3_scale(fr->u, U), gi_v3_scale(fr->v, V));
        float L[3] = {sky[0], sky[1], sky[2]};
        for (size_t j = 0; j < e - a; j++) {
            const frag_tmp *fg = &buf->v[sign > 0 ? a + j : e - 1 - j];
            uint32_t el = fg->elem;
            const vlf_face *fc = &f->faces[f->elem_face[el]];
            float cs = gi_v3_dot(fc->n, t);
            float lum = L[0] + L[1] + L[2];
            size_t slot = SIZE_MAX;
            if (fc->nd >= 0 && cs != 0.0f)
                slot = slot_at(f, fc, i, gi_v3_add(o, gi_v3_scale(fr->n, fg->depth)));
            if (cs < 0.0f) {
                float s = cell_area * dW / fmaxf(f->elem_area[el], min_area);
                for (int q = 0; q < 3; q++)
                    f->E_next[3 * (size_t)el + q] += L[q] * s;
                if (slot != SIZE_MAX)
                    for (int q = 0; q < 3; q++)
                        f->in[3 * slot + q] += L[q] * inv_s2 / (float)f->prm.perturbed;
                recv += lum;
                L[0] = L[1] = L[2] = 0.0f;
            } else if (cs > 0.0f) {
                back += lum;
                for (int q = 0; q < 3; q++)
                    L[q] = f->L_cur[3 * (size_t)el + q] * fc->send_scale;
                if (slot != SIZE_MAX)
                    for (int q = 0; q < 3; q++)
                        L[q] += f->out_cur[3 * slot + q];
                shot += L[0] + L[1] + L[2];
            }
            f->st.samples++;
        }
        esc += L[0] + L[1] + L[2];
        a = e;
    }
    double w = (double)cell_area * dW / 3.0;
    f->st.flux_shot += shot * w;
    f->st.flux_received += recv * w;
    f->st.flux_back += back * w;
    f->st.flux_escaped += esc * w;
}

/* Perturbed direction k of fixed direction i: uniform in the cap of solid
 * angle dOmega_i around w_i (the paper's samples spread over the solid
 * angle each fixed direction stands for), from a hash of (seed, i, k). */
static gi_vec3 perturbed_dir(const vlf_field *f, uint32_t i, uint32_t k)
{
    uint32_t h = f->prm.seed * 0x9E3779B9u ^ (i * 0x85EBCA6Bu) ^ (k * 0xC2B2AE35u);
    float u[2];
    for (int j = 0; j < 2; j++) {
        h ^= h >> 16;
        h *= 0x7FEB352Du;
        h ^= h >> 15;
        h *= 0x846CA68Bu;
        h ^= h >> 16;
        u[j] = (float)(h >> 8) / 16777216.0f;
    }
    float cos_max = 1.0f - f->dirs.solid_angle[i] / (2.0f * GI_PI);
    float cz = 1.0f - u[0] * (1.0f - cos_max), sz = sqrtf(fmaxf(0.0f, 1.0f - cz * cz));
    float phi = 2.0f * GI_PI * u[1];
    const vlf_psf *p = &f->psf[i];
    return gi_v3_normalize(
        gi_v3_add(gi_v3_scale(p->n, cz),
                  gi_v3_add(gi_v3_scale(p->u, sz * cosf(phi)), gi_v3_scale(p->v, sz * sinf(phi)))));
}

/* The radiance the interface of fixed direction i starts a sweep with
 * (travel direction sign * w_i): the sky's radiance from where the light
 * comes (Fig. 6) and the directional lights', in the first iteration
 * only; black after. */
void vlf_sweep_sky(const vlf_field *f, uint32_t i, int sign, int first_iteration, float sky[3])
{
    uint32_t sd = sign > 0 ? i : i + f->prm.l;
    sky[0] = sky[1] = sky[2] = 0.0f;
    if (first_iteration && f->env)
        gi_envmap_eval(f->env, gi_v3_scale(f->dirs.signed_dirs[sd], -1.0f), sky);
    if (first_iteration)
        for (int q = 0; q < 3; q++)
            sky[q] += f->sun[3 * sd + (uint32_t)q];
}

/* One sweep of subfield i along travel direction t = sign * w_i, front to
 * back along t through every ray's fragments with the radiance interface:
 * receivers (front side facing against t) take the interface's radiance,
 * senders (front side along t) overwrite it with their unshot radiance. */
static void sweep(vlf_field *f, uint32_t i, int sign, int first_iteration)
{
    const vlf_psf *p = &f->psf[i];
    uint32_t S = f->prm.S, N = f->prm.N * S, l = f->prm.l;
    float inv_s2 = 1.0f / (float)(S * S);
    uint32_t sd = sign > 0 ? i : i + l;
    gi_vec3 t = f->dirs.signed_dirs[sd];
    float dW = f->dirs.solid_angle[sd];
    float cell_area = (2.0f / (float)N) * (2.0f / (float)N);
    float sky[3];
    vlf_sweep_sky(f, i, sign, first_iteration, sky);
    double shot = 0, recv = 0, back = 0, esc = 0;
    float min_area = 1.0f / (64.0f * f->prm.density * f->prm.density);
    for (uint32_t c = 0; c < N * N; c++) {
        uint32_t a = p->cell_start[c], e = p->cell_start[c + 1];
        float L[3] = {sky[0], sky[1], sky[2]};
        int32_t step = sign > 0 ? 1 : -1;
        int32_t k = sign > 0 ? (int32_t)a : (int32_t)e - 1,
                end = sign > 0 ? (int32_t)e : (int32_t)a - 1;
        uint32_t cx = (c % N) / S,
                 cy = (c / N) / S; /* the subfield's cell of this interface cell */
        for (; k != end; k += step) {
            uint32_t el = p->frag[k];
            const vlf_face *fc = &f->faces[f->elem_face[el]];
            float cs = gi_v3_dot(fc->n, t);
            float lum = L[0] + L[1] + L[2];
            if (cs < 0.0f) {
                /* receiver */
                float s = cell_area * dW / fmaxf(f->elem_area[el], min_area);
                for (int q = 0; q < 3; q++)
                    f->E_next[3 * (size_t)el + q] += L[q] * s;
                if (fc->nd >= 0) {
                    size_t slot = rect_slot(&f->rects[(size_t)fc->nd * l + i], cx, cy);
                    for (int q = 0; q < 3; q++)
                        f->in[3 * slot + q] += L[q] * inv_s2;
                }
                recv += lum;
                L[0] = L[1] = L[2] = 0.0f;
            } else if (cs > 0.0f) {
                /* sender: what arrived on its back side is absorbed */
                back += lum;
                for (int q = 0; q < 3; q++)
                    L[q] = f->L_cur[3 * (size_t)el + q] * fc->send_scale;
                if (fc->nd >= 0) {
                    size_t slot = rect_slot(&f->rects[(size_t)fc->nd * l + i], cx, cy);
                    for (int q = 0; q < 3; q++)
                        L[q] += f->out_cur[3 * slot + q];
                }
                shot += L[0] + L[1] + L[2];
            }
            f->st.samples++;
        }
        esc += L[0] + L[1] + L[2];
    }
    double w = (double)cell_area * dW / 3.0;
    f->st.flux_shot += shot * w;
    f->st.flux_received += recv * w;
    f->st.flux_back += back * w;
    f->st.flux_escaped += esc * w;
}

/* Bilinear read of face nd's incoming radiance in subfield i at continuous
 * cell position (x, y), over covered cells only. */
static int read_in(const vlf_field *f, const vlf_rect *r, float x, float y, float out[3])
{
    float fx = x - 0.5f - (float)r->x0, fy = y - 0.5f - (float)r->y0;
    int ix = (int)floorf(fx), iy = (int)floorf(fy);
    float ax = fx - (float)ix, ay = fy - (float)iy;
    float wsum = 0.0f;
    out[0] = out[1] = out[2] = 0.0f;
    for (int dy = 0; dy < 2; dy++)
        for (int dx = 0; dx < 2; dx++) {
            int X = ix + dx, Y = iy + dy;
            if (X < 0 || Y < 0 || X >= (int)r->w || Y >= (int)r->h)
                continue;
            size_t slot = r->offset + (size_t)Y * r->w + (size_t)X;
            if (!f->nd_cover[slot])
                continue;
            float wt = (dx ? ax : 1.0f - ax) * (dy ? ay : 1.0f - ay) + 1e-6f;
            for (int q = 0; q < 3; q++)
                out[q] += wt * f->in[3 * slot + q];
            wsum += wt;
        }
    if (wsum <= 0.0f)
        return 0;
    for (int q = 0; q < 3; q++)
        out[q] /= wsum;
    return 1;
}

/* Weights g over the 2l signed directions of light reflected by
 * non-diffuse face fc into direction r (§3.4): mirrors and lobes narrower
 * than the direction set (fewer than ~3 directions' worth of lobe) go to
 * the three nearest directions of r with their barycentric weights, wider
 * Phong lobes to every direction of the lobe; directions below the face
 * get 0. Returns sum_j g_j cos_j dOmega_j divided by the lobe's albedo at
 * this incidence (the normaliser that makes the face reflect ks A(theta) of
 * what arrives: ks at normal incidence, less toward grazing as core
 * brdf.h's lobe; mirrors ks), 0 if nothing is reflected. */
double vlf_reflect_weights(const vlf_field *f, const vlf_face *fc, gi_vec3 r, float *g)
{
    uint32_t n2 = 2 * f->prm.l;
    memset(g, 0, n2 * sizeof *g);
    int lobe = 0;
    if (!fc->mirror) {
        double s1 = 0, s2 = 0;
        for (uint32_t j = 0; j < n2; j++) {
            float cj = gi_v3_dot(f->dirs.signed_dirs[j], r);
            if (cj > 0.0f && gi_v3_dot(f->dirs.signed_dirs[j], fc->n) > 0.0f) {
                g[j] = powf(cj, fc->exponent);
                if (g[j] < 1e-3f)
                    g[j] = 0.0f;
                s1 += g[j];
                s2 += (double)g[j] * g[j];
            }
        }
        lobe = s2 > 0.0 && s1 * s1 / s2 >= 3.0; /* at least ~3 directions in the lobe */
        if (!lobe)
            memset(g, 0, n2 * sizeof *g);
    }
    if (!lobe) {
        uint32_t node[3];
        float al[3];
        vlf_dirs_locate(&f->dirs, r, node, al);
        for (int j = 0; j < 3; j++)
            g[node[j]] += al[j];
    }
    double norm = 0.0;
    for (uint32_t j = 0; j < n2; j++) {
        float cj = gi_v3_dot(f->dirs.signed_dirs[j], fc->n);
        if (g[j] > 0.0f && cj > 0.0f)
            norm += g[j] * cj * f->dirs.solid_angle[j];
        else
            g[j] = 0.0f;
    }
    if (!fc->mirror && norm > 0.0) {
        /* the Phong lobe's albedo at this incidence (its grazing fall-off) */
        float a = vlf_phong_albedo_at(fc, gi_v3_dot(r, fc->n));
        norm = a > 1e-6f ? norm / a : 0.0;
    }
    return norm;
}

/* Irradiance at world point x of surface normal n from the point and spot
 * lights, each through a shadow ray (Embree, core raytrace.h); per light
 * into E + 3 k, and the unit direction toward it into w + k. */
static void punctual_at(const vlf_field *f, gi_vec3 x, gi_vec3 n, float *E, gi_vec3 *w)
{
    for (uint32_t k = 0; k < f->punctual_count; k++) {
        const vlf_punctual *L = &f->punctual[k];
        E[3 * k] = E[3 * k + 1] = E[3 * k + 2] = 0.0f;
        gi_vec3 d = gi_v3_sub(L->pos, x);
        float dist = gi_v3_length(d);
        if (!(dist > 0.0f))
            continue;
        w[k] = gi_v3_scale(d, 1.0f / dist);
        float c = gi_v3_dot(n, w[k]);
        if (c <= 0.0f)
            continue;
        float scale = gi_range_window(dist, L->range) / (dist * dist);
        if (L->spot)
            scale *= gi_spot_falloff(-gi_v3_dot(w[k], L->dir), L->cos_inner, L->cos_outer);
        if (!(scale > 0.0f))
            continue;
        gi_vec3 o = gi_v3_add(x, gi_v3_scale(n, 1e-4f * f->radius));
        float tfar = gi_v3_length(gi_v3_sub(L->pos, o)) * (1.0f - 1e-5f);
        if (gi_rt_occluded(f->rt, o, w[k], 0.0f, tfar))
            continue;
        for (int q = 0; q < 3; q++)
            E[3 * k + (uint32_t)q] = L->I[q] * c * scale;
    }
}

/* The point and spot lights' first shot (not in the paper, which has
 * emissive faces and sky): their direct irradiance on every diffuse
 * element (at the element's centroid on its face) and their reflection by
 * every non-diffuse face into its tiles (each covered cell's point on the
 * face, reflected as §3.4 reflects the interface's light), added to the
 * next maps of the first iteration: shot on from there like received
 * light. */
static int punctual_first_shot(vlf_field *f)
{
    uint32_t P = f->punctual_count, l = f->prm.l;
    float *E = malloc((size_t)P * 3 * sizeof *E), *g = malloc((size_t)2 * l * sizeof *g);
    gi_vec3 *w = malloc((size_t)P * sizeof *w);
    if (!E || !g || !w) {
        free(E), free(g), free(w);
        return 0;
    }
    for (uint32_t e = 0; e < f->elem_count; e++) {
        if (!(f->elem_area[e] > 0.0f))
            continue;
        const vlf_face *fc = &f->faces[f->elem_face[e]];
        gi_vec3 q =
            gi_v3_add(fc->origin,
                      gi_v3_add(gi_v3_scale(fc->t, f->elem_c[2 * (size_t)e] / f->prm.density),
                                gi_v3_scale(fc->b, f->elem_c[2 * (size_t)e + 1] / f->prm.density)));
        punctual_at(f, gi_v3_add(f->centre, gi_v3_scale(q, f->radius)), fc->n, E, w);
        for (uint32_t k = 0; k < P; k++)
            for (int c = 0; c < 3; c++)
                f->E_next[3 * (size_t)e + (size_t)c] += E[3 * k + (uint32_t)c];
    }
    for (uint32_t fi = 0; fi < f->face_count; fi++) {
        const vlf_face *fc = &f->faces[fi];
        if (fc->nd < 0)
            continue;
        for (uint32_t i = 0; i < l; i++) {
            const vlf_rect *rj = &f->rects[(size_t)fc->nd * l + i];
            const vlf_psf *ps = &f->psf[i];
            float dn = gi_v3_dot(ps->n, fc->n);
            if (rj->w == 0 || fabsf(dn) < 1e-6f)
                continue;
            uint32_t sd = dn > 0.0f ? i : i + l; /* the signed direction leaving the front */
            for (uint32_t yy = 0; yy < rj->h; yy++)
                for (uint32_t xx = 0; xx < rj->w; xx++) {
                    size_t slot = rj->offset + (size_t)yy * rj->w + xx;
                    if (!f->nd_cover[slot])
                        continue;
                    float U =
                        ((float)(rj->x0 + (int32_t)xx) + 0.5f) / (float)f->prm.N * 2.0f - 1.0f;
                    float V =
                        ((float)(rj->y0 + (int32_t)yy) + 0.5f) / (float)f->prm.N * 2.0f - 1.0f;
                    gi_vec3 o = gi_v3_add(gi_v3_scale(ps->u, U), gi_v3_scale(ps->v, V));
                    float tt = gi_v3_dot(fc->n, gi_v3_sub(fc->origin, o)) / dn;
                    gi_vec3 q = gi_v3_add(o, gi_v3_scale(ps->n, tt));
                    punctual_at(f, gi_v3_add(f->centre, gi_v3_scale(q, f->radius)), fc->n, E, w);
                    for (uint32_t k = 0; k < P; k++) {
                        if (E[3 * k] <= 0.0f && E[3 * k + 1] <= 0.0f && E[3 * k + 2] <= 0.0f)
                            continue;
                        /* light travelling along -w, reflected about the face */
                        gi_vec3 t = gi_v3_scale(w[k], -1.0f);
                        gi_vec3 r = gi_v3_sub(t, gi_v3_scale(fc->n, 2.0f * gi_v3_dot(t, fc->n)));
                        double norm = vlf_reflect_weights(f, fc, r, g);
                        if (norm <= 0.0 || g[sd] <= 0.0f)
                            continue;
                        for (int c = 0; c < 3; c++)
                            f->out_next[3 * slot + (size_t)c] +=
                                fc->ks[c] * E[3 * k + (uint32_t)c] * (float)(g[sd] / norm);
                    }
                }
        }
    }
    free(E), free(g), free(w);
    return 1;
}

/* Non-diffuse scattering (§3.4): the radiance that subfield i brought to
 * each non-diffuse face is reflected into the subfields around the
 * reflected direction (mirrors and lobes narrower than the direction set:
 * the three nearest, barycentric weights; wider Phong lobes: every
 * direction of the lobe, weighted by it), by backward mapping of each
 * target cell through the face's plane into subfield i. */
static void scatter(vlf_field *f, uint32_t i)
{
    uint32_t l = f->prm.l, n2 = 2 * l;
    float *g = malloc(n2 * sizeof *g);
    if (!g)
        return;
    for (uint32_t fi = 0; fi < f->face_count; fi++) {
        const vlf_face *fc = &f->faces[fi];
        if (fc->nd < 0)
            continue;
        const vlf_rect *ri = &f->rects[(size_t)fc->nd * l + i];
        float ci = gi_v3_dot(fc->n, f->dirs.signed_dirs[i]);
        if (ri->w == 0 || ci == 0.0f)
            continue;
        uint32_t sd_in = ci < 0.0f ? i : i + l; /* travel direction of the incoming light */
        gi_vec3 t = f->dirs.signed_dirs[sd_in];
        float cos_in = fabsf(ci);
        gi_vec3 r = gi_v3_sub(t, gi_v3_scale(fc->n, 2.0f * gi_v3_dot(t, fc->n)));
        double norm = vlf_reflect_weights(f, fc, r, g);
        if (norm <= 0.0)
            continue;
        float scale = (float)((double)cos_in * f->dirs.solid_angle[sd_in] / norm);
        for (uint32_t j = 0; j < n2; j++) {
            if (g[j] <= 0.0f)
                continue;
            uint32_t pj = j % l;
            const vlf_rect *rj = &f->rects[(size_t)fc->nd * l + pj];
            const vlf_psf *P = &f->psf[pj];
            float c[3];
            for (int q = 0; q < 3; q++)
                c[q] = fc->ks[q] * g[j] * scale;
            float dn = gi_v3_dot(P->n, fc->n);
            if (fabsf(dn) < 1e-6f)
                continue;
            for (uint32_t yy = 0; yy < rj->h; yy++)
                for (uint32_t xx = 0; xx < rj->w; xx++) {
                    size_t slot = rj->offset + (size_t)yy * rj->w + xx;
                    if (!f->nd_cover[slot])
                        continue;
                    /* the cell's ray meets the face's plane at q */
                    float U =
                        ((float)(rj->x0 + (int32_t)xx) + 0.5f) / (float)f->prm.N * 2.0f - 1.0f;
                    float V =
                        ((float)(rj->y0 + (int32_t)yy) + 0.5f) / (float)f->prm.N * 2.0f - 1.0f;
                    gi_vec3 o = gi_v3_add(gi_v3_scale(P->u, U), gi_v3_scale(P->v, V));
                    float tt = gi_v3_dot(fc->n, gi_v3_sub(fc->origin, o)) / dn;
                    gi_vec3 q = gi_v3_add(o, gi_v3_scale(P->n, tt));
                    float x, y, z;
                    vlf_psf_project(f, i, q, &x, &y, &z);
                    float Lin[3];
                    if (!read_in(f, ri, x, y, Lin))
                        continue;
                    for (int k = 0; k < 3; k++)
                        f->out_next[3 * slot + k] += c[k] * Lin[k];
                }
            /* one pass into the target's tiles: written in the storage format */
            vlf_quantise(f->prm.precision, f->out_next + 3 * (size_t)rj->offset,
                         (size_t)rj->w * rj->h);
        }
    }
    free(g);
}

/* The sorting of one fixed direction's perturbed directions beside its
 * propagation (§3.5: "carried out on the CPU in parallel with
 * propagation"): worker threads build the fragment lists of perturbed
 * directions k = t, t + T, ... into their slots, while the propagating
 * thread sweeps them in order k = 0, 1, ... as they become ready (the
 * same lists and the same order of sweeps for any thread count). */
typedef struct pert_pipe {
    vlf_field *f;
    uint32_t i, T, P;
    frag_buf *slot; /* P fragment lists */
    vlf_psf *frame; /* P frames */
    uint8_t *ready; /* P: 0 not yet, 1 ready, 2 failed */
    int sync;       /* the mutex and condition are set up (and the rest owned) */
    pthread_mutex_t mu;
    pthread_cond_t cv;
} pert_pipe;

typedef struct pert_worker {
    pert_pipe *pp;
    uint32_t t;
    frag_buf tmp;
    vlf_sorter so;
} pert_worker;

static void *pert_thread(void *arg)
{
    pert_worker *w = arg;
    pert_pipe *pp = w->pp;
    int ok = 1;
    for (uint32_t k = w->t; k < pp->P; k += pp->T) {
        if (ok) {
            vlf_psf *fr = &pp->frame[k];
            fr->n = perturbed_dir(pp->f, pp->i, k);
            gi_onb(fr->n, &fr->u, &fr->v);
            ok = perturbed_list(pp->f, fr, &pp->slot[k], &w->tmp, &w->so);
        }
        pthread_mutex_lock(&pp->mu);
        pp->ready[k] = ok ? 1 : 2;
        pthread_cond_broadcast(&pp->cv);
        pthread_mutex_unlock(&pp->mu);
    }
    return NULL;
}

static void pipe_free(pert_pipe *pp, pert_worker *wk)
{
    if (!pp->sync)
        return;
    for (uint32_t k = 0; k < pp->P; k++)
        free(pp->slot[k].v);
    for (uint32_t t = 0; t < pp->T; t++) {
        free(wk[t].tmp.v);
        vlf_sorter_free(&wk[t].so);
    }
    free(pp->slot), free(pp->frame), free(pp->ready), free(wk);
    pthread_mutex_destroy(&pp->mu);
    pthread_cond_destroy(&pp->cv);
    pp->sync = 0;
}

/* The perturbed sweeps of fixed direction i with the lists sorted beside
 * them on T threads; 0 out of memory. */
static int perturbed_pipelined(vlf_field *f, uint32_t i, int first_iteration, pert_pipe *pp,
                               pert_worker *wk)
{
    uint32_t T = pp->T, P = pp->P, l = f->prm.l, prec = f->prm.precision;
    pp->i = i;
    memset(pp->ready, 0, P);
    pthread_t *th = calloc(T, sizeof *th);
    uint8_t *started = calloc(T, 1);
    if (!th || !started) {
        free(th), free(started);
        return 0;
    }
    for (uint32_t t = 0; t < T; t++)
        started[t] = pthread_create(&th[t], NULL, pert_thread, &wk[t]) == 0;
    for (uint32_t t = 0; t < T; t++)
        if (!started[t])
            pert_thread(&wk[t]); /* no thread to be had: its share here */
    int ok = 1;
    for (uint32_t k = 0; k < P && ok; k++) {
        pthread_mutex_lock(&pp->mu);
        while (pp->ready[k] == 0)
            pthread_cond_wait(&pp->cv, &pp->mu);
        ok = pp->ready[k] == 1;
        pthread_mutex_unlock(&pp->mu);
        if (!ok)
            break;
        /* each sign's solid angle: the fixed direction's, shared */
        sweep_perturbed(f, i, &pp->frame[k], &pp->slot[k], +1, f->dirs.solid_angle[i] / (float)P,
                        first_iteration);
        vlf_quantise(prec, f->E_next, f->elem_count);
        sweep_perturbed(f, i, &pp->frame[k], &pp->slot[k], -1,
                        f->dirs.solid_angle[i + l] / (float)P, first_iteration);
        vlf_quantise(prec, f->E_next, f->elem_count);
    }
    for (uint32_t t = 0; t < T; t++)
        if (started[t])
            pthread_join(th[t], NULL);
    free(th), free(started);
    return ok;
}

int vlf_propagate_init(vlf_field *f)
{
    uint32_t prec = f->prm.precision;
    size_t ne = (size_t)f->elem_count * 3, nc = (size_t)f->nd_cells * 3;
    memset(f->E_tot, 0, ne * sizeof(float));
    memset(f->out_tot, 0, nc * sizeof(float));
    memset(f->out_cur, 0, nc * sizeof(float));
    memset(f->out_next, 0, nc * sizeof(float));
    memset(f->E_next, 0, ne * sizeof(float));
    f->st.flux_emitted = 0;
    for (uint32_t e = 0; e < f->elem_count; e++) {
        const vlf_face *fc = &f->faces[f->elem_face[e]];
        for (int q = 0; q < 3; q++) {
            f->L_cur[3 * e + q] = fc->emission[q];
            f->st.flux_emitted += GI_PI * fc->emission[q] * f->elem_area[e] / 3.0;
        }
    }
    vlf_quantise(prec, f->L_cur, f->elem_count);
    if (f->punctual_count) {
        if (!punctual_first_shot(f))
            return -1;
        vlf_quantise(prec, f->E_next, f->elem_count);
        vlf_quantise(prec, f->out_next, f->nd_cells);
    }
    f->st.flux_shot = f->st.flux_received = f->st.flux_back = f->st.flux_escaped = 0;
    f->st.samples = 0;
    return 0;
}

int vlf_field_propagate(vlf_field *f, int (*cancelled)(void *), void *user)
{
    double t0 = now_s();
    uint32_t l = f->prm.l, prec = f->prm.precision;
    size_t ne = (size_t)f->elem_count * 3, nc = (size_t)f->nd_cells * 3;
    if (vlf_propagate_init(f) != 0)
        return -1;
    frag_buf pbuf = {0}, ptmp = {0};
    vlf_sorter psort;
    memset(&psort, 0, sizeof psort);
    /* perturbed directions: sorted on `threads` threads beside the sweeps */
    pert_pipe pp;
    memset(&pp, 0, sizeof pp);
    pert_worker *wk = NULL;
    int pipe_ok = 0;
    if (f->prm.perturbed > 0 && f->prm.threads > 1) {
        pp.f = f;
        pp.T = f->prm.threads < f->prm.perturbed ? f->prm.threads : f->prm.perturbed;
        pp.P = f->prm.perturbed;
        pp.slot = calloc(pp.P, sizeof *pp.slot);
        pp.frame = calloc(pp.P, sizeof *pp.frame);
        pp.ready = calloc(pp.P, 1);
        wk = calloc(pp.T, sizeof *wk);
        pipe_ok = pp.slot && pp.frame && pp.ready && wk && pthread_mutex_init(&pp.mu, NULL) == 0;
        if (pipe_ok && pthread_cond_init(&pp.cv, NULL) != 0) {
            pthread_mutex_destroy(&pp.mu);
            pipe_ok = 0;
        }
        if (!pipe_ok) {
            free(pp.slot), free(pp.frame), free(pp.ready), free(wk);
            return -1;
        }
        pp.sync = 1;
        for (uint32_t t = 0; t < pp.T; t++)
            wk[t].pp = &pp, wk[t].t = t;
    }
    for (uint32_t it = 0; it < f->prm.iterations; it++) {
        for (uint32_t i = 0; i < l; i++) {
            if (cancelled && cancelled(user)) {
                pipe_free(&pp, wk);
                free(pbuf.v), free(ptmp.v), vlf_sorter_free(&psort);
                return -1;
            }
            for (uint32_t fi = 0; fi < f->face_count; fi++)
                if (f->faces[fi].nd >= 0) {
                    const vlf_rect *r = &f->rects[(size_t)f->faces[fi].nd * l + i];
                    memset(f->in + 3 * (size_t)r->offset, 0,
                           (size_t)r->w * r->h * 3 * sizeof(float));
                }
            if (f->prm.perturbed == 0) {
                sweep(f, i, +1, it == 0);
                vlf_quantise(prec, f->E_next, f->elem_count);
                sweep(f, i, -1, it == 0);
                vlf_quantise(prec, f->E_next, f->elem_count);
            } else if (pipe_ok) {
                if (!perturbed_pipelined(f, i, it == 0, &pp, wk)) {
                    pipe_free(&pp, wk);
                    free(pbuf.v), free(ptmp.v), vlf_sorter_free(&psort);
                    return -1;
                }
            } else {
                for (uint32_t k = 0; k < f->prm.perturbed; k++) {
                    vlf_psf fr;
                    fr.n = perturbed_dir(f, i, k);
                    gi_onb(fr.n, &fr.u, &fr.v);
                    if (!perturbed_list(f, &fr, &pbuf, &ptmp, &psort)) {
                        pipe_free(&pp, wk);
                        free(pbuf.v), free(ptmp.v), vlf_sorter_free(&psort);
                        return -1;
                    }
                    /* each sign's solid angle: the fixed direction's, shared */
                    sweep_perturbed(f, i, &fr, &pbuf, +1,
                                    f->dirs.solid_angle[i] / (float)f->prm.perturbed, it == 0);
                    vlf_quantise(prec, f->E_next, f->elem_count);
                    sweep_perturbed(f, i, &fr, &pbuf, -1,
                                    f->dirs.solid_angle[i + l] / (float)f->prm.perturbed, it == 0);
                    vlf_quantise(prec, f->E_next, f->elem_count);
                }
            }
            if (prec != VLF_PREC_32F)
                for (uint32_t fi = 0; fi < f->face_count; fi++)
                    if (f->faces[fi].nd >= 0) {
                        const vlf_rect *r = &f->rects[(size_t)f->faces[fi].nd * l + i];
                        vlf_quantise(prec, f->in + 3 * (size_t)r->offset, (size_t)r->w * r->h);
                    }
            if (f->nd_count)
                scatter(f, i);
        }
        for (size_t k = 0; k < ne; k++) {
            f->E_tot[k] += f->E_next[k];
            f->L_cur[k] = f->elem_kd[k] * (float)GI_INV_PI * f->E_next[k];
            f->E_next[k] = 0.0f;
        }
        for (size_t k = 0; k < nc; k++) {
            f->out_tot[k] += f->out_next[k];
            f->out_cur[k] = f->out_next[k];
            f->out_next[k] = 0.0f;
        }
        /* the total and current maps are written in the storage format */
        vlf_quantise(prec, f->E_tot, f->elem_count);
        vlf_quantise(prec, f->L_cur, f->elem_count);
        vlf_quantise(prec, f->out_tot, f->nd_cells);
    }
    pipe_free(&pp, wk);
    free(pbuf.v), free(ptmp.v), vlf_sorter_free(&psort);
    f->st.propagate_s = now_s() - t0;
    return 0;
}

void vlf_field_free(vlf_field *f)
{
    if (f->psf)
        for (uint32_t i = 0; i < f->prm.l; i++) {
            free(f->psf[i].cell_start);
            free(f->psf[i].frag);
        }
    free(f->psf);
    vlf_dirs_free(&f->dirs);
    free(f->faces);
    free(f->tri_face);
    free(f->tri_group);
    free(f->tri_p);
    free(f->elem_face);
    free(f->elem_area);
    free(f->elem_kd);
    free(f->rects);
    free(f->nd_cover);
    free(f->E_tot);
    free(f->E_next);
    free(f->L_cur);
    free(f->out_cur);
    free(f->out_next);
    free(f->out_tot);
    free(f->in);
    free(f->sun);
    free(f->punctual);
    free(f->elem_c);
    if (f->rt)
        gi_rt_free(f->rt);
    memset(f, 0, sizeof *f);
}
