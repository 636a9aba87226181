// Shading (§III-C, Fig. 4): every texel of the split G-buffer gathers the
// N_VPL / M VPLs of its subset m (VPLs m, m + M, m + 2M, ...): the VPL's
// emission times the clamped geometry term, times the VPL's visibility from
// its shadow map when visibility is on (avg_visibility.glsl). The result S is irradiance-like:
// the Lambert receiver reflects (albedo / pi) S (applied after the filter).
#define AVG_NO_GRID_SAMPLERS
#include "avg_bindings.h"
#include "avg_vpl.glsl"
#include "avg_visibility.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = AVG_TEX_SPLIT_POS) uniform sampler2D u_split_pos;
layout(binding = AVG_TEX_SPLIT_NRM) uniform sampler2D u_split_nrm;
layout(rgba32f, binding = 0) uniform writeonly image2D u_split_out;
// The punctual lights' covers (the first u_whole VPLs, avg.c
// punctual_parts), shaded at every texel: their sum is the lights' exact
// direct light, so it goes to a second image that the final pass adds
// unfiltered (filtering it would only blur its shadows).
layout(rgba32f, binding = 1) uniform writeonly image2D u_split_whole;
layout(std430, binding = AVG_SSBO_VPLS) readonly buffer AvgVpls { AvgVpl vpls[]; };

uniform ivec2 u_sub;   // sw, sh
uniform int u_mx;
uniform uint u_count;  // VPLs shaded: u_whole at every texel, then the interleaved ones
uniform uint u_whole;  // punctual lights' covers (avg.c punctual_parts)
uniform float u_dmin2; // clamping distance squared
uniform bool u_visibility;

void main()
{
    ivec2 s = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(s, u_sub * u_mx)))
        return;
    ivec2 ab = s / u_sub;
    uint M = uint(u_mx * u_mx);
    uint m = uint(ab.y * u_mx + ab.x);
    vec4 P = texelFetch(u_split_pos, s, 0);
    vec3 S = vec3(0.0), W = vec3(0.0);
    if (P.w > 0.0) {
        vec3 x = P.xyz;
        vec3 n = normalize(texelFetch(u_split_nrm, s, 0).xyz);
        for (uint j = 0u; j < u_whole; j++) {
            AvgVpl v = vpls[j];
            vec3 c = avg_vpl_contribution(v, x, n, u_dmin2);
            if (c != vec3(0.0) && u_visibility)
                c *= avg_visible(j, x, n, normalize(v.position - x));
            W += c;
        }
        for (uint j = u_whole + m; j < u_count; j += M) {
            AvgVpl v = vpls[j];
            vec3 c = avg_vpl_contribution(v, x, n, u_dmin2);
            if (c == vec3(0.0))
                continue;
            if (u_visibility)
                c *= avg_visible(j, x, n, normalize(v.position - x));
            S += c;
        }
    }
    // Each subset is an estimate of the whole VPL set: N_VPL / M VPLs stand
    // for all N_VPL, so the subset's sum counts M times.
    imageStore(u_split_out, s, vec4(S * float(M), 1.0));
    imageStore(u_split_whole, s, vec4(W, 1.0));
}
