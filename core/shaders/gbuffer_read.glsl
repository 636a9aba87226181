// The G-buffer (passes.h) as a method reads it: samplers at the named units
// of glsl_shared.h (gi_kit_bind binds them) and one decoded surface per
// pixel. C side: gi_gbuffer (passes.h), gi_kit (kit.h).
#ifndef GI_GBUFFER_READ_GLSL
#define GI_GBUFFER_READ_GLSL
#include "glsl_shared.h"
#include "brdf.glsl"

layout(binding = GI_TEX_GBUFFER_POSITION) uniform sampler2D gi_gbuffer_position; // xyz world, w eye depth (0: no hit)
layout(binding = GI_TEX_GBUFFER_NORMAL) uniform sampler2D gi_gbuffer_normal;     // world shading normal, facing the eye
layout(binding = GI_TEX_GBUFFER_ALBEDO) uniform sampler2D gi_gbuffer_albedo;     // Lambert albedo, a = 1 mirror
layout(binding = GI_TEX_GBUFFER_PHONG) uniform sampler2D gi_gbuffer_phong;       // ks rgb, exponent
layout(binding = GI_TEX_GBUFFER_EMISSION) uniform sampler2D gi_gbuffer_emission; // emitted radiance toward the eye
layout(binding = GI_TEX_GBUFFER_IDS) uniform usampler2D gi_gbuffer_ids;          // object, material, triangle

// One pixel's visible surface.
struct GiSurface {
    bool hit;        // false where the view ray left the scene
    vec3 position;   // world
    float eye_depth; // linear eye depth
    vec3 normal;     // unit, facing the eye
    gi_brdf brdf;    // kd, ks, n, mirror
    vec3 emission;   // emitted radiance toward the eye
};

GiSurface gi_gbuffer_surface(ivec2 px)
{
    GiSurface s;
    vec4 P = texelFetch(gi_gbuffer_position, px, 0);
    s.hit = P.w > 0.0;
    s.position = P.xyz;
    s.eye_depth = P.w;
    s.normal = s.hit ? normalize(texelFetch(gi_gbuffer_normal, px, 0).xyz) : vec3(0.0);
    vec4 alb = texelFetch(gi_gbuffer_albedo, px, 0);
    vec4 ph = texelFetch(gi_gbuffer_phong, px, 0);
    s.brdf.kd = alb.rgb;
    s.brdf.ks = ph.rgb;
    s.brdf.n = ph.a;
    s.brdf.mirror = alb.a > 0.5 ? 1 : 0;
    s.emission = texelFetch(gi_gbuffer_emission, px, 0).rgb;
    return s;
}

// Object, material and triangle of the pixel (GI_NO_ID where nothing was hit).
uvec3 gi_gbuffer_ids_at(ivec2 px) { return texelFetch(gi_gbuffer_ids, px, 0).xyz; }
#endif
