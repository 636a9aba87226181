/* Propagation in the vlf method (paper §3.2-§3.4): unshot radiance shot
 * iteration after iteration along every subfield, both ways, through each
 * ray's fragments in depth order with the radiance interface (the sweeps),
 * the non-diffuse faces scattering what they received (scatter.c), the
 * perturbed directions standing in for the fixed ones where asked
 * (perturbed.c, §3.5). */
#define _POSIX_C_SOURCE 200809L
#include "field_internal.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

#include "gi/envmap.h"

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

/* What one sweep needs of its direction, and the fluxes it sums. */
typedef struct {
    vlf_field *f;
    uint32_t i, l;
    int sign;
    gi_vec3 t;    /* the travel direction */
    float sky[3]; /* the radiance each ray starts with */
    float recv_scale, inv_s2, min_area;
    double shot, recv, back;
} sweep_ctx;

/* One ray of a sweep, in subfield cell (cx, cy), through its fragments
 * a..e-1 in travel order; returns the radiance that escapes at its end. Receivers (front side
 * facing against t) take the interface's radiance and let it go on, senders (front side along t)
 * stop what arrived on their back (flux_back counts it) and send their unshot radiance on. */
static float sweep_ray(sweep_ctx *x, const uint32_t *frag, uint32_t a, uint32_t e, uint32_t cx,
                       uint32_t cy)
{
    vlf_field *f = x->f;
    float L[3] = {x->sky[0], x->sky[1], x->sky[2]};
    int32_t step = x->sign > 0 ? 1 : -1;
    int32_t k = x->sign > 0 ? (int32_t)a : (int32_t)e - 1,
            end = x->sign > 0 ? (int32_t)e : (int32_t)a - 1;
    for (; k != end; k += step) {
        uint32_t el = frag[k];
        const vlf_face *fc = &f->faces[f->elem_face[el]];
        float cs = gi_v3_dot(fc->n, x->t);
        float lum = L[0] + L[1] + L[2];
        if (cs < 0.0f) {
            /* receiver */
            float s = x->recv_scale / fmaxf(f->elem_area[el], x->min_area);
            for (int q = 0; q < 3; q++)
                f->E_next[3 * (size_t)el + q] += L[q] * s;
            if (fc->nd >= 0) {
                size_t slot = vlf_rect_slot(&f->rects[(size_t)fc->nd * x->l + x->i], cx, cy);
                for (int q = 0; q < 3; q++)
                    f->in[3 * slot + q] += L[q] * x->inv_s2;
            }
            x->recv += lum;
            /* and it goes on: a ray from a point further along back toward
             * the light meets this face's back, which does not exist (the
             * one rule for sides, gi/scene.h, as the reference casts that
             * ray); a closed surface's exit face stops it below */
        } else if (cs > 0.0f) {
            /* sender: a ray from downstream meets its front, so what
             * arrived on its back stops here (flux_back), and its front
             * sends its unshot radiance on */
            x->back += lum;
            L[0] = L[1] = L[2] = 0.0f;
            float own[3];
            for (int q = 0; q < 3; q++)
                own[q] = f->L_cur[3 * (size_t)el + q] * fc->send_scale;
            if (fc->nd >= 0) {
                size_t slot = vlf_rect_slot(&f->rects[(size_t)fc->nd * x->l + x->i], cx, cy);
                for (int q = 0; q < 3; q++)
                    own[q] += f->out_cur[3 * slot + q];
            }
            for (int q = 0; q < 3; q++)
                L[q] += own[q];
            x->shot += own[0] + own[1] + own[2];
        }
    }
    f->st.samples += e - a;
    return L[0] + L[1] + L[2];
}

/* One sweep of subfield i along travel direction t = sign * w_i, front to
 * back along t through every ray's fragments with the radiance interface
 * (sweep_ray). This is the one rule for sides (gi/scene.h) as the
 * reference applies it to a ray cast from a point back toward the light:
 * it meets a single-sided face only on its front. A closed surface
 * receives at its entry and stops at its exit. */
static void sweep(vlf_field *f, uint32_t i, int sign, int first_iteration)
{
    const vlf_psf *p = &f->psf[i];
    uint32_t S = f->prm.S, Nf = f->prm.N, N = Nf * S, l = f->prm.l;
    uint32_t sd = sign > 0 ? i : i + l;
    float cell_area = (2.0f / (float)N) * (2.0f / (float)N);
    float dW = f->dirs.solid_angle[sd];
    sweep_ctx x = {.f = f,
                   .i = i,
                   .l = l,
                   .sign = sign,
                   .t = f->dirs.signed_dirs[sd],
                   .recv_scale = cell_area * dW,
                   .inv_s2 = 1.0f / (float)(S * S),
                   .min_area = 1.0f / (64.0f * f->prm.density * f->prm.density)};
    vlf_sweep_sky(f, i, sign, first_iteration, x.sky);
    float sky_sum = x.sky[0] + x.sky[1] + x.sky[2];
    double esc = 0;
    /* the interface cells in row-major order (c counts them), walked by
     * subfield cell (cx, cy) and sub-cell (sx, sy) so that no cell needs a
     * division; an empty cell only lets the sky's radiance escape (nothing
     * after the first iteration) */
    uint32_t c = 0;
    for (uint32_t cy = 0; cy < Nf; cy++)
        for (uint32_t sy = 0; sy < S; sy++)
            for (uint32_t cx = 0; cx < Nf; cx++)
                for (uint32_t sx = 0; sx < S; sx++, c++) {
                    uint32_t a = p->cell_start[c], e = p->cell_start[c + 1];
                    if (a != e)
                        esc += sweep_ray(&x, p->frag, a, e, cx, cy);
                    else if (sky_sum != 0.0f)
                        esc += sky_sum;
                }
    double w = (double)cell_area * dW / 3.0;
    f->st.flux_shot += x.shot * w;
    f->st.flux_received += x.recv * w;
    f->st.flux_back += x.back * w;
    f->st.flux_escaped += esc * w;
}

