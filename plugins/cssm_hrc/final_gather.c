/* The final gather of cssm_hrc per frame (Ritschel et al. 2008, §4.4 and
 * §4.5): the G-buffer read back; per pixel the stack-less traversal of
 * the hierarchy with a Phong bound, VPLs jittered inside their area and
 * averaged over frames, distances clamped (or with mode=texels, Fig. 17
 * right, the indirect light gathered once per atlas texel and looked up
 * bicubically); plus emission, the punctual lights and the environment
 * per pixel. Pixels thus get light paths of 0 .. n + 1 bounces. */
#include "cssm_hrc.h"

#include "env_cssm.h"

#include "gi/lights.h"
#include "gi/rng.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

gi_result cssm_read_gbuffer(cssm_hrc *c, uint32_t w, uint32_t h)
{
    const gi_gbuffer *g = c->kit.gbuffer;
    GLuint tex[5] = {g->tex_position, g->tex_normal, g->tex_albedo, g->tex_phong, g->tex_emission};
    size_t n = (size_t)w * h * 4;
    for (int i = 0; i < 5; i++) {
        if (c->acc_w != w || c->acc_h != h || !c->gb[i]) {
            free(c->gb[i]);
            c->gb[i] = malloc(n * sizeof(float));
            if (!c->gb[i])
                return gi_kit_fail(&c->kit, GI_ERR_OUT_OF_MEMORY,
                                   "cssm_hrc: out of memory for the G-buffer");
        }
        glGetTextureImage(tex[i], 0, GL_RGBA, GL_FLOAT, (GLsizei)(n * sizeof(float)), c->gb[i]);
    }
    if (c->mode == 1 || c->motion.moving >= 0 || c->texel_E) { /* triangle ids: charts, movers */
        if (c->acc_w != w || c->acc_h != h || !c->ids) {
            free(c->ids);
            c->ids = malloc(n * sizeof *c->ids);
            if (!c->ids)
                return gi_kit_fail(&c->kit, GI_ERR_OUT_OF_MEMORY,
                                   "cssm_hrc: out of memory for the G-buffer");
        }
        glGetTextureImage(g->tex_ids, 0, GL_RGBA_INTEGER, GL_UNSIGNED_INT,
                          (GLsizei)(n * sizeof *c->ids), c->ids);
    }
    if (c->acc_w != w || c->acc_h != h || !c->accum) {
        free(c->accum);
        c->accum = calloc(n, sizeof(float));
        if (!c->accum)
            return gi_kit_fail(&c->kit, GI_ERR_OUT_OF_MEMORY,
                               "cssm_hrc: out of memory for the image");
        c->acc_w = w, c->acc_h = h;
    }
    return GI_OK;
}

/* One gather of light set `which` (0: emission + reflected, 1: emission,
 * 2: reflected) by the hierarchy's cut, or by Monte Carlo (indirect=mc). */
static void gather(const cssm_hrc *c, int which, const cssm_receiver *rc, const cssm_gather_opts *o,
                   float out[3], cssm_gather_stats *st)
{
    if (c->indirect == 1) {
        const float *tv = which == 0 ? c->texel_L : which == 1 ? c->texel_Le : c->texel_B;
        cssm_gather_mc(&c->atlas, &c->maps, tv, c->cdf[which], (uint32_t)c->mc_samples, rc, o, out);
        return;
    }
    if (c->nodes) {
        cssm_cgather(&c->ct[which], &c->atlas, &c->maps, rc, o, out, st);
        return;
    }
    const float *nv = which == 0 ? c->node_L : which == 1 ? c->node_Le : c->node_B;
    cssm_gather(&c->tree, &c->atlas, &c->maps, nv, rc, o, out, st);
}

/* The nearest atlas texel to P whose normal faces the same way (brute
 * force; only for surface samples, which have no chart). -1: none. */
static int32_t nearest_texel(const cssm_atlas *a, gi_vec3 P, gi_vec3 n)
{
    int32_t best = -1;
    float bd = INFINITY;
    for (uint32_t i = 0; i < a->count; i++) {
        if (gi_v3_dot(a->texels[i].n, n) <= 0.0f)
            continue;
        gi_vec3 d = gi_v3_sub(a->texels[i].p, P);
        float dd = gi_v3_dot(d, d);
        if (dd < bd)
            bd = dd, best = (int32_t)i;
    }
    return best;
}

