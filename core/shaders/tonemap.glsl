// Display mapping: exposure in stops, clamp, sRGB transfer. GLSL twin of
// core/include/gi/tonemap.h; for display and metrics only, never for the
// radiance a method outputs.
#ifndef GI_TONEMAP_GLSL
#define GI_TONEMAP_GLSL

// sRGB OETF of a linear value, clamped to [0, 1] (NaN gives 0; clamp()
// leaves NaN undefined, hence the comparisons).
float gi_srgb_encode(float x)
{
    x = x > 0.0 ? min(x, 1.0) : 0.0;
    return x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1.0 / 2.4) - 0.055;
}
vec3 gi_srgb_encode(vec3 x)
{
    return vec3(gi_srgb_encode(x.r), gi_srgb_encode(x.g), gi_srgb_encode(x.b));
}

float gi_srgb_decode(float y)
{
    return y <= 0.04045 ? y / 12.92 : pow((y + 0.055) / 1.055, 2.4);
}
vec3 gi_srgb_decode(vec3 y)
{
    return vec3(gi_srgb_decode(y.r), gi_srgb_decode(y.g), gi_srgb_decode(y.b));
}

// Linear radiance -> display value in [0, 1]; NaN maps to 0.
float gi_tonemap(float x, float exposure)
{
    float v = x * exp2(exposure);
    if (isnan(v))
        v = 0.0;
    return gi_srgb_encode(v);
}
vec3 gi_tonemap(vec3 x, float exposure)
{
    return vec3(gi_tonemap(x.r, exposure), gi_tonemap(x.g, exposure), gi_tonemap(x.b, exposure));
}
#endif
