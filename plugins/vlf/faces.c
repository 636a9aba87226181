/* The faces of the vlf method and their elements (paper §3.1): the
 * scene's triangles grouped into planar faces of one material, each with a
 * chart of diffuse elements (the irradiance atlas), the exact area of every
 * element on its face, and the triangles cut finer for the tessellation
 * sweep. */
#define _POSIX_C_SOURCE 200809L
#include "field_internal.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

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

/* 1 if triangles x and y have the same material and plane (their keys
 * but the triangle). */
static int same_face(const tri_key *x, const tri_key *y)
{
    return key_cmp(&(tri_key){0, x->material, x->nx, x->ny, x->nz, x->d},
                   &(tri_key){0, y->material, y->nx, y->ny, y->nz, y->d}) == 0;
}

/* The scene's triangles at time t in VLF coordinates (f->tri_p), each
 * one's scene object (f->tri_group), unit normal (nrm) and key. */
static void key_triangles(vlf_field *f, const gi_scene *s, float t, tri_key *keys, gi_vec3 *nrm)
{
    for (uint32_t ti = 0; ti < s->triangle_count; ti++) {
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
}

/* Face fi of the triangles keys[0 .. n): their summed area, the normal of
 * their summed cross products (the first triangle's where that vanishes)
 * and the chart axes in the plane; the triangles marked as the face's. */
static void face_plane(vlf_field *f, uint32_t fi, const tri_key *keys, uint32_t n,
                       const gi_vec3 *nrm)
{
    vlf_face *fc = &f->faces[fi];
    gi_vec3 sum = gi_v3(0, 0, 0);
    for (uint32_t k = 0; k < n; k++) {
        const gi_vec3 *p = f->tri_p + 3 * (size_t)keys[k].tri;
        gi_vec3 c = gi_v3_cross(gi_v3_sub(p[1], p[0]), gi_v3_sub(p[2], p[0]));
        sum = gi_v3_add(sum, c);
        fc->area += 0.5f * gi_v3_length(c);
        f->tri_face[keys[k].tri] = fi;
    }
    fc->n = gi_v3_length(sum) > 0.0f ? gi_v3_normalize(sum) : nrm[keys[0].tri];
    gi_onb(fc->n, &fc->t, &fc->b);
}

/* Face fc's chart: the bounding rectangle in its plane of the triangles
 * keys[0 .. n), density texels per unit length (1 to 1024 a side). */
static void face_chart(const vlf_field *f, vlf_face *fc, const tri_key *keys, uint32_t n)
{
    float lo[2] = {FLT_MAX, FLT_MAX}, hi[2] = {-FLT_MAX, -FLT_MAX};
    gi_vec3 p0 = f->tri_p[3 * (size_t)keys[0].tri];
    for (uint32_t k = 0; k < n; k++)
        for (int c = 0; c < 3; c++) {
            gi_vec3 d = gi_v3_sub(f->tri_p[3 * (size_t)keys[k].tri + (size_t)c], p0);
            float x = gi_v3_dot(d, fc->t), y = gi_v3_dot(d, fc->b);
            lo[0] = fminf(lo[0], x), lo[1] = fminf(lo[1], y);
            hi[0] = fmaxf(hi[0], x), hi[1] = fmaxf(hi[1], y);
        }
    fc->origin = gi_v3_add(p0, gi_v3_add(gi_v3_scale(fc->t, lo[0]), gi_v3_scale(fc->b, lo[1])));
    float W = ceilf((hi[0] - lo[0]) * f->prm.density), H = ceilf((hi[1] - lo[1]) * f->prm.density);
    fc->W = W < 1.0f ? 1u : W > 1024.0f ? 1024u : (uint32_t)W;
    fc->H = H < 1.0f ? 1u : H > 1024.0f ? 1024u : (uint32_t)H;
}

/* Face fc's material (the scene's material m) with its lobe's albedo
 * table, and the emission of its triangle t0. The table depends on the
 * material alone: computed at its first face into tables[m] (have[m] set),
 * copied for the others (a mesh like the bunny is thousands of faces of one
 * material, and each table is 135 168 cosines). */
static void face_material(vlf_face *fc, const gi_scene *s, uint32_t m, uint32_t t0, float *tables,
                          unsigned char *have)
{
    const gi_material *mt = &s->materials[m];
    memcpy(fc->kd, mt->albedo, sizeof fc->kd);
    memcpy(fc->ks, mt->ks, sizeof fc->ks);
    fc->exponent = mt->exponent;
    fc->material = m;
    fc->textured = mt->albedo_texture >= 0 && (uint32_t)mt->albedo_texture < s->texture_count;
    fc->mirror = mt->mirror || mt->exponent >= GI_MIRROR_EXPONENT;
    float *tab = tables + (size_t)m * VLF_ALBEDO_TABLE;
    if (!have[m])
        for (int k = 0; k < VLF_ALBEDO_TABLE; k++)
            tab[k] = fc->mirror ? 1.0f
                                : (float)vlf_phong_albedo(fc->exponent,
                                                          (float)k / (float)(VLF_ALBEDO_TABLE - 1));
    have[m] = 1;
    memcpy(fc->albedo, tab, sizeof fc->albedo);
    const float *le = gi_scene_triangle_emission(s, t0);
    for (int k = 0; k < 3; k++)
        fc->emission[k] = le ? le[k] : 0.0f;
}

gi_result vlf_group_faces(vlf_field *f, const gi_scene *s, float t)
{
    uint32_t T = s->triangle_count;
    f->tri_count = T;
    f->tri_face = malloc((size_t)T * sizeof *f->tri_face);
    f->tri_group = malloc((size_t)T * sizeof *f->tri_group);
    f->tri_p = malloc((size_t)T * 3 * sizeof *f->tri_p);
    tri_key *keys = malloc((size_t)T * sizeof *keys);
    gi_vec3 *nrm = malloc((size_t)T * sizeof *nrm);
    f->faces = calloc((size_t)T * 2, sizeof *f->faces); /* double-sided faces take two */
    size_t nm = s->material_count ? s->material_count : 1;
    float *tables = malloc(nm * VLF_ALBEDO_TABLE * sizeof *tables);
    unsigned char *have = calloc(nm, 1);
    if (!f->tri_face || !f->tri_group || !f->tri_p || !keys || !nrm || !f->faces || !tables ||
        !have) {
        free(keys), free(nrm), free(tables), free(have);
        return GI_ERR_OUT_OF_MEMORY;
    }
    key_triangles(f, s, t, keys, nrm);
    qsort(keys, T, sizeof *keys, key_cmp);
    uint32_t nf = 0, groups = 0;
    for (uint32_t a = 0; a < T;) {
        /* a material's albedo table costs about 1 ms of CPU on llvmpipe's
         * machine (measured, issue 32): asked every 64 faces */
        if ((groups++ & 63) == 0 && f->prm.cancelled && f->prm.cancelled(f->prm.cancel_user)) {
            free(keys), free(nrm), free(tables), free(have);
            f->face_count = nf;
            return GI_ERR_CANCELLED;
        }
        uint32_t b = a + 1;
        while (b < T && same_face(&keys[a], &keys[b]))
            b++;
        vlf_face *fc = &f->faces[nf];
        face_plane(f, nf, keys + a, b - a, nrm);
        face_chart(f, fc, keys + a, b - a);
        face_material(fc, s, keys[a].material, keys[a].tri, tables, have);
        fc->twin = -1;
        if (s->materials[keys[a].material].double_sided) {
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
    free(keys), free(nrm), free(tables), free(have);
    return GI_OK;
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

void vlf_element_areas(vlf_field *f, const gi_scene *s)
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

gi_result vlf_subdivide_triangles(vlf_field *f, uint32_t k)
{
    f->tri_sub = k * k;
    if (k <= 1)
        return GI_OK;
    size_t T = (size_t)f->tri_count * k * k;
    gi_vec3 *P = malloc(T * 3 * sizeof *P);
    uint32_t *F = malloc(T * sizeof *F), *Gr = malloc(T * sizeof *Gr);
    if (!P || !F || !Gr) {
        free(P), free(F), free(Gr);
        return GI_ERR_OUT_OF_MEMORY;
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
    return GI_OK;
}
