/* Display mapping: exposure in stops, clamp, sRGB transfer. C twin of
 * core/shaders/tonemap.glsl; used only for PNG output and for metrics that
 * need display values, never for the radiance images themselves. */
#ifndef GI_TONEMAP_H
#define GI_TONEMAP_H

#include <math.h>

#ifdef __cplusplus
extern "C" {
#endif

/* sRGB OETF of a linear value, clamped to [0, 1] (NaN gives 0). */
static inline float gi_srgb_encode(float x)
{
    x = x > 0.0f ? (x < 1.0f ? x : 1.0f) : 0.0f;
    return x <= 0.0031308f ? 12.92f * x : 1.055f * powf(x, 1.0f / 2.4f) - 0.055f;
}
/* Inverse of gi_srgb_encode, for 8-bit textures. */
static inline float gi_srgb_decode(float y)
{
    return y <= 0.04045f ? y / 12.92f : powf((y + 0.055f) / 1.055f, 2.4f);
}
/* Linear radiance -> display value in [0, 1]: scale by 2^exposure, clamp, sRGB.
 * NaN maps to 0. */
static inline float gi_tonemap(float linear, float exposure)
{
    float v = linear * exp2f(exposure);
    if (!(v == v))
        v = 0.0f;
    return gi_srgb_encode(v);
}

#ifdef __cplusplus
}
#endif
#endif
