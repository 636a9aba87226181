/* Storage precision of the vlf method's maps (paper §3.1, §6): the bytes a
 * value takes, and the RGBA16F and RGB9E5 encoders (see vlf_field.h). */
#include "vlf_field.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

size_t vlf_precision_bytes(uint32_t prec)
{
    return prec == VLF_PREC_16F ? 8 : prec == VLF_PREC_RGB9E5 ? 4 : 12;
}

/* IEEE half from float, rounding to nearest even; beyond the largest half
 * (65504) the largest half (a GPU would store infinity). */
static uint16_t float_to_half(float f)
{
    uint32_t x;
    memcpy(&x, &f, sizeof x);
    uint32_t sign = (x >> 16) & 0x8000u, ax = x & 0x7fffffffu;
    if (ax > 0x7f800000u)
        return 0; /* NaN: stored as 0 (values here are never NaN) */
    if (ax >= 0x477fe000u)
        return (uint16_t)(sign | 0x7bffu);
    if (ax < 0x38800000u) { /* below 2^-14: subnormal half or zero */
        if (ax < 0x33000000u)
            return (uint16_t)sign;
        uint32_t e = ax >> 23, m = (ax & 0x7fffffu) | 0x800000u, shift = 126 - e;
        uint32_t h = m >> shift, rem = m & ((1u << shift) - 1), halfway = 1u << (shift - 1);
        if (rem > halfway || (rem == halfway && (h & 1u)))
            h++;
        return (uint16_t)(sign | h);
    }
    uint32_t h = (ax - 0x38000000u) >> 13, rem = ax & 0x1fffu;
    if (rem > 0x1000u || (rem == 0x1000u && (h & 1u)))
        h++;
    if (h >= 0x7c00u)
        h = 0x7bffu;
    return (uint16_t)(sign | h);
}

static float half_to_float(uint16_t h)
{
    uint32_t e = (h >> 10) & 0x1fu, m = h & 0x3ffu;
    float f = e == 0 ? ldexpf((float)m, -24) : ldexpf((float)(m | 0x400u), (int)e - 25);
    return (h & 0x8000u) ? -f : f;
}

/* RGB9E5 as the GL spec (EXT_texture_shared_exponent) packs it: 9-bit
 * mantissas, one 5-bit exponent (bias 15), negative values as 0. */
static uint32_t pack_9e5(const float *c)
{
    const float maxv = 511.0f / 512.0f * 65536.0f;
    float v[3];
    for (int k = 0; k < 3; k++)
        v[k] = c[k] > 0.0f ? fminf(c[k], maxv) : 0.0f;
    float mx = fmaxf(v[0], fmaxf(v[1], v[2]));
    int e2 = -16;
    if (mx > 0.0f) {
        int ex;
        frexpf(mx, &ex);
        e2 = ex - 1 > -16 ? ex - 1 : -16; /* floor(log2 mx), at least -16 */
    }
    int es = e2 + 1 + 15;
    float scale = ldexpf(1.0f, es - 15 - 9);
    if ((int)floorf(mx / scale + 0.5f) == 512)
        es++, scale *= 2.0f;
    uint32_t m[3];
    for (int k = 0; k < 3; k++) {
        int q = (int)floorf(v[k] / scale + 0.5f);
        m[k] = (uint32_t)(q > 511 ? 511 : q);
    }
    return m[0] | m[1] << 9 | m[2] << 18 | (uint32_t)es << 27;
}

static void unpack_9e5(uint32_t x, float *c)
{
    float scale = ldexpf(1.0f, (int)(x >> 27) - 24);
    c[0] = (float)(x & 511u) * scale;
    c[1] = (float)((x >> 9) & 511u) * scale;
    c[2] = (float)((x >> 18) & 511u) * scale;
}

void vlf_pack(uint32_t prec, const float *rgb, size_t count, void *out)
{
    if (prec == VLF_PREC_16F) {
        uint16_t *h = out;
        for (size_t i = 0; i < count; i++) {
            for (int k = 0; k < 3; k++)
                h[4 * i + (size_t)k] = float_to_half(rgb[3 * i + (size_t)k]);
            h[4 * i + 3] = 0;
        }
    } else if (prec == VLF_PREC_RGB9E5) {
        uint32_t *w = out;
        for (size_t i = 0; i < count; i++)
            w[i] = pack_9e5(rgb + 3 * i);
    } else {
        memcpy(out, rgb, count * 3 * sizeof(float));
    }
}

void vlf_unpack(uint32_t prec, const void *in, size_t count, float *rgb)
{
    if (prec == VLF_PREC_16F) {
        const uint16_t *h = in;
        for (size_t i = 0; i < count; i++)
            for (int k = 0; k < 3; k++)
                rgb[3 * i + (size_t)k] = half_to_float(h[4 * i + (size_t)k]);
    } else if (prec == VLF_PREC_RGB9E5) {
        const uint32_t *w = in;
        for (size_t i = 0; i < count; i++)
            unpack_9e5(w[i], rgb + 3 * i);
    } else {
        memcpy(rgb, in, count * 3 * sizeof(float));
    }
}

void vlf_quantise(uint32_t prec, float *rgb, size_t count)
{
    if (prec == VLF_PREC_16F) {
        for (size_t i = 0; i < 3 * count; i++)
            rgb[i] = half_to_float(float_to_half(rgb[i]));
    } else if (prec == VLF_PREC_RGB9E5) {
        for (size_t i = 0; i < count; i++)
            unpack_9e5(pack_9e5(rgb + 3 * i), rgb + 3 * i);
    }
}
