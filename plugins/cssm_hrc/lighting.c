/* The lighting of cssm_hrc's illumination atlas (Ritschel et al. 2008,
 * §4.1, Fig. 8) over the hierarchy (§4.2; packed nodes §4.2.1):
 *   direct:  R1 = kd/pi gather(emission) + punctual lights (shadow maps)
 *            + the environment (§4.7: ray-traced, or with env=cssm by the
 *              texels' own cube maps, env_cssm.c), or with direct=csm
 *              every light by the CSMs of direct_csm.c;
 *   bounce:  R_k = kd/pi gather(pull(R_{k-1})), k = 2 .. n (§4.1.1);
 *   pull:    the tree of L = emission + sum R_k,
 * then the light sets the final gather reads (emission, reflected) and
 * the pdf tables of indirect=mc (§4.6). */
#include "cssm_hrc.h"

#include "env_cssm.h"

#include <stdlib.h>
#include <string.h>

cssm_gather_opts cssm_hrc_gather_opts(const cssm_hrc *c, float exposure, uint32_t *rng)
{
    cssm_gather_opts o = {.threshold = c->threshold,
                          .max_cut = (uint32_t)c->max_cut,
                          .exposure = exposure,
                          .clamp = c->clamp_f * c->atlas.diameter,
                          .bias = c->bias_f * c->atlas.diameter,
                          .pcf = c->pcf,
                          .rng = rng,
                          .rep_centroid = c->rep_centroid,
                          .trace = c->vis ? c->vis_rt : NULL};
    return o;
}

gi_vec3 cssm_hrc_offset(const cssm_hrc *c, gi_vec3 p, gi_vec3 n)
{
    return cssm_receiver_point(&c->maps, &c->atlas, p, n);
}

gi_result cssm_make_compact(cssm_hrc *c, gi_error *err)
{
    const gi_host *host = c->kit.host;
    for (int i = 0; i < 3; i++)
        cssm_ctree_free(&c->ct[i]);
    host->stat(host, "node_count", (double)c->tree.count);
    if (!c->nodes) { /* a float node and its pulled radiance */
        host->stat(host, "node_bytes",
                   (double)c->tree.count * (double)(sizeof(cssm_node) + 3 * sizeof(float)));
        return GI_OK;
    }
    for (int i = 0; i < 3; i++) {
        gi_result r = cssm_ctree_build(&c->tree, &c->atlas, &c->ct[i], err);
        if (r != GI_OK)
            return r;
    }
    host->stat(host, "node_bytes", (double)c->tree.count * (double)sizeof(cssm_pnode));
    host->stat(host, "node_side_bytes", (double)c->tree.count * 2.0 * sizeof(uint32_t));
    return GI_OK;
}

/* The environment's direct light per texel added to D (c->texel_E keeps
 * the irradiance): with env=cssm by the texels' own cube maps
 * (env_cssm.c), else traced by the core's ray tracer (c->rt, kept for the
 * per-pixel environment light). */
static gi_result texels_environment(cssm_hrc *c, const gi_gpu_scene *gs, const gi_envmap *env,
                                    float *D)
{
    const cssm_atlas *a = &c->atlas;
    const uint32_t N = a->count;
    if (c->maps.escape) { /* env=cssm: the texels' own cube maps (env_cssm.c) */
        c->texel_E = calloc(3 * (size_t)N, sizeof *c->texel_E);
        if (!c->texel_E)
            return gi_kit_fail(&c->kit, GI_ERR_OUT_OF_MEMORY,
                               "cssm_hrc: out of memory for the lighting");
        cssm_env_texels(env, a, &c->maps, (uint32_t)c->env_samples, c->pcf, c->texel_E);
        for (uint32_t i = 0; i < N; i++)
            for (int k = 0; k < 3; k++)
                D[3 * i + k] += a->texels[i].albedo[k] / GI_PI * c->texel_E[3 * i + k];
        return GI_OK;
    }
    gi_rt *rt = NULL;
    gi_error rerr;
    gi_rt_free(c->rt);
    c->rt = NULL;
    c->texel_E = calloc(3 * (size_t)N, sizeof *c->texel_E);
    gi_result rr =
        c->texel_E ? gi_rt_create(gs->scene, gs->time, &rt, &rerr) : GI_ERR_OUT_OF_MEMORY;
    if (rr != GI_OK)
        return c->texel_E ? gi_kit_fail_with(&c->kit, rr, &rerr)
                          : gi_kit_fail(&c->kit, GI_ERR_OUT_OF_MEMORY,
                                        "cssm_hrc: out of memory for the lighting");
    for (uint32_t i = 0; i < N; i++) {
        const cssm_texel *x = &a->texels[i];
        float *e = &c->texel_E[3 * i];
        cssm_env_irradiance(env, rt, cssm_hrc_offset(c, x->p, x->n), x->n, (uint32_t)c->env_samples,
                            i, NULL, e);
        for (int k = 0; k < 3; k++)
            D[3 * i + k] += x->albedo[k] / GI_PI * e[k];
    }
    c->rt = rt; /* kept for the per-pixel environment light */
    return GI_OK;
}

