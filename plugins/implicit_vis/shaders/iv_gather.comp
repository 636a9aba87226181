// GPU illumination, gathering at the leaves (Sec. 4.3, 4.3.1, 4.4): per
// element, the radiance of the nodes at the other end of its receiving
// links (the light links only for the direct light, the paper's "Speedup"),
// each over its bin with Eq. 5 (the nearest node covering its bin, or the
// share `covered` of it; the weights from iv_weights.comp); for the direct light also the environment through
// the empty bins and the punctual lights through the bin toward them. The
// irradiance is added to the element's total, and times albedo / pi becomes
// the leaf's outgoing radiance for the next bounce. The GLSL twin of
// iv_illuminate's loop in illuminate.c.
#include "iv_gpu.glsl"

layout(local_size_x = IV_GROUP) in;
uniform uint u_base;  // first item of this dispatch
uniform uint u_count; // items in all
layout(std430, binding = IV_SSBO_ELEM) readonly buffer IvElems { IvElem iv_elem[]; };
layout(std430, binding = IV_SSBO_BINS) readonly buffer IvBins { IvBin iv_bin[]; };
layout(std430, binding = IV_SSBO_GEOM) readonly buffer IvGeom { IvNode iv_node[]; };
layout(std430, binding = IV_SSBO_RAD_SRC) readonly buffer IvRadSrc { IvRad iv_src[]; };
layout(std430, binding = IV_SSBO_RAD_DST) writeonly buffer IvRadDst { IvRad iv_dst[]; };
layout(std430, binding = IV_SSBO_LINKS) readonly buffer IvLinks { uvec4 iv_link[]; }; // bin, node, covered, length
layout(std430, binding = IV_SSBO_LINK_OFF) readonly buffer IvLinkOff { uvec2 iv_off[]; };
layout(std430, binding = IV_SSBO_WLINKS) readonly buffer IvWLinks { uvec2 iv_wl[]; }; // node | side << 30, weight
layout(std430, binding = IV_SSBO_ELEM_LIGHT) buffer IvOut { IvElemLight iv_out[]; };

struct IvPunctual { // the scene's GiLight (scene.glsl, gpu.h gi_gpu_light)
    vec3 position; uint type;
    vec3 direction; float range;
    vec3 intensity; float cos_inner;
    float cos_outer; float pad0, pad1, pad2;
};
layout(std430, binding = IV_SSBO_PUNCTUAL) readonly buffer IvPunctuals { IvPunctual iv_punctual[]; };
#include "iv_direct.glsl"
// direct=traced (README "Traced direct light"): the first gather's irradiance, traced on the CPU
layout(std430, binding = IV_SSBO_DIRECT) readonly buffer IvTraced { IvRad iv_traced[]; };

uniform uint u_bins;        // 6 n n
uniform int u_direct;       // 1: the direct light (light links, environment, punctual lights)
uniform uint u_light_base;  // the light links' first record in iv_link
uniform int u_env;          // 1: the scene has an environment
uniform int u_env_share;    // 1: a linked bin passes the environment through what its share leaves open (iv_env_partial)
uniform uint u_punctual;    // number of punctual lights
uniform int u_traced;       // 1: the direct light is iv_traced's, and the display adds its own per pixel

// Radiance node `src` sends from its side `side` (iv_weights.comp).
vec3 node_radiance(uint src, uint side)
{
    if (side == IV_SIDE_BOTH)
        return 0.5 * (iv_src[src].front.rgb + iv_src[src].back.rgb);
    return side == IV_SIDE_FRONT ? iv_src[src].front.rgb : iv_src[src].back.rgb;
}

// Radiance L through the share `frac` of bin b onto the side of the disc it falls on.
void add_bin(uint b, vec3 n, float norm, float frac, vec3 L, inout vec3 ep, inout vec3 em)
{
    float w = dot(n, iv_bin[b].dir.xyz) * iv_bin[b].dir.w * norm * frac;
    if (w >= 0.0)
        ep += w * L;
    else
        em += -w * L;
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
    bool traced = u_direct != 0 && u_traced != 0;
    uint j0 = u_direct != 0 ? u_light_base + o0.y : o0.x;
    uint j1 = traced ? j0 : (u_direct != 0 ? u_light_base + o1.y : o1.x);
    vec3 ep = traced ? iv_traced[e].front.rgb : vec3(0.0), em = traced ? iv_traced[e].back.rgb : vec3(0.0);
    for (uint j = j0; j < j1; j++) { // Eq. 5 with the weights of iv_weights.comp
        uvec2 l = iv_wl[j];
        float w = uintBitsToFloat(l.y);
        vec3 L = node_radiance(l.x & 0x3FFFFFFFu, l.x >> 30);
        if (w >= 0.0)
            ep += w * L;
        else
            em += -w * L;
    }
    if (u_direct != 0 && !traced) {
        if (u_env != 0) { // Sec. 4.4: what the links leave open of each bin sees the environment
            uint j = o0.x;
            for (uint b = 0u; b < u_bins; b++) {
                float open = 1.0;
                if (j < o1.x && iv_link[j].x == b) { // linked: closed, or open where its share leaves it
                    open = u_env_share != 0 ? max(1.0 - uintBitsToFloat(iv_link[j].z), 0.0) : 0.0;
                    j++;
                }
                if (open > 0.0)
                    add_bin(b, n, norm, open, iv_bin[b].env.rgb, ep, em);
            }
        }
        for (uint i = 0u; i < u_punctual; i++) { // blocked where the bin toward the light holds a nearer link
            IvPunctual lt = iv_punctual[i];
            vec3 wl;
            float scale;
            if (!iv_punctual_seen(lt.position, lt.type, lt.direction, lt.range, lt.cos_inner, lt.cos_outer, p, o0.x,
                                  o1.x, wl, scale))
                continue;
            float c = dot(n, wl);
            if (c >= 0.0)
                ep += abs(c) * scale * lt.intensity;
            else
                em += abs(c) * scale * lt.intensity;
        }
    }
    if (iv_elem[e].info.y == 0u) // single-sided: lit on its front only (the one rule for sides)
        em = vec3(0.0);
    if (!traced) { // traced: the display adds the direct light per pixel
        iv_out[e].e_front += vec4(ep, 0.0);
        iv_out[e].e_back += vec4(em, 0.0);
    }
    vec3 rho = iv_elem[e].albedo.rgb / GI_PI;
    iv_dst[leaf].front = vec4(rho * ep, 0.0);
    iv_dst[leaf].back = vec4(rho * em, 0.0);
}
