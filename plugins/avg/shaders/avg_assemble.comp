// Reassembly (§III-C): the shaded sub-images swizzled back into one
// interleaved image (the inverse of avg_split.comp).
layout(local_size_x = 8, local_size_y = 8) in;

#include "avg_bindings.h"

layout(binding = AVG_TEX_SPLIT_OUT) uniform sampler2D u_split_out;
layout(binding = AVG_TEX_SPLIT_WHOLE) uniform sampler2D u_split_whole;
layout(rgba32f, binding = 0) uniform writeonly image2D u_indirect;
layout(rgba32f, binding = 1) uniform writeonly image2D u_whole;

uniform ivec2 u_size;
uniform ivec2 u_sub;
uniform int u_mx;

void main()
{
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, u_size)))
        return;
    ivec2 ab = p % u_mx;
    ivec2 s = ab * u_sub + p / u_mx;
    imageStore(u_indirect, p, texelFetch(u_split_out, s, 0));
    imageStore(u_whole, p, texelFetch(u_split_whole, s, 0));
}
