// The final image (§III-C): the interleaved S image filtered by an mx x mx
// box (4 x 4 for M = 16, so that on a smooth surface every subset counts
// once) that leaves out neighbours across a discontinuity, found on the
// fly: normals differing (dot < u_normal_dot) or world positions farther
// apart than u_max_dist x the pixel's eye depth (that is, more than a fixed
// multiple of the window's footprint on a surface facing the camera); the
// remaining weights are renormalised; the punctual lights' part that every
// subset holds whole (avg_shade.comp) is added after the filter. Then
// times albedo / pi (Lambert), plus the emission seen directly.
#include "common.glsl"
#include "gbuffer_read.glsl"
#include "avg_bindings.h"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = AVG_TEX_INDIRECT) uniform sampler2D u_indirect;
layout(binding = AVG_TEX_WHOLE) uniform sampler2D u_whole; // punctual lights' exact part, unfiltered
layout(rgba32f, binding = GI_IMAGE_TARGET) uniform writeonly image2D u_target;

uniform ivec2 u_size;
uniform int u_mx;
uniform bool u_filter;
uniform float u_normal_dot;
uniform float u_max_dist;   // world distance limit per unit of eye depth

void main()
{
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, u_size)))
        return;
    vec4 P = texelFetch(gi_gbuffer_position, p, 0);
    vec3 L = vec3(0.0);
    if (P.w > 0.0) {
        vec3 S = texelFetch(u_indirect, p, 0).rgb;
        if (u_filter && u_mx > 1) {
            vec3 n = texelFetch(gi_gbuffer_normal, p, 0).xyz;
            vec3 sum = vec3(0.0);
            float wsum = 0.0;
            int lo = -(u_mx / 2);
            for (int dy = lo; dy < lo + u_mx; dy++) {
                for (int dx = lo; dx < lo + u_mx; dx++) {
                    ivec2 q = p + ivec2(dx, dy);
                    if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, u_size)))
                        continue;
                    vec4 Q = texelFetch(gi_gbuffer_position, q, 0);
                    if (Q.w <= 0.0)
                        continue;
                    if (dot(n, texelFetch(gi_gbuffer_normal, q, 0).xyz) < u_normal_dot)
                        continue;
                    if (distance(P.xyz, Q.xyz) > u_max_dist * P.w)
                        continue;
                    sum += texelFetch(u_indirect, q, 0).rgb;
                    wsum += 1.0;
                }
            }
            S = wsum > 0.0 ? sum / wsum : S; // the pixel itself always passes
        }
        S += texelFetch(u_whole, p, 0).rgb;
        L = texelFetch(gi_gbuffer_emission, p, 0).rgb + texelFetch(gi_gbuffer_albedo, p, 0).rgb * GI_INV_PI * S;
    }
    imageStore(u_target, p, vec4(L, 1.0));
}
