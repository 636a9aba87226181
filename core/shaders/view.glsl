// The frame's view as gi_kit_bind sets it (kit.h), the eye ray through a
// pixel, and the background a pixel shows where its ray leaves the scene.
#ifndef GI_VIEW_GLSL
#define GI_VIEW_GLSL
#include "scene.glsl"
#include "envmap.glsl"

uniform vec3 u_eye;
uniform mat4 u_inv_view_proj;
uniform ivec2 u_size;
uniform uint u_frame; // frames already in the running average
uniform uint u_seed;

// Unit direction of the eye ray through the centre of pixel px (row 0 at the bottom).
vec3 gi_view_ray(ivec2 px)
{
    vec2 ndc = (vec2(px) + 0.5) / vec2(u_size) * 2.0 - 1.0;
    vec4 far_point = u_inv_view_proj * vec4(ndc, 1.0, 1.0);
    return normalize(far_point.xyz / far_point.w - u_eye);
}

// What pixel px shows where nothing was hit: the environment map seen
// directly, or black without one.
vec3 gi_background(ivec2 px)
{
    return gi_has_environment() ? gi_envmap_eval(gi_view_ray(px)) : vec3(0.0);
}
#endif