void cssm_texel_gather(cssm_hrc *c, const gi_view *view, uint32_t frame, int random,
                       cssm_gather_stats *st)
{
    const gi_host *host = c->kit.host;
    /* Fig. 17 right: the final, glossy gather of the indirect light once
     * per atlas texel toward the eye */
    host->stage_begin(host, "texel_gather");
    for (uint32_t i = 0; i < c->atlas.count; i++) {
        const cssm_texel *x = &c->atlas.texels[i];
        cssm_receiver rc = {.x = cssm_hrc_offset(c, x->p, x->n),
                            .n = x->n,
                            .self = (int32_t)i,
                            .glossy = 1,
                            .exponent = fminf(x->exponent, 1000.0f)};
        memcpy(rc.kd, x->albedo, sizeof rc.kd);
        memcpy(rc.ks, x->ks, sizeof rc.ks);
        rc.wo = gi_v3_normalize(gi_v3_sub(view->eye, x->p));
        uint32_t rng = gi_rng_init(i, frame, view->seed ^ 0x7e1u);
        cssm_gather_opts o = cssm_hrc_gather_opts(c, view->exposure, random ? &rng : NULL);
        gather(c, 2, &rc, &o, &c->texel_T[3 * i], st);
    }
    host->stage_end(host, "texel_gather");
}

/* What every pixel of a frame shares. */
typedef struct frame_ctx {
    const gi_view *view;
    const gi_scene *s;
    uint32_t frame;
    int random; /* frames differ: the gathers jitter (their generator per pixel and frame) */
} frame_ctx;

/* The receiver of pixel p from the G-buffer; *P and *Nn get its position
 * and unit normal. */
static cssm_receiver pixel_receiver(const cssm_hrc *c, const frame_ctx *f, size_t p, gi_vec3 *P_out,
                                    gi_vec3 *Nn_out)
{
    const float *pos = &c->gb[0][4 * p], *nor = &c->gb[1][4 * p], *alb = &c->gb[2][4 * p];
    const float *ph = &c->gb[3][4 * p];
    gi_vec3 P = gi_v3(pos[0], pos[1], pos[2]), Nn = gi_v3_normalize(gi_v3(nor[0], nor[1], nor[2]));
    cssm_receiver rc = {
        .x = cssm_hrc_offset(c, P, Nn), .n = Nn, .self = -1, .glossy = 1, .exponent = ph[3]};
    if (c->motion.moving >= 0) { /* §3.3: the pixel's object and proxy texel */
        uint32_t tri = c->ids[4 * p + 2];
        int32_t proxy = cssm_motion_proxy(&c->motion, f->s, &c->atlas, tri, P, Nn);
        rc.proxy1 = proxy >= 0 ? (uint32_t)proxy + 1u : 0u;
        rc.moving = cssm_motion_mover1(&c->motion, f->s, tri);
    }
    memcpy(rc.kd, alb, 3 * sizeof(float));
    memcpy(rc.ks, ph, 3 * sizeof(float));
    if (alb[3] > 0.5f) /* mirrors: their Phong lobe stands in (README) */
        rc.exponent = fminf(rc.exponent, 1000.0f);
    rc.wo = gi_v3_normalize(gi_v3_sub(f->view->eye, P));
    *P_out = P;
    *Nn_out = Nn;
    return rc;
}

/* The light the hierarchy brings to pixel p into out: the cut's gather,
 * or in texel mode the emitting texels gathered per pixel and the
 * indirect light from the lightmap. */
