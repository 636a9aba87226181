/* The implicit_vis method's cube-map bins (Sec. 4.2.2 "Discretization"):
 * the bin of a direction, a bin's centre direction and its exact solid
 * angle, in a 6 x N x N world-aligned cube map. See iv.h. */
#include "iv.h"

#include <math.h>

uint32_t iv_bin_of(gi_vec3 d, uint32_t n)
{
    return iv_bin_fast(d, n);
}

/* Face, and the texel's square [u0, u1] x [v0, v1] on it. */
static void bin_square(uint32_t b, uint32_t n, uint32_t *face, float *u0, float *u1, float *v0,
                       float *v1)
{
    *face = b / (n * n);
    uint32_t r = b % (n * n), row = r / n, col = r % n;
    *u0 = 2.0f * (float)col / (float)n - 1.0f;
    *u1 = 2.0f * (float)(col + 1) / (float)n - 1.0f;
    *v0 = 2.0f * (float)row / (float)n - 1.0f;
    *v1 = 2.0f * (float)(row + 1) / (float)n - 1.0f;
}

gi_vec3 iv_bin_centre(uint32_t b, uint32_t n)
{
    uint32_t face;
    float u0, u1, v0, v1;
    bin_square(b, n, &face, &u0, &u1, &v0, &v1);
    int ax = (int)face / 2;
    float a[3];
    a[ax] = (face & 1u) ? -1.0f : 1.0f;
    a[(ax + 1) % 3] = 0.5f * (u0 + u1);
    a[(ax + 2) % 3] = 0.5f * (v0 + v1);
    return gi_v3_normalize(gi_v3(a[0], a[1], a[2]));
}

static double texel_f(double x, double y)
{
    return atan2(x * y, sqrt(x * x + y * y + 1.0));
}

float iv_bin_solid_angle(uint32_t b, uint32_t n)
{
    uint32_t face;
    float u0, u1, v0, v1;
    bin_square(b, n, &face, &u0, &u1, &v0, &v1);
    return (float)(texel_f(u1, v1) - texel_f(u0, v1) - texel_f(u1, v0) + texel_f(u0, v0));
}
