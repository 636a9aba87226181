// GPU illumination, once per frame after iv_emit.comp (Sec. 4.3.1): what
// does not change from bounce to bounce, per receiving link of each
// element: its weight in Eq. 5 (the bin's cosine-weighted solid angle
// seen from the disc, normalised, times the share of the bin the link
// covers; its sign the side of the disc it falls on) and which side of the
// node at the other end faces the element (front, back, or both averaged
// for a cluster facing every way; node_radiance in illuminate.c). The
// gathers then read one record and one radiance per link.
#include "iv_gpu.glsl"

layout(local_size_x = IV_GROUP) in;
uniform uint u_base;  // first item of this dispatch
uniform uint u_count; // items in all
layout(std430, binding = IV_SSBO_ELEM) readonly buffer IvElems { IvElem iv_elem[]; };
layout(std430, binding = IV_SSBO_BINS) readonly buffer IvBins { IvBin iv_bin[]; };
layout(std430, binding = IV_SSBO_GEOM) readonly buffer IvGeom { IvNode iv_node[]; };
layout(std430, binding = IV_SSBO_LINKS) readonly buffer IvLinks { uvec4 iv_link[]; }; // bin, node, covered, length
layout(std430, binding = IV_SSBO_LINK_OFF) readonly buffer IvLinkOff { uvec2 iv_off[]; };
layout(std430, binding = IV_SSBO_ELEM_LIGHT) readonly buffer IvOut { IvElemLight iv_out[]; };
layout(std430, binding = IV_SSBO_WLINKS) writeonly buffer IvWLinks { uvec2 iv_wl[]; }; // node | side << 30, weight

uniform uint u_light_base; // the light links' first record in iv_link

void weigh(uint j, vec3 p, vec3 n, float norm)
{
    uvec4 l = iv_link[j];
    vec3 ns = iv_node[l.y].nrm.xyz;
    uint side = dot(ns, ns) < 0.09 ? IV_SIDE_BOTH : (dot(ns, p - iv_node[l.y].pos.xyz) >= 0.0 ? IV_SIDE_FRONT : IV_SIDE_BACK);
    float w = dot(n, iv_bin[l.x].dir.xyz) * iv_bin[l.x].dir.w * norm * uintBitsToFloat(l.z);
    iv_wl[j] = uvec2(l.y | (side << 30), floatBitsToUint(w));
}

void main()
{
    uint e = u_base + gl_GlobalInvocationID.x;
    if (e >= u_count)
        return;
    uint leaf = iv_elem[e].info.x;
    vec3 p = iv_node[leaf].pos.xyz, n = iv_node[leaf].nrm.xyz;
    float norm = iv_out[e].normal.w;
    uvec2 o0 = iv_off[e], o1 = iv_off[e + 1u];
    for (uint j = o0.x; j < o1.x; j++)
        weigh(j, p, n, norm);
    for (uint j = u_light_base + o0.y; j < u_light_base + o1.y; j++)
        weigh(j, p, n, norm);
}