static void pixel_indirect(const cssm_hrc *c, const frame_ctx *f, size_t p, gi_vec3 P,
                           const cssm_receiver *rc, const cssm_gather_opts *o, float out[3],
                           cssm_gather_stats *st)
{
    if (c->mode != 1) {
        gather(c, c->csm ? 2 : 0, rc, o, out, st); /* with direct=csm the reflected light only */
        return;
    }
    /* direct light of the emitting texels per pixel, the indirect light from the
     * lightmap */
    if (!c->csm)
        gather(c, 1, rc, o, out, NULL);
    uint32_t tri = c->ids[4 * p + 2];
    int32_t chart = tri < f->s->triangle_count ? cssm_side_chart(&c->atlas, tri, rc->n) : -1;
    float ind[3] = {0, 0, 0}, u, v;
    int ok = 0;
    if (chart >= 0) {
        cssm_chart_coords(&c->atlas, (uint32_t)chart, P, &u, &v);
        ok = cssm_chart_bicubic(&c->atlas, (uint32_t)chart, u, v, c->texel_T, ind);
    }
    if (!ok) /* surface samples have no atlas position: gathered per pixel */
        gather(c, 2, rc, o, ind, st);
    for (int k = 0; k < 3; k++)
        out[k] += ind[k];
}

/* The punctual lights' direct light at a pixel (shadow maps), Lambert and
 * normalised Phong, added to out. */
static void pixel_punctual(const cssm_hrc *c, const gi_scene *s, const cssm_receiver *rc, gi_vec3 P,
                           gi_vec3 Nn, float out[3])
{
    for (uint32_t l = 0; l < c->shadow_count; l++) {
        float e[3];
        cssm_punctual(c, s, l, rc->x, Nn, e);
        if (e[0] <= 0.0f && e[1] <= 0.0f && e[2] <= 0.0f)
            continue;
        gi_vec3 wi = c->shadows[l].type == GI_LIGHT_DIRECTIONAL
                         ? gi_v3_scale(c->shadows[l].dir, -1.0f)
                         : gi_v3_normalize(gi_v3_sub(c->shadows[l].pos, P));
        gi_vec3 rr = gi_v3_sub(gi_v3_scale(Nn, 2.0f * gi_v3_dot(Nn, rc->wo)), rc->wo);
        float cl = gi_v3_dot(rr, wi);
        float lobe =
            cl > 0.0f ? (rc->exponent + 2.0f) / (2.0f * GI_PI) * powf(cl, rc->exponent) : 0.0f;
        for (int k = 0; k < 3; k++)
            out[k] += (rc->kd[k] / GI_PI + rc->ks[k] * lobe) * e[k];
    }
}

/* The environment's light at pixel p added to out: with env=cssm by the
 * maps of the texels around it, else traced at the pixel (env_pixel), or
 * the texels' irradiance, bicubic (surface samples: the nearest texel). */
static void pixel_environment(const cssm_hrc *c, const frame_ctx *f, size_t p,
                              const cssm_receiver *rc, gi_vec3 P, gi_vec3 Nn, float out[3])
{
    const gi_scene *s = f->s;
    uint32_t tri = c->ids[4 * p + 2];
    int32_t chart = tri < s->triangle_count ? cssm_side_chart(&c->atlas, tri, Nn) : -1;
    float e[3] = {0, 0, 0}, u, v;
    int ok = 0;
    if (c->env_pixel && c->maps.escape) { /* env=cssm: the maps of the texels around it */
        cssm_env_proxy px;
        cssm_env_proxies(&c->atlas, &c->maps, s, tri, P, Nn, c->pcf, &px);
        if (px.count)
            cssm_env_estimate(s->envmap, Nn, (uint32_t)c->env_samples,
                              gi_pcg_hash((uint32_t)p ^ gi_pcg_hash(f->frame ^ f->view->seed)), rc,
                              cssm_env_proxy_vis, &px, e);
        for (int k = 0; k < 3; k++)
            out[k] += e[k];
    } else if (c->env_pixel) { /* reflected radiance (diffuse and glossy) traced at the pixel */
        cssm_env_irradiance(s->envmap, c->rt, rc->x, Nn, (uint32_t)c->env_samples,
                            gi_pcg_hash((uint32_t)p ^ gi_pcg_hash(f->frame ^ f->view->seed)), rc,
                            e);
        for (int k = 0; k < 3; k++)
            out[k] += e[k];
    } else {
        if (chart >= 0) {
            cssm_chart_coords(&c->atlas, (uint32_t)chart, P, &u, &v);
            ok = cssm_chart_bicubic(&c->atlas, (uint32_t)chart, u, v, c->texel_E, e);
        }
        if (!ok) {
            int32_t near = nearest_texel(&c->atlas, P, Nn);
            if (near >= 0)
                memcpy(e, &c->texel_E[3 * near], sizeof e);
        }
        for (int k = 0; k < 3; k++)
            out[k] += rc->kd[k] / GI_PI * e[k];
    }
}

