/* Non-diffuse reflection in the vlf method (paper §3.4): the weights of
 * the directions a mirror or glossy face reflects into, and the scattering
 * of the radiance a subfield brought to the non-diffuse faces into the
 * tiles of the subfields around the reflected direction. */
#define _POSIX_C_SOURCE 200809L
#include "field_internal.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

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

/* Non-diffuse scattering (§3.4): the radiance that subfield i brought to
 * each non-diffuse face is reflected into the subfields around the
 * reflected direction (mirrors and lobes narrower than the direction set:
 * the three nearest, barycentric weights; wider Phong lobes: every
 * direction of the lobe, weighted by it), by backward mapping of each
 * target cell through the face's plane into subfield i. */
void vlf_scatter(vlf_field *f, uint32_t i)
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
