/* Sampling building blocks shared by the reference path tracer and the GPU
 * methods: warps from [0,1)^2 to disk, hemisphere, sphere, cone and triangle
 * with their pdfs, the power heuristic for MIS, and the local shading frame.
 * C twin of core/shaders/sampling.glsl (same names, same operation order).
 *
 * Local frame: z is the normal; gi_to_world / gi_to_local use the basis of
 * gi_onb (vecmath.h). All pdfs are with respect to solid angle except the
 * disk's and the triangle's (area).
 */
#ifndef GI_SAMPLING_H
#define GI_SAMPLING_H

#include <math.h>
#include <stdint.h>

#include "gi/vecmath.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Concentric map of the unit square onto the unit disk (Shirley and Chiu
 * 1997): area-preserving up to a constant, so pdf = 1/pi w.r.t. area. */
static inline void gi_sample_concentric_disk(float u1, float u2, float *x, float *y)
{
    float a = 2.0f * u1 - 1.0f, b = 2.0f * u2 - 1.0f;
    if (a == 0.0f && b == 0.0f) {
        *x = 0.0f;
        *y = 0.0f;
        return;
    }
    float r, phi;
    if (fabsf(a) > fabsf(b)) {
        r = a;
        phi = (GI_PI / 4.0f) * (b / a);
    } else {
        r = b;
        phi = (GI_PI / 2.0f) - (GI_PI / 4.0f) * (a / b);
    }
    *x = r * cosf(phi);
    *y = r * sinf(phi);
}

/* Cosine-weighted hemisphere about +z (Malley: lift the concentric disk);
 * pdf = cos(theta) / pi. */
static inline gi_vec3 gi_sample_cosine_hemisphere(float u1, float u2)
{
    float x, y;
    gi_sample_concentric_disk(u1, u2, &x, &y);
    float z = sqrtf(fmaxf(0.0f, 1.0f - x * x - y * y));
    return gi_v3(x, y, z);
}
static inline float gi_cosine_hemisphere_pdf(float cos_theta)
{
    return cos_theta > 0.0f ? cos_theta * GI_INV_PI : 0.0f;
}

/* Uniform over the unit sphere; pdf = 1 / (4 pi). */
static inline gi_vec3 gi_sample_uniform_sphere(float u1, float u2)
{
    float z = 1.0f - 2.0f * u1;
    float r = sqrtf(fmaxf(0.0f, 1.0f - z * z));
    float phi = 2.0f * GI_PI * u2;
    return gi_v3(r * cosf(phi), r * sinf(phi), z);
}
static inline float gi_uniform_sphere_pdf(void)
{
    return 1.0f / (4.0f * GI_PI);
}

/* Uniform over the hemisphere about +z; pdf = 1 / (2 pi). */
static inline gi_vec3 gi_sample_uniform_hemisphere(float u1, float u2)
{
    float z = u1;
    float r = sqrtf(fmaxf(0.0f, 1.0f - z * z));
    float phi = 2.0f * GI_PI * u2;
    return gi_v3(r * cosf(phi), r * sinf(phi), z);
}
static inline float gi_uniform_hemisphere_pdf(void)
{
    return 1.0f / (2.0f * GI_PI);
}

/* Uniform over the cone about +z with cos(half angle) = cos_max;
 * pdf = 1 / (2 pi (1 - cos_max)). */
static inline gi_vec3 gi_sample_uniform_cone(float u1, float u2, float cos_max)
{
    float z = (1.0f - u1) + u1 * cos_max;
    float r = sqrtf(fmaxf(0.0f, 1.0f - z * z));
    float phi = 2.0f * GI_PI * u2;
    return gi_v3(r * cosf(phi), r * sinf(phi), z);
}
static inline float gi_uniform_cone_pdf(float cos_max)
{
    return 1.0f / (2.0f * GI_PI * (1.0f - cos_max));
}

/* Uniform barycentrics (b0, b1, b2) on a triangle (square-root method);
 * p = b0 A + b1 B + b2 C has pdf 1 / area. */
static inline void gi_sample_uniform_triangle(float u1, float u2, float b[3])
{
    float su = sqrtf(u1);
    b[0] = 1.0f - su;
    b[1] = u2 * su;
    b[2] = 1.0f - b[0] - b[1];
}

/* Sampling a piecewise-constant distribution from its CDF (cdf[0] = 0 <=
 * x < cdf[n] = 1, n + 1 entries): the largest k in [0, n) with cdf[k] <= x,
 * i.e. the interval [cdf[k], cdf[k+1]) holding x, never an empty one. Used
 * by the environment map and the reference's emitter choice. */
static inline uint32_t gi_cdf_find_interval(const float *cdf, uint32_t n, float x)
{
    uint32_t lo = 0, hi = n;
    while (hi - lo > 1) {
        uint32_t mid = (lo + hi) >> 1;
        if (cdf[mid] <= x)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

/* Veach's power heuristic (beta = 2) weight of strategy f, taking nf
 * samples of pdf f_pdf against ng samples of pdf g_pdf. */
static inline float gi_power_heuristic(float nf, float f_pdf, float ng, float g_pdf)
{
    float f = nf * f_pdf, g = ng * g_pdf;
    if (!(f > 0.0f))
        return 0.0f;
    /* f^2 / (f^2 + g^2) without overflow for huge (delta-like) pdfs. */
    float r = g / f;
    return 1.0f / (1.0f + r * r);
}

/* Local (z = n) -> world, and back, in the gi_onb frame of unit n. */
static inline gi_vec3 gi_to_world(gi_vec3 local, gi_vec3 n)
{
    gi_vec3 t, b;
    gi_onb(n, &t, &b);
    return gi_v3(t.x * local.x + b.x * local.y + n.x * local.z,
                 t.y * local.x + b.y * local.y + n.y * local.z,
                 t.z * local.x + b.z * local.y + n.z * local.z);
}
static inline gi_vec3 gi_to_local(gi_vec3 world, gi_vec3 n)
{
    gi_vec3 t, b;
    gi_onb(n, &t, &b);
    return gi_v3(gi_v3_dot(world, t), gi_v3_dot(world, b), gi_v3_dot(world, n));
}

#ifdef __cplusplus
}
#endif
#endif