/* The radiance of pixel p, which sees a surface, into out. */
static void shade_surface(const cssm_hrc *c, const frame_ctx *f, size_t p, float out[3],
                          cssm_gather_stats *st)
{
    gi_vec3 P, Nn;
    cssm_receiver rc = pixel_receiver(c, f, p, &P, &Nn);
    uint32_t rng = gi_rng_init((uint32_t)p, f->frame, f->view->seed ^ 0xc55u);
    cssm_gather_opts o = cssm_hrc_gather_opts(c, f->view->exposure, f->random ? &rng : NULL);
    pixel_indirect(c, f, p, P, &rc, &o, out, st);
    if (c->csm) /* §4.7: the direct light of every light by the CSMs, S new light points a frame */
        cssm_csm_direct_eval(
            c->csm, f->s, &rc, (uint32_t)c->csm_samples, (uint32_t)c->env_samples,
            gi_pcg_hash((uint32_t)p ^ gi_pcg_hash(f->frame ^ f->view->seed ^ 0xd1cu)),
            c->bias_f * c->atlas.diameter, c->pcf, out);
    pixel_punctual(c, f->s, &rc, P, Nn, out);
    if (c->texel_E)
        pixel_environment(c, f, p, &rc, P, Nn, out);
    const float *em = &c->gb[4][4 * p];
    for (int k = 0; k < 3; k++)
        out[k] += em[k];
}

/* The environment past the scene at pixel (x, y) of a w x h image. */
static void background(const frame_ctx *f, uint32_t x, uint32_t y, uint32_t w, uint32_t h,
                       float out[3])
{
    const gi_view *view = f->view;
    gi_vec3 d =
        gi_mat4_point(view->inv_view_proj, gi_v3(((float)x + 0.5f) / (float)w * 2.0f - 1.0f,
                                                 ((float)y + 0.5f) / (float)h * 2.0f - 1.0f, 1.0f));
    gi_envmap_eval(f->s->envmap, gi_v3_normalize(gi_v3_sub(d, view->eye)), out);
}

void cssm_final_gather(cssm_hrc *c, const gi_view *view, uint32_t frame, int random,
                       cssm_gather_stats *st)
{
    const gi_host *host = c->kit.host;
    const gi_scene *s = c->kit.scene->scene;
    const uint32_t w = view->width, h = view->height;
    const frame_ctx f = {.view = view, .s = s, .frame = frame, .random = random};
    host->stage_begin(host, "final_gather");
    for (uint32_t y = 0; y < h; y++)
        for (uint32_t x = 0; x < w; x++) {
            size_t p = (size_t)y * w + x;
            float out[3] = {0, 0, 0};
            if (c->gb[0][4 * p + 3] > 0.0f)
                shade_surface(c, &f, p, out, st);
            else if (c->texel_E || (c->csm && s->has_environment && s->envmap))
                background(&f, x, y, w, h, out); /* the environment past the scene */
            float *acc = &c->accum[4 * p];
            float wgt = 1.0f / (float)(frame + 1);
            for (int k = 0; k < 3; k++)
                acc[k] = frame ? acc[k] + (out[k] - acc[k]) * wgt : out[k];
            acc[3] = 1.0f;
        }
    host->stage_end(host, "final_gather");
}

void cssm_pixel_reflected(const cssm_hrc *c, const gi_view *view, size_t p, float out[3])
{
    const frame_ctx f = {.view = view, .s = c->kit.scene->scene, .frame = 0, .random = 0};
    gi_vec3 P, Nn;
    cssm_receiver rc = pixel_receiver(c, &f, p, &P, &Nn);
    cssm_gather_opts o = cssm_hrc_gather_opts(c, view->exposure, NULL);
    gather(c, 2, &rc, &o, out, NULL);
}