/* The punctual lights' direct light per texel added to D (shadow maps). */
static void texels_punctual(const cssm_hrc *c, const gi_scene *s, float *D)
{
    const cssm_atlas *a = &c->atlas;
    for (uint32_t i = 0; i < a->count && c->shadow_count; i++) {
        const cssm_texel *x = &a->texels[i];
        for (uint32_t l = 0; l < c->shadow_count; l++) {
            float e[3];
            cssm_punctual(c, s, l, cssm_hrc_offset(c, x->p, x->n), x->n, e);
            for (int k = 0; k < 3; k++)
                D[3 * i + k] += x->albedo[k] / GI_PI * e[k];
        }
    }
}

/* §4.7 with direct=csm: every light's direct light per texel by the CSMs,
 * the fixed estimate over the light points, added to D. */
static void texels_csm(const cssm_hrc *c, const gi_scene *s, float *D)
{
    const cssm_atlas *a = &c->atlas;
    for (uint32_t i = 0; i < a->count; i++) {
        const cssm_texel *x = &a->texels[i];
        cssm_receiver rc = {.x = cssm_hrc_offset(c, x->p, x->n), .n = x->n, .self = (int32_t)i};
        memcpy(rc.kd, x->albedo, sizeof rc.kd);
        cssm_csm_direct_eval(c->csm, s, &rc, 0, (uint32_t)c->env_samples, i,
                             c->bias_f * a->diameter, c->pcf, &D[3 * i]);
    }
}

/* The direct light of every texel that does not come from emitting
 * texels, into D (stage timer direct); *env gets the environment the
 * texels were lit by (NULL: none). */
static gi_result texels_direct(cssm_hrc *c, const gi_gpu_scene *gs, float *D,
                               const gi_envmap **env_out)
{
    const gi_host *host = c->kit.host;
    host->stage_begin(host, "direct");
    free(c->texel_E);
    c->texel_E = NULL;
    const gi_envmap *env = gs->scene->has_environment && !c->csm ? gs->scene->envmap : NULL;
    *env_out = env;
    if (env) {
        gi_result r = texels_environment(c, gs, env, D);
        if (r != GI_OK) {
            host->stage_end(host, "direct");
            return r;
        }
    }
    texels_punctual(c, gs->scene, D);
    if (c->csm) /* §4.7: every light's direct light by the CSMs, the fixed estimate over the light
                   points */
        texels_csm(c, gs->scene, D);
    host->stage_end(host, "direct");
    return GI_OK;
}

/* The light sets the final gather reads besides texel_L: the pulled
 * emission (node_Le) and reflected light (node_B, texel_B), packed too
 * with nodes=compact; texel_T allocated for texel mode. */
static gi_result light_sets(cssm_hrc *c)
{
    const cssm_atlas *a = &c->atlas;
    const uint32_t N = a->count, NN = c->tree.count;
    free(c->node_Le);
    free(c->node_B);
    free(c->texel_T);
    c->node_Le = calloc(3 * (size_t)NN, sizeof *c->node_Le);
    c->node_B = calloc(3 * (size_t)NN, sizeof *c->node_B);
    c->texel_T = calloc(3 * (size_t)N, sizeof *c->texel_T);
    float *tmp = calloc(3 * (size_t)N, sizeof *tmp);
    if (!c->node_Le || !c->node_B || !c->texel_T || !tmp) {
        free(tmp);
        return gi_kit_fail(&c->kit, GI_ERR_OUT_OF_MEMORY,
                           "cssm_hrc: out of memory for the lighting");
    }
    for (uint32_t i = 0; i < N; i++)
        memcpy(&tmp[3 * i], a->texels[i].emission, 3 * sizeof(float));
    cssm_tree_pull(&c->tree, a, tmp, c->node_Le);
    if (c->nodes)
        cssm_ctree_pull(&c->ct[1], a, tmp);
    for (size_t k = 0; k < 3 * (size_t)N; k++)
        tmp[k] = c->texel_L[k] - tmp[k];
    cssm_tree_pull(&c->tree, a, tmp, c->node_B);
    if (c->nodes)
        cssm_ctree_pull(&c->ct[2], a, tmp);
    free(c->texel_B);
    c->texel_B = tmp;
    return GI_OK;
}

