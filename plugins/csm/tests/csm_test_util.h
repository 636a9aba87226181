/* Helpers shared by the csm plugin's integration tests (csm_local.c,
 * csm_visibility.c, csm_twins.c). */
#ifndef CSM_TEST_UTIL_H
#define CSM_TEST_UTIL_H

#include "gi/gpu.h"
#include "gi/shader.h"
#include "gi/vecmath.h"

#include <math.h>
#include <stdio.h>

/* Does the ray o + h d meet triangle (p0, p1, p2) at some 0 < h < hmax?
 * Moller-Trumbore on the CPU, independent of Embree and of the plugin; the
 * tests count these hits to tell visibility and inside/outside. */
static inline int csm_test_ray_hits_triangle(gi_vec3 p0, gi_vec3 p1, gi_vec3 p2, gi_vec3 o,
                                             gi_vec3 d, float hmax)
{
    gi_vec3 e1 = gi_v3_sub(p1, p0), e2 = gi_v3_sub(p2, p0);
    gi_vec3 pv = gi_v3_cross(d, e2);
    float det = gi_v3_dot(e1, pv);
    if (fabsf(det) < 1e-14f)
        return 0;
    gi_vec3 tv = gi_v3_sub(o, p0);
    float u = gi_v3_dot(tv, pv) / det;
    gi_vec3 qv = gi_v3_cross(tv, e1);
    float v = gi_v3_dot(d, qv) / det;
    float h = gi_v3_dot(e2, qv) / det;
    return u >= 0 && v >= 0 && u + v <= 1 && h > 0 && h < hmax;
}

/* Runs the bound compute program (64 invocations per group) over `count`
 * invocations and reads the first `bytes` of buffer `out` into dst. */
static inline void csm_test_dispatch_read(uint32_t count, GLuint out, GLsizeiptr bytes, void *dst)
{
    glDispatchCompute((count + 63) / 64, 1, 1);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    glGetNamedBufferSubData(out, 0, bytes, dst);
}

/* The GLSL queries' results, 4 floats per pair (nearest, PCF, RR averaged
 * over 256 stratified numbers, 0): mean and largest |RR - PCF|. */
static inline void csm_test_rr_error(const float *gout, int pairs, double *mean, double *max)
{
    double sum = 0, worst = 0;
    for (int p = 0; p < pairs; p++) {
        double e = fabs((double)gout[4 * p + 2] - gout[4 * p + 1]);
        sum += e;
        worst = e > worst ? e : worst;
    }
    *mean = sum / pairs;
    *max = worst;
}

/* The GL context (EGL surfaceless) with the test's embedded shaders
 * registered; NULL after a one-line error when there is no GL. */
static inline gi_gpu *csm_test_gpu(const gi_shader_source *shaders)
{
    gi_error err;
    gi_gpu *gpu = gi_gpu_create(NULL, &err);
    if (!gpu) {
        fprintf(stderr, "no GL: %s\n", err.text);
        return NULL;
    }
    if (shaders && gi_shader_register(shaders, &err) != GI_OK) {
        fprintf(stderr, "shaders: %s\n", err.text);
        gi_gpu_destroy(gpu);
        return NULL;
    }
    return gpu;
}

#endif
