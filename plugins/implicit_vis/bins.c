/* The implicit_vis method's cube-map bins (Sec. 4.2.2 "Discretization"):
 * the bin of a direction, a bin's centre direction and its exact solid
 * angle, in a 6 x N x N world-aligned cube map. See iv.h. */
#include "iv.h"

#include <math.h>

uint32_t iv_bin_of(gi_vec3 d, uint32_t n)
{
    float a[3] = {d.x, d.y, d.z};
    int ax = 0;
    if (fabsf(a[1]) > fabsf(a[ax]))
        ax = 1;
    if (fabsf(a[2]) > fabsf(a[ax]))
        ax = 2;
    float m = fabsf(a[ax]);
    if (!(m > 0.0f))
        return 0;
    uint32_t face = 2u * (uint32_t)ax + (a[ax] < 0.0f ? 1u : 0u);
    float u = a[(ax + 1) % 3] / m, v = a[(ax + 2) % 3] / m;
    int col = (int)floorf((u + 1.0f) * 0.5f * (float)n),
        row = (int)floorf((v + 1.0f) * 0.5f * (float)n);
    col = col < 0 ? 0 : (col >= (int)n ? (int)n - 1 : col);
    row = row < 0 ? 0 : (row >= (int)n ? (int)n - 1 : row);
    return face * n * n + (uint32_t)row * n + (uint32_t)col;
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