gi_result vlf_propagate_init(vlf_field *f, gi_error *err)
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
        if (vlf_punctual_first_shot(f) != GI_OK)
            return gi_error_set(err, GI_ERR_OUT_OF_MEMORY,
                                "vlf: out of memory starting propagation");
        vlf_quantise(prec, f->E_next, f->elem_count);
        vlf_quantise(prec, f->out_next, f->nd_cells);
    }
    f->st.flux_shot = f->st.flux_received = f->st.flux_back = f->st.flux_escaped = 0;
    f->st.samples = 0;
    return GI_OK;
}

/* The transport of fixed direction i in one iteration: the incoming
 * radiance of its tiles cleared, the sweeps along +w_i and -w_i (or along
 * the perturbed directions standing in for it, §3.5), the incoming
 * radiance written in the storage format, then the non-diffuse faces'
 * scattering (§3.4). */
static gi_result propagate_direction(vlf_field *f, vlf_perturbed *pt, uint32_t i,
                                     int first_iteration)
{
    uint32_t l = f->prm.l, prec = f->prm.precision;
    for (uint32_t fi = 0; fi < f->face_count; fi++)
        if (f->faces[fi].nd >= 0) {
            const vlf_rect *r = &f->rects[(size_t)f->faces[fi].nd * l + i];
            memset(f->in + 3 * (size_t)r->offset, 0, (size_t)r->w * r->h * 3 * sizeof(float));
        }
    if (f->prm.perturbed == 0) {
        sweep(f, i, +1, first_iteration);
        vlf_quantise(prec, f->E_next, f->elem_count);
        sweep(f, i, -1, first_iteration);
        vlf_quantise(prec, f->E_next, f->elem_count);
    } else if (vlf_perturbed_sweeps(pt, i, first_iteration) != GI_OK) {
        return GI_ERR_OUT_OF_MEMORY;
    }
    if (prec != VLF_PREC_32F)
        for (uint32_t fi = 0; fi < f->face_count; fi++)
            if (f->faces[fi].nd >= 0) {
                const vlf_rect *r = &f->rects[(size_t)f->faces[fi].nd * l + i];
                vlf_quantise(prec, f->in + 3 * (size_t)r->offset, (size_t)r->w * r->h);
            }
    if (f->nd_count)
        vlf_scatter(f, i);
    return GI_OK;
}

/* The end of a shooting iteration: what was received is added to the
 * totals and becomes the unshot radiance of the next (diffuse: albedo E /
 * pi; non-diffuse: the tiles as they are). */
static void end_iteration(vlf_field *f)
{
    uint32_t prec = f->prm.precision;
    size_t ne = (size_t)f->elem_count * 3, nc = (size_t)f->nd_cells * 3;
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

gi_result vlf_field_propagate(vlf_field *f, int (*cancelled)(void *), void *user, gi_error *err)
{
    double t0 = vlf_now_s();
    gi_result r = vlf_propagate_init(f, err);
    if (r != GI_OK)
        return r;
    /* perturbed directions: sorted on `threads` threads beside the sweeps */
    vlf_perturbed *pt = NULL;
    if (f->prm.perturbed > 0 && !(pt = vlf_perturbed_create(f)))
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY,
                            "vlf: out of memory propagating the light field");
    for (uint32_t it = 0; it < f->prm.iterations && r == GI_OK; it++) {
        for (uint32_t i = 0; i < f->prm.l && r == GI_OK; i++) {
            if (cancelled && cancelled(user))
                r = gi_error_set(err, GI_ERR_CANCELLED, "vlf: propagation cancelled");
            else if (propagate_direction(f, pt, i, it == 0) != GI_OK)
                r = gi_error_set(err, GI_ERR_OUT_OF_MEMORY,
                                 "vlf: out of memory propagating the light field");
        }
        if (r == GI_OK)
            end_iteration(f);
    }
    vlf_perturbed_free(pt);
    if (r != GI_OK)
        return r;
    f->st.propagate_s = vlf_now_s() - t0;
    return GI_OK;
}
