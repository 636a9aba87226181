// Interleaved sampling (§III-C, Keller and Heidrich 2001; Segovia et al.
// 2006): the G-buffer's positions and normals split into M = mx x mx
// sub-images in one swizzle pass. Pixel p belongs to subset
// (p.x mod mx, p.y mod mx); the sub-image of subset (a, b) is the block at
// (a sw, b sh) of the split texture, sw x sh = ceil(W / mx) x ceil(H / mx).
#include "gbuffer_read.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(rgba32f, binding = 0) uniform writeonly image2D u_split_pos;
layout(rgba32f, binding = 1) uniform writeonly image2D u_split_nrm;

uniform ivec2 u_size;   // W, H
uniform ivec2 u_sub;    // sw, sh
uniform int u_mx;

void main()
{
    ivec2 s = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(s, u_sub * u_mx)))
        return;
    ivec2 ab = s / u_sub;
    ivec2 p = (s - ab * u_sub) * u_mx + ab;
    vec4 P = vec4(0.0), N = vec4(0.0);
    if (all(lessThan(p, u_size))) {
        P = texelFetch(gi_gbuffer_position, p, 0);
        N = texelFetch(gi_gbuffer_normal, p, 0);
    }
    imageStore(u_split_pos, s, P);
    imageStore(u_split_nrm, s, N);
}
