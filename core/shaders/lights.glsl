// Light helpers: GLSL twin of core/include/gi/lights.h (same formulas).
#ifndef GI_LIGHTS_GLSL
#define GI_LIGHTS_GLSL

float gi_spot_falloff(float cos_angle, float cos_inner, float cos_outer)
{
    if (cos_inner <= cos_outer)
        return cos_angle >= cos_outer ? 1.0 : 0.0;
    float t = clamp((cos_angle - cos_outer) / (cos_inner - cos_outer), 0.0, 1.0);
    return t * t;
}

float gi_range_window(float d, float range)
{
    if (range <= 0.0)
        return 1.0;
    float r = d / range;
    float w = max(1.0 - r * r * r * r, 0.0);
    return w * w;
}

float gi_emitter_cos(vec3 ng_unit, vec3 w_to_light, bool double_sided)
{
    float c = -dot(ng_unit, w_to_light);
    return double_sided ? abs(c) : max(c, 0.0);
}
#endif
