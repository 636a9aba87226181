// GPU illumination, first pass (Sec. 4.3.1): per element, the emission as
// the leaf's outgoing radiance (bounce 0), its irradiance cleared, and the
// normalisation of its bins (cosine-weighted solid angles summing to pi
// over a hemisphere, as iv_illuminate in illuminate.c).
#include "iv_gpu.glsl"

layout(local_size_x = IV_GROUP) in;
uniform uint u_base;  // first item of this dispatch
uniform uint u_count; // items in all
layout(std430, binding = IV_SSBO_ELEM) readonly buffer IvElems { IvElem iv_elem[]; };
layout(std430, binding = IV_SSBO_BINS) readonly buffer IvBins { IvBin iv_bin[]; };
layout(std430, binding = IV_SSBO_GEOM) readonly buffer IvGeom { IvNode iv_node[]; };
layout(std430, binding = IV_SSBO_RAD_DST) writeonly buffer IvRadDst { IvRad iv_rad[]; };
layout(std430, binding = IV_SSBO_ELEM_LIGHT) writeonly buffer IvOut { IvElemLight iv_out[]; };

uniform uint u_bins;

void main()
{
    uint e = u_base + gl_GlobalInvocationID.x;
    if (e >= u_count)
        return;
    uint leaf = iv_elem[e].info.x;
    vec3 n = iv_node[leaf].nrm.xyz;
    float s = 0.0;
    for (uint b = 0u; b < u_bins; b++)
        s += abs(dot(n, iv_bin[b].dir.xyz)) * iv_bin[b].dir.w;
    float norm = s > 0.0 ? 2.0 * GI_PI / s : 0.0;
    iv_out[e].e_front = vec4(0.0);
    iv_out[e].e_back = vec4(0.0);
    iv_out[e].normal = vec4(n, norm);
    vec3 le = iv_elem[e].emit.rgb;
    iv_rad[leaf].front = vec4(le, 0.0);
    iv_rad[leaf].back = vec4(iv_elem[e].info.y != 0u ? le : vec3(0.0), 0.0);
}