/* Per-texel values and pdf tables for indirect=mc (§4.6). */
static gi_result mc_tables(cssm_hrc *c)
{
    const cssm_atlas *a = &c->atlas;
    const uint32_t N = a->count;
    free(c->texel_Le);
    c->texel_Le = calloc(3 * (size_t)N, sizeof *c->texel_Le);
    for (int i = 0; i < 3; i++) {
        free(c->cdf[i]);
        c->cdf[i] = malloc(((size_t)N + 1) * sizeof *c->cdf[i]);
    }
    if (!c->texel_Le || !c->cdf[0] || !c->cdf[1] || !c->cdf[2])
        return gi_kit_fail(&c->kit, GI_ERR_OUT_OF_MEMORY,
                           "cssm_hrc: out of memory for the lighting");
    for (uint32_t i = 0; i < N; i++)
        memcpy(&c->texel_Le[3 * i], a->texels[i].emission, 3 * sizeof(float));
    cssm_pdf_build(a, c->texel_L, c->cdf[0]);
    cssm_pdf_build(a, c->texel_Le, c->cdf[1]);
    cssm_pdf_build(a, c->texel_B, c->cdf[2]);
    return GI_OK;
}

gi_result cssm_lighting(cssm_hrc *c, const gi_gpu_scene *gs)
{
    const cssm_atlas *a = &c->atlas;
    const uint32_t N = a->count, NN = c->tree.count;
    free(c->texel_D);
    free(c->texel_L);
    free(c->node_L);
    c->texel_D = calloc(3 * (size_t)N, sizeof *c->texel_D);
    c->texel_L = calloc(3 * (size_t)N, sizeof *c->texel_L);
    c->node_L = calloc(3 * (size_t)NN, sizeof *c->node_L);
    if (!c->texel_D || !c->texel_L || !c->node_L)
        return gi_kit_fail(&c->kit, GI_ERR_OUT_OF_MEMORY,
                           "cssm_hrc: out of memory for the lighting");
    const gi_envmap *env;
    gi_result r = texels_direct(c, gs, c->texel_D, &env);
    if (r != GI_OK)
        return r;
    c->has_direct = c->shadow_count || env || c->csm;
    c->gpu_maps_ok = 0; /* the texels or their albedo may have changed */
    c->kit.host->stat(c->kit.host, "bounces_gpu", c->bounces_on == 0 && !c->vis);
    return cssm_bounces_solve(c, 0, 0, 0);
}

gi_result cssm_bounces_solve(cssm_hrc *c, int jitter, uint32_t frame, uint32_t seed)
{
    const gi_host *host = c->kit.host;
    cssm_gather_opts o = cssm_hrc_gather_opts(c, 0.0f, NULL);
    o.no_emission = c->csm != NULL; /* R1 = the CSMs' direct light alone */
    o.atlas_jitter = jitter;
    o.atlas_frame = frame;
    o.atlas_seed = seed;
    gi_result r;
    /* §4.1.1 "HRC on the GPU": the per-texel gathers in a compute pass */
    const int gpu_bounces = c->bounces_on == 0 && !c->vis; /* vis=trace: the C loop */
    if (gpu_bounces && (r = cssm_gpu_bounces(c, &o)) != GI_OK)
        return r;
    cssm_gather_stats st = {0};
    gi_error err;
    double t0[2], t1[2];
    cssm_cpu_now(t0);
    r = cssm_solve_ex(&c->tree, c->nodes ? &c->ct[0] : NULL, &c->atlas, &c->maps, &o,
                      (uint32_t)c->bounces, c->has_direct ? c->texel_D : NULL, host, c->texel_L,
                      c->node_L, &st, &err);
    cssm_cpu_now(t1);
    host->stat(host, "solve_cpu_ms", 1e3 * (t1[0] - t0[0]));
    if (t1[0] > t0[0])
        host->stat(host, "solve_main_share", (t1[1] - t0[1]) / (t1[0] - t0[0]));
    if (r != GI_OK)
        return gi_kit_fail_with(&c->kit, r, &err);
    if ((r = light_sets(c)) != GI_OK || (r = mc_tables(c)) != GI_OK)
        return r;
    if (st.receivers)
        host->stat(host, "cut_size_atlas", (double)st.nodes / (double)st.receivers);
    c->gpu_dirty = 1; /* the final gather's nodes */
    return GI_OK;
}
