/* The material model shared by the reference and every GPU method: a
 * Lambertian lobe plus a normalised Phong lobe, or an ideal mirror.
 * C twin of core/shaders/brdf.glsl; test_twins holds the two equal.
 *
 *   f(wo, wi) = kd / pi + ks (n + 2) / (2 pi) max(0, r . wi)^n,
 *   r = reflect(-wo, N) = 2 (N . wo) N - wo,
 * with wo and wi unit vectors pointing AWAY from the surface and N the unit
 * shading normal on the side of wo (flip it for back faces of double-sided
 * materials before calling). f is zero when wo or wi is below the surface.
 * The (n + 2) / (2 pi) factor makes the lobe's albedo at normal incidence
 * ks, and never above ks (energy conserving for kd + ks <= 1).
 *
 * Mirror: the mirror flag or n >= GI_MIRROR_EXPONENT turns the Phong lobe
 * into a delta lobe of reflectance ks in direction r. gi_brdf_eval and
 * gi_brdf_pdf leave a delta lobe out; only gi_brdf_sample produces it.
 *
 * Sampling: the lobe is chosen by u3 with P_spec = lum(ks) / (lum(kd) +
 * lum(ks)) (0 when ks is black); the diffuse lobe draws a cosine-weighted
 * direction about N, the Phong lobe a direction about r with pdf
 * (n + 1) / (2 pi) cos^n(alpha). The returned pdf is the mixture
 * (1 - P_spec) cos(theta_i) / pi + P_spec p_phong, so that MIS weights see
 * the density the sampler really has.
 */
#ifndef GI_BRDF_H
#define GI_BRDF_H

#include <math.h>

#include "gi/sampling.h"
#include "gi/vecmath.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Same value as scene.h (an identical redefinition is harmless). */
#ifndef GI_MIRROR_EXPONENT
#define GI_MIRROR_EXPONENT 10000.0f
#endif

typedef struct gi_brdf {
    float kd[3]; /* Lambert albedo */
    float ks[3]; /* Phong / mirror reflectance */
    float n;     /* Phong exponent */
    int mirror;  /* ideal mirror of reflectance ks */
} gi_brdf;

static inline int gi_brdf_is_mirror(const gi_brdf *b)
{
    return b->mirror != 0 || b->n >= GI_MIRROR_EXPONENT;
}

/* Probability of sampling the specular (Phong or mirror) lobe. */
static inline float gi_brdf_spec_prob(const gi_brdf *b)
{
    float ls = gi_luminance(b->ks), ld = gi_luminance(b->kd);
    return ls > 0.0f ? ls / (ld + ls) : 0.0f;
}

/* Mirror direction of wo about N: 2 (N . wo) N - wo. */
static inline gi_vec3 gi_reflect(gi_vec3 wo, gi_vec3 N)
{
    return gi_v3_sub(gi_v3_scale(N, 2.0f * gi_v3_dot(N, wo)), wo);
}

/* Normalised Phong lobe about unit axis r: a direction with pdf
 * (n + 1) / (2 pi) cos^n(alpha), alpha the angle to r (never below r's
 * horizon, but possibly below the surface's). */
static inline gi_vec3 gi_phong_lobe_sample(gi_vec3 r, float n, float u1, float u2)
{
    float cos_a = powf(u1, 1.0f / (n + 1.0f));
    float sin_a = sqrtf(fmaxf(0.0f, 1.0f - cos_a * cos_a));
    float phi = 2.0f * GI_PI * u2;
    return gi_to_world(gi_v3(sin_a * cosf(phi), sin_a * sinf(phi), cos_a), r);
}
static inline float gi_phong_lobe_pdf(gi_vec3 r, float n, gi_vec3 wi)
{
    float c = gi_v3_dot(r, wi);
    return c > 0.0f ? (n + 1.0f) * (0.5f * GI_INV_PI) * powf(c, n) : 0.0f;
}

/* f(wo, wi) without the cosine, delta lobe excluded. */
static inline void gi_brdf_eval(const gi_brdf *b, gi_vec3 N, gi_vec3 wo, gi_vec3 wi, float f[3])
{
    f[0] = f[1] = f[2] = 0.0f;
    if (gi_v3_dot(N, wo) <= 0.0f || gi_v3_dot(N, wi) <= 0.0f)
        return;
    float spec = 0.0f;
    /* A purely diffuse material skips the lobe (and its powf): ks * spec
     * would add exactly 0. */
    if (!gi_brdf_is_mirror(b) && (b->ks[0] != 0.0f || b->ks[1] != 0.0f || b->ks[2] != 0.0f)) {
        float c = gi_v3_dot(gi_reflect(wo, N), wi);
        if (c > 0.0f)
            spec = (b->n + 2.0f) * (0.5f * GI_INV_PI) * powf(c, b->n);
    }
    for (int k = 0; k < 3; k++)
        f[k] = b->kd[k] * GI_INV_PI + b->ks[k] * spec;
}

/* Solid-angle pdf with which gi_brdf_sample draws wi (non-delta part);
 * zero when wo or wi is below the surface. */
static inline float gi_brdf_pdf(const gi_brdf *b, gi_vec3 N, gi_vec3 wo, gi_vec3 wi)
{
    float cos_o = gi_v3_dot(N, wo), cos_i = gi_v3_dot(N, wi);
    if (cos_o <= 0.0f || cos_i <= 0.0f)
        return 0.0f;
    float ps = gi_brdf_spec_prob(b);
    float pdf = (1.0f - ps) * cos_i * GI_INV_PI;
    if (ps > 0.0f && !gi_brdf_is_mirror(b))
        pdf += ps * gi_phong_lobe_pdf(gi_reflect(wo, N), b->n, wi);
    return pdf;
}

/* Draws wi from (u1, u2, u3) in [0,1)^3. weight = f cos(theta_i) / pdf.
 * A delta (mirror) sample has *is_delta = 1, *pdf = P_spec (the discrete
 * probability of the lobe) and weight = ks / P_spec. A failed sample (wo
 * or the drawn wi below the surface) has pdf 0 and weight 0. */
static inline void gi_brdf_sample(const gi_brdf *b, gi_vec3 N, gi_vec3 wo, float u1, float u2,
                                  float u3, gi_vec3 *wi, float *pdf, float weight[3], int *is_delta)
{
    *wi = N;
    *pdf = 0.0f;
    *is_delta = 0;
    weight[0] = weight[1] = weight[2] = 0.0f;
    if (gi_v3_dot(N, wo) <= 0.0f)
        return;
    float ps = gi_brdf_spec_prob(b);
    gi_vec3 r = gi_reflect(wo, N);
    if (u3 < ps) {
        if (gi_brdf_is_mirror(b)) {
            *wi = r;
            *pdf = ps;
            *is_delta = 1;
            for (int k = 0; k < 3; k++)
                weight[k] = b->ks[k] / ps;
            return;
        }
        *wi = gi_phong_lobe_sample(r, b->n, u1, u2);
    } else {
        *wi = gi_to_world(gi_sample_cosine_hemisphere(u1, u2), N);
    }
    float cos_i = gi_v3_dot(N, *wi);
    if (cos_i <= 0.0f)
        return;
    float p = gi_brdf_pdf(b, N, wo, *wi);
    if (!(p > 0.0f))
        return;
    float f[3];
    gi_brdf_eval(b, N, wo, *wi, f);
    *pdf = p;
    for (int k = 0; k < 3; k++)
        weight[k] = f[k] * cos_i / p;
}

#ifdef __cplusplus
}
#endif
#endif
