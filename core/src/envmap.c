/* Environment map: equirectangular radiance with a piecewise-constant
 * importance-sampling distribution (pbrt's 2D distribution, PBR 3rd ed.
 * 13.6.7 / 14.2.4). C twin of core/shaders/envmap.glsl: both read the same
 * CDF tables and do the same binary searches, so they draw the same samples.
 *
 * Texel (i, j) has weight lum(i, j) x sin(theta_j), theta_j = (j + 1/2) pi / h
 * the angle of its centre. The pdf over (u, v) is constant per texel,
 *     p(u, v) = (M[j+1] - M[j]) h (C_j[i+1] - C_j[i]) w,
 * read from the marginal (M) and conditional (C_j) CDFs themselves, which is
 * exactly the probability with which the sampler picks the texel; over solid
 * angle it is p(u, v) / (2 pi^2 sin theta) with theta of the direction.
 * (u1 picks the column inside the row, u2 the row.)
 *
 * A black map has an all-zero marginal CDF (M[h] = 0): the GPU side tests
 * that to return pdf 0. A black row inside a lit map gets a uniform
 * conditional CDF; the marginal never selects it. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gi/envmap.h"
#include "gi/sampling.h"

/* Direction in the map's frame: rotate d by -rotation about +Y. */
static gi_vec3 to_map_frame(float rotation, gi_vec3 d)
{
    float c = cosf(rotation), s = sinf(rotation);
    return gi_v3(c * d.x - s * d.z, d.y, s * d.x + c * d.z);
}

static gi_vec3 from_map_frame(float rotation, gi_vec3 d)
{
    float c = cosf(rotation), s = sinf(rotation);
    return gi_v3(c * d.x + s * d.z, d.y, -s * d.x + c * d.z);
}

static float clamp_unit(float x)
{
    return x < 0.0f ? 0.0f : (x < 0x1.fffffep-1f ? x : 0x1.fffffep-1f);
}

gi_envmap *gi_envmap_create(const float *rgba, uint32_t width, uint32_t height, float intensity,
                            float rotation_deg)
{
    if (!rgba || width == 0 || height == 0 || (uint64_t)width * height > (1ull << 28))
        return NULL;
    gi_envmap *env = calloc(1, sizeof *env);
    if (!env)
        return NULL;
    size_t n = (size_t)width * height;
    env->width = width;
    env->height = height;
    env->rotation = rotation_deg * (GI_PI / 180.0f);
    env->rgb = malloc(n * 3 * sizeof(float));
    env->cond_cdf = malloc((size_t)(width + 1) * height * sizeof(float));
    env->marg_cdf = malloc((size_t)(height + 1) * sizeof(float));
    env->row_weight = malloc((size_t)height * sizeof(float));
    if (!env->rgb || !env->cond_cdf || !env->marg_cdf || !env->row_weight) {
        gi_envmap_free(env);
        return NULL;
    }
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++)
            env->rgb[i * 3 + c] = rgba[i * 4 + c] * intensity;

    /* Rows: conditional CDFs from double partial sums. */
    double total = 0.0;
    for (uint32_t j = 0; j < height; j++) {
        float sin_theta = sinf(((float)j + 0.5f) * GI_PI / (float)height);
        float *cdf = env->cond_cdf + (size_t)j * (width + 1);
        double sum = 0.0;
        for (int pass = 0; pass < 2; pass++) {
            double acc = 0.0;
            for (uint32_t i = 0; i < width; i++) {
                float lum = gi_luminance(env->rgb + ((size_t)j * width + i) * 3);
                /* Negative or non-finite radiance cannot be sampled. */
                acc += (lum > 0.0f && isfinite(lum)) ? (double)lum * sin_theta : 0.0;
                if (pass == 1)
                    cdf[i + 1] = sum > 0.0 ? (float)(acc / sum) : (float)(i + 1) / (float)width;
            }
            sum = acc;
        }
        cdf[0] = 0.0f;
        cdf[width] = 1.0f;
        env->row_weight[j] = (float)sum;
        total += sum;
    }

    /* Marginal CDF over rows. */
    env->marg_cdf[0] = 0.0f;
    double acc = 0.0;
    for (uint32_t j = 0; j < height; j++) {
        acc += env->row_weight[j];
        env->marg_cdf[j + 1] = total > 0.0 ? (float)(acc / total) : 0.0f;
    }
    if (total > 0.0)
        env->marg_cdf[height] = 1.0f;
    /* Integral of lum x sin(theta) over (u, v) in [0,1]^2. */
    env->total_weight = total / ((double)width * height);
    return env;
}

uint64_t gi_envmap_count_nonfinite(const float *rgba, uint32_t width, uint32_t height, uint32_t *x,
                                   uint32_t *y)
{
    uint64_t bad = 0;
    for (size_t i = 0; rgba && i < (size_t)width * height; i++) {
        const float *p = rgba + 4 * i;
        if (isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]))
            continue;
        if (!bad++) {
            *x = (uint32_t)(i % width);
            *y = (uint32_t)(i / width);
        }
    }
    return bad;
}

void gi_envmap_free(gi_envmap *env)
{
    if (!env)
        return;
    free(env->rgb);
    free(env->cond_cdf);
    free(env->marg_cdf);
    free(env->row_weight);
    free(env);
}

