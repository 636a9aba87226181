/* Environment light from the texels' own coherent surface shadow maps
 * (§4.7 "Direct Light", §4: the CSM shadows environment maps), and the
 * Monte Carlo estimator both env=trace and env=cssm use. Conventions in
 * env_cssm.h. */
#include "env_cssm.h"

#include "gi/algo/cubemap.h"
#include "gi/rng.h"
#include "gi/sampling.h"

#include <float.h>
#include <math.h>

void cssm_env_estimate(const gi_envmap *env, gi_vec3 n, uint32_t K, uint32_t seed,
                       const cssm_receiver *brdf, cssm_env_vis_fn vis, const void *ctx, float e[3])
{
    e[0] = e[1] = e[2] = 0.0f;
    uint32_t rng = gi_rng_init(seed, 0, 0x5e17u);
    for (uint32_t k = 0; k < K; k++) {
        float u1 = gi_rng_next_float(&rng), u2 = gi_rng_next_float(&rng);
        gi_vec3 w;
        float weight = gi_envmap_mis_direction(env, n, k, K, u1, u2, &w);
        if (!(weight > 0.0f))
            continue;
        float v = vis(ctx, w);
        if (!(v > 0.0f))
            continue;
        float L[3], lobe = 0.0f;
        gi_envmap_eval(env, w, L);
        if (brdf) { /* reflected radiance: the receiver's diffuse + Phong BRDF */
            gi_vec3 rr = gi_v3_sub(gi_v3_scale(n, 2.0f * gi_v3_dot(n, brdf->wo)), brdf->wo);
            float cl = gi_v3_dot(rr, w);
            lobe = cl > 0.0f ? (brdf->exponent + 2.0f) / (2.0f * GI_PI) * powf(cl, brdf->exponent)
                             : 0.0f;
        }
        for (int j = 0; j < 3; j++)
            e[j] += v * L[j] * weight * (brdf ? brdf->kd[j] / GI_PI + brdf->ks[j] * lobe : 1.0f);
    }
}

/* 1 when the segment of face texel (tx, ty) that holds texel j's map lies
 * at or past the far plane: nothing was seen there. */
static int escapes_at(const cssm_maps *m, const gi_csm_data *data, int tx, int ty, uint32_t i)
{
    const int M = (int)m->M;
    tx = tx < 0 ? 0 : tx >= M ? M - 1 : tx;
    ty = ty < 0 ? 0 : ty >= M ? M - 1 : ty;
    return gi_csm_lookup(data, (uint32_t)ty * m->M + (uint32_t)tx, i) >= m->zfar;
}

float cssm_escape(const cssm_maps *m, uint32_t j, gi_vec3 w, int pcf)
{
    int face = gi_cube_face(w);
    float sx, sy;
    gi_cube_project(face, w, &sx, &sy);
    const uint32_t i = m->seq[j];
    const gi_csm_data *data = &m->face[face];
    float fx = (sx * 0.5f + 0.5f) * (float)m->M, fy = (sy * 0.5f + 0.5f) * (float)m->M;
    if (!pcf)
        return (float)escapes_at(m, data, (int)fx, (int)fy, i);
    /* 2 x 2 face texels around the direction, bilinear weights (as cssm_visible) */
    float gx = fx - 0.5f, gy = fy - 0.5f;
    int x0 = (int)floorf(gx), y0 = (int)floorf(gy);
    float wx = gx - (float)x0, wy = gy - (float)y0, v = 0.0f;
    for (int k = 0; k < 4; k++) {
        float wt = ((k & 1) ? wx : 1.0f - wx) * ((k >> 1) ? wy : 1.0f - wy);
        if (wt > 0.0f)
            v += wt * (float)escapes_at(m, data, x0 + (k & 1), y0 + (k >> 1), i);
    }
    return v;
}

float cssm_env_texel_vis(const void *ctx, gi_vec3 w)
{
    const cssm_env_texel_ctx *p = ctx;
    /* below the plane of the map's texel the map holds "don't care" */
    if (!(gi_v3_dot(w, p->n) > 0.0f))
        return 0.0f;
    return cssm_escape(p->m, p->texel, w, p->pcf);
}

