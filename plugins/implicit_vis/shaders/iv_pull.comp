// GPU illumination, pull-up (Sec. 4.3, 4.3.1): one level of the hierarchy
// per dispatch, deepest first; each inner node's outgoing radiance (both
// sides) becomes the area-weighted mean of its children's.
#include "iv_gpu.glsl"

layout(local_size_x = IV_GROUP) in;
uniform uint u_base;  // first item of this dispatch
uniform uint u_count; // items in all
layout(std430, binding = IV_SSBO_CHILDREN) readonly buffer IvChildren { uvec2 iv_children[]; };
layout(std430, binding = IV_SSBO_GEOM) readonly buffer IvGeom { IvNode iv_node[]; };
layout(std430, binding = IV_SSBO_RAD_DST) buffer IvRadDst { IvRad iv_rad[]; };

void main()
{
    uint i = u_base + gl_GlobalInvocationID.x;
    if (i >= u_count)
        return;
    uvec2 c = iv_children[i];
    if (c.y == 0u)
        return; // a leaf keeps what it gathered
    float a = 0.0;
    vec3 p = vec3(0.0), m = vec3(0.0);
    for (uint k = 0u; k < c.y; k++) {
        uint ch = c.x + k;
        float w = iv_node[ch].pos.w;
        a += w;
        p += w * iv_rad[ch].front.rgb;
        m += w * iv_rad[ch].back.rgb;
    }
    iv_rad[i].front = vec4(a > 0.0 ? p / a : vec3(0.0), 0.0);
    iv_rad[i].back = vec4(a > 0.0 ? m / a : vec3(0.0), 0.0);
}