void gi_envmap_dir_to_uv(const gi_envmap *env, gi_vec3 d, float *u, float *v)
{
    gi_vec3 m = to_map_frame(env->rotation, d);
    /* At the poles u is arbitrary; pin it (GLSL's atan(0, 0) is undefined). */
    float uu = (m.x == 0.0f && m.z == 0.0f) ? 0.5f : 0.5f + atan2f(m.x, -m.z) * (0.5f * GI_INV_PI);
    /* acos(d.y) as atan2(|d.xz|, d.y): accurate near the poles, and GPU
     * acos can be poor (llvmpipe's is off by 1.6e-4 rad). */
    float vv = atan2f(sqrtf(m.x * m.x + m.z * m.z), m.y) * GI_INV_PI;
    if (uu >= 1.0f)
        uu -= 1.0f;
    *u = clamp_unit(uu);
    *v = clamp_unit(vv);
}

gi_vec3 gi_envmap_uv_to_dir(const gi_envmap *env, float u, float v)
{
    float phi = (u - 0.5f) * (2.0f * GI_PI);
    float theta = v * GI_PI;
    float sin_t = sinf(theta);
    gi_vec3 m = gi_v3(sin_t * sinf(phi), cosf(theta), -sin_t * cosf(phi));
    return from_map_frame(env->rotation, m);
}

/* Texel holding (u, v) in [0,1)^2. */
static void texel_of(const gi_envmap *env, float u, float v, uint32_t *i, uint32_t *j)
{
    uint32_t x = (uint32_t)(u * (float)env->width);
    uint32_t y = (uint32_t)(v * (float)env->height);
    *i = x < env->width ? x : env->width - 1;
    *j = y < env->height ? y : env->height - 1;
}

void gi_envmap_eval(const gi_envmap *env, gi_vec3 d, float out[3])
{
    float u, v;
    uint32_t i, j;
    gi_envmap_dir_to_uv(env, d, &u, &v);
    texel_of(env, u, v, &i, &j);
    memcpy(out, env->rgb + ((size_t)j * env->width + i) * 3, 3 * sizeof(float));
}

/* p(u, v) of texel (i, j) from the CDF tables, over solid angle at v. */
static float texel_pdf(const gi_envmap *env, uint32_t i, uint32_t j, float v)
{
    const float *cdf = env->cond_cdf + (size_t)j * (env->width + 1);
    float p_row = (env->marg_cdf[j + 1] - env->marg_cdf[j]) * (float)env->height;
    float p_col = (cdf[i + 1] - cdf[i]) * (float)env->width;
    float sin_t = sinf(v * GI_PI);
    if (!(sin_t > 0.0f))
        return 0.0f;
    return p_row * p_col / (2.0f * GI_PI * GI_PI * sin_t);
}

float gi_envmap_sample(const gi_envmap *env, float u1, float u2, gi_vec3 *dir)
{
    const uint32_t w = env->width, h = env->height;
    if (!(env->marg_cdf[h] > 0.0f)) {
        *dir = gi_v3(0.0f, 1.0f, 0.0f);
        return 0.0f;
    }
    uint32_t j = gi_cdf_find_interval(env->marg_cdf, h, u2);
    float m0 = env->marg_cdf[j], m1 = env->marg_cdf[j + 1];
    float dv = (u2 - m0) / (m1 - m0);
    const float *cdf = env->cond_cdf + (size_t)j * (w + 1);
    uint32_t i = gi_cdf_find_interval(cdf, w, u1);
    float c0 = cdf[i], c1 = cdf[i + 1];
    float du = (u1 - c0) / (c1 - c0);
    /* Stay inside the chosen texel whatever the rounding. */
    float u = fminf(((float)i + clamp_unit(du)) / (float)w, 0x1.fffffep-1f);
    float v = fminf(((float)j + clamp_unit(dv)) / (float)h, 0x1.fffffep-1f);
    *dir = gi_envmap_uv_to_dir(env, u, v);
    return texel_pdf(env, i, j, v);
}

float gi_envmap_pdf(const gi_envmap *env, gi_vec3 d)
{
    if (!(env->marg_cdf[env->height] > 0.0f))
        return 0.0f;
    float u, v;
    uint32_t i, j;
    gi_envmap_dir_to_uv(env, d, &u, &v);
    texel_of(env, u, v, &i, &j);
    return texel_pdf(env, i, j, v);
}

float gi_envmap_mis_direction(const gi_envmap *env, gi_vec3 n, uint32_t k, uint32_t K, float u1,
                              float u2, gi_vec3 *w)
{
    const uint32_t half = K > 1 ? K / 2 : 1, Kc = K > half ? K - half : 0;
    if (k < half) {
        if (!(gi_envmap_sample(env, u1, u2, w) > 0.0f))
            return 0.0f;
    } else {
        *w = gi_to_world(gi_sample_cosine_hemisphere(u1, u2), n);
    }
    float cs = gi_v3_dot(n, *w);
    if (!(cs > 0.0f))
        return 0.0f;
    float denom = (float)half * gi_envmap_pdf(env, *w) + (float)Kc * gi_cosine_hemisphere_pdf(cs);
    return denom > 0.0f ? cs / denom : 0.0f;
}

float gi_envmap_average_radiance(const gi_envmap *env)
{
    /* (1 / 4 pi) Int L dw, with dw = 2 pi^2 sin(theta) du dv. */
    return (float)(env->total_weight * (GI_PI / 2.0));
}
