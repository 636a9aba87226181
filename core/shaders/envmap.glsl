// Environment map: radiance lookup and importance sampling from the
// textures the core uploads (gpu.h): GI_TEX_ENV = 0 radiance RGBA32F w x h
// (intensity applied, row 0 = v = 0 = top), GI_TEX_ENV_COND = 1 R32F
// (w+1) x h conditional CDFs, GI_TEX_ENV_MARG = 2 R32F (h+1) x 1 marginal
// CDF. GLSL twin of core/include/gi/envmap.h / core/src/envmap.c: same
// mapping, same binary searches over the same tables, same pdf.
//
// The map's rotation about +Y (radians, gi_envmap.rotation) comes from
// GI_ENV_ROTATION. scene.glsl defines it (the scene-info block), so include
// scene.glsl BEFORE this file; without scene.glsl, define it yourself or set
// the uniform gi_env_rotation declared here.
// Only call these when the scene has an environment (gi_has_environment()).
#ifndef GI_ENVMAP_GLSL
#define GI_ENVMAP_GLSL
#include "common.glsl"
#include "glsl_shared.h"

layout(binding = GI_TEX_ENV) uniform sampler2D gi_env_radiance;
layout(binding = GI_TEX_ENV_COND) uniform sampler2D gi_env_cond_cdf;
layout(binding = GI_TEX_ENV_MARG) uniform sampler2D gi_env_marg_cdf;

#ifndef GI_ENV_ROTATION
uniform float gi_env_rotation;
#define GI_ENV_ROTATION gi_env_rotation
#endif

ivec2 gi_envmap_size()
{
    return textureSize(gi_env_radiance, 0);
}

// Rotate by -rotation about +Y (world -> map frame), and back.
vec3 gi_envmap_to_map_frame(vec3 d)
{
    float c = cos(GI_ENV_ROTATION), s = sin(GI_ENV_ROTATION);
    return vec3(c * d.x - s * d.z, d.y, s * d.x + c * d.z);
}
vec3 gi_envmap_from_map_frame(vec3 d)
{
    float c = cos(GI_ENV_ROTATION), s = sin(GI_ENV_ROTATION);
    return vec3(c * d.x + s * d.z, d.y, -s * d.x + c * d.z);
}

// u = 0.5 + atan2(d.x, -d.z) / (2 pi), v = acos(d.y) / pi, in [0, 1).
vec2 gi_envmap_dir_to_uv(vec3 d)
{
    vec3 m = gi_envmap_to_map_frame(d);
    float u = (m.x == 0.0 && m.z == 0.0) ? 0.5 : 0.5 + atan(m.x, -m.z) * (0.5 * GI_INV_PI);
    // acos(d.y) as atan(|d.xz|, d.y), as in envmap.c (GPU acos can be poor).
    float v = atan(sqrt(m.x * m.x + m.z * m.z), m.y) * GI_INV_PI;
    if (u >= 1.0)
        u -= 1.0;
    return clamp(vec2(u, v), 0.0, GI_ONE_MINUS_EPSILON);
}

vec3 gi_envmap_uv_to_dir(vec2 uv)
{
    float phi = (uv.x - 0.5) * (2.0 * GI_PI);
    float theta = uv.y * GI_PI;
    float sin_t = sin(theta);
    return gi_envmap_from_map_frame(vec3(sin_t * sin(phi), cos(theta), -sin_t * cos(phi)));
}

ivec2 gi_envmap_texel(vec2 uv)
{
    ivec2 size = gi_envmap_size();
    return min(ivec2(uv * vec2(size)), size - 1);
}

// Radiance seen in direction d (nearest texel).
vec3 gi_envmap_eval(vec3 d)
{
    return texelFetch(gi_env_radiance, gi_envmap_texel(gi_envmap_dir_to_uv(d)), 0).rgb;
}

// Solid-angle pdf of texel t at v, from the CDF differences.
float gi_envmap_texel_pdf(ivec2 t, float v)
{
    ivec2 size = gi_envmap_size();
    float p_row = (texelFetch(gi_env_marg_cdf, ivec2(t.y + 1, 0), 0).r -
                   texelFetch(gi_env_marg_cdf, ivec2(t.y, 0), 0).r) * float(size.y);
    float p_col = (texelFetch(gi_env_cond_cdf, ivec2(t.x + 1, t.y), 0).r -
                   texelFetch(gi_env_cond_cdf, ivec2(t.x, t.y), 0).r) * float(size.x);
    float sin_t = sin(v * GI_PI);
    if (!(sin_t > 0.0))
        return 0.0;
    return p_row * p_col / (2.0 * GI_PI * GI_PI * sin_t);
}

bool gi_envmap_is_black()
{
    return !(texelFetch(gi_env_marg_cdf, ivec2(gi_envmap_size().y, 0), 0).r > 0.0);
}

// Draws a direction from (u1, u2) in [0,1)^2 (u2: row by the marginal CDF,
// u1: column by the row's CDF, linear inside the texel); returns its
// solid-angle pdf, 0 (and dir = +Y) for a black map.
float gi_envmap_sample(float u1, float u2, out vec3 dir)
{
    ivec2 size = gi_envmap_size();
    if (gi_envmap_is_black()) {
        dir = vec3(0.0, 1.0, 0.0);
        return 0.0;
    }
    // Largest j with marg[j] <= u2, then largest i with cond_j[i] <= u1.
    int lo = 0, hi = size.y;
    while (hi - lo > 1) {
        int mid = (lo + hi) >> 1;
        if (texelFetch(gi_env_marg_cdf, ivec2(mid, 0), 0).r <= u2)
            lo = mid;
        else
            hi = mid;
    }
    int j = lo;
    float m0 = texelFetch(gi_env_marg_cdf, ivec2(j, 0), 0).r;
    float m1 = texelFetch(gi_env_marg_cdf, ivec2(j + 1, 0), 0).r;
    float dv = (u2 - m0) / (m1 - m0);
    lo = 0;
    hi = size.x;
    while (hi - lo > 1) {
        int mid = (lo + hi) >> 1;
        if (texelFetch(gi_env_cond_cdf, ivec2(mid, j), 0).r <= u1)
            lo = mid;
        else
            hi = mid;
    }
    int i = lo;
    float c0 = texelFetch(gi_env_cond_cdf, ivec2(i, j), 0).r;
    float c1 = texelFetch(gi_env_cond_cdf, ivec2(i + 1, j), 0).r;
    float du = (u1 - c0) / (c1 - c0);
    float u = min((float(i) + clamp(du, 0.0, GI_ONE_MINUS_EPSILON)) / float(size.x),
                  GI_ONE_MINUS_EPSILON);
    float v = min((float(j) + clamp(dv, 0.0, GI_ONE_MINUS_EPSILON)) / float(size.y),
                  GI_ONE_MINUS_EPSILON);
    dir = gi_envmap_uv_to_dir(vec2(u, v));
    return gi_envmap_texel_pdf(ivec2(i, j), v);
}

float gi_envmap_pdf(vec3 d)
{
    if (gi_envmap_is_black())
        return 0.0;
    vec2 uv = gi_envmap_dir_to_uv(d);
    return gi_envmap_texel_pdf(gi_envmap_texel(uv), uv.y);
}
#endif