float cssm_env_proxy_vis(const void *ctx, gi_vec3 w)
{
    const cssm_env_proxy *p = ctx;
    float v = 0.0f, wsum = 0.0f;
    for (uint32_t k = 0; k < p->count; k++) {
        const uint32_t j = p->texel[k];
        if (!(gi_v3_dot(w, p->a->texels[j].n) > 0.0f))
            continue;
        v += p->weight[k] * cssm_escape(p->m, j, w, p->pcf);
        wsum += p->weight[k];
    }
    return wsum > 0.0f ? v / wsum : 0.0f;
}

void cssm_env_texels(const gi_envmap *env, const cssm_atlas *a, const cssm_maps *m, uint32_t K,
                     int pcf, float *texel_E)
{
    for (uint32_t i = 0; i < a->count; i++) {
        cssm_env_texel_ctx ctx = {.m = m, .texel = i, .n = a->texels[i].n, .pcf = pcf};
        cssm_env_estimate(env, a->texels[i].n, K, i, NULL, cssm_env_texel_vis, &ctx,
                          &texel_E[3 * i]);
    }
}

static uint32_t object_of(const gi_scene *s, uint32_t tri)
{
    return s->vertices[s->indices[3 * tri]].object;
}

void cssm_env_proxies(const cssm_atlas *a, const cssm_maps *m, const gi_scene *s, uint32_t tri,
                      gi_vec3 P, gi_vec3 n, int pcf, cssm_env_proxy *out)
{
    out->m = m;
    out->a = a;
    out->pcf = pcf;
    out->count = 0;
    if (tri >= s->triangle_count)
        return;
    int32_t chart = cssm_side_chart(a, tri, n);
    if (chart >= 0) { /* the 2 x 2 chart texels around P, bilinear weights */
        const cssm_chart *c = &a->charts[chart];
        float u, v;
        cssm_chart_coords(a, (uint32_t)chart, P, &u, &v);
        float gx = u - 0.5f, gy = v - 0.5f;
        int x0 = (int)floorf(gx), y0 = (int)floorf(gy);
        float wx = gx - (float)x0, wy = gy - (float)y0;
        for (int k = 0; k < 4; k++) {
            int x = x0 + (k & 1), y = y0 + (k >> 1);
            x = x < 0 ? 0 : x >= (int)c->w ? (int)c->w - 1 : x;
            y = y < 0 ? 0 : y >= (int)c->h ? (int)c->h - 1 : y;
            int32_t t = a->grid[(size_t)(c->y0 + (uint32_t)y) * a->R + c->x0 + (uint32_t)x];
            float wt = ((k & 1) ? wx : 1.0f - wx) * ((k >> 1) ? wy : 1.0f - wy);
            if (t < 0 || !(wt > 0.0f))
                continue;
            out->texel[out->count] = (uint32_t)t;
            out->weight[out->count++] = wt;
        }
        if (out->count)
            return;
    }
    /* the nearest texels of the same object facing the same way */
    const uint32_t o = object_of(s, tri);
    float best[CSSM_ENV_PROXIES];
    for (uint32_t i = 0; i < a->count; i++) {
        const cssm_texel *x = &a->texels[i];
        if (gi_v3_dot(x->n, n) < 0.5f || object_of(s, x->triangle) != o)
            continue;
        gi_vec3 d = gi_v3_sub(x->p, P);
        float dd = gi_v3_dot(d, d);
        uint32_t k = out->count < CSSM_ENV_PROXIES ? out->count++ : CSSM_ENV_PROXIES;
        if (k == CSSM_ENV_PROXIES) {
            if (dd >= best[k - 1])
                continue;
            k--;
        }
        for (; k > 0 && best[k - 1] > dd; k--) { /* insertion: best[] ascending */
            best[k] = best[k - 1];
            out->texel[k] = out->texel[k - 1];
        }
        best[k] = dd;
        out->texel[k] = i;
    }
    const float h2 = a->h * a->h; /* keeps a texel under P from taking all the weight */
    for (uint32_t k = 0; k < out->count; k++)
        out->weight[k] = 1.0f / (best[k] + h2);
}
