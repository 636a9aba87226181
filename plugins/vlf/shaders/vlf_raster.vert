// Propagation by the rasteriser (plugins/vlf/vlf_raster.c, paper §3.2,
// §5): the depth-ordered faces of a batch of fixed directions drawn
// orthographically along each into its tile of the interface atlas, the
// projection set here from the subfields' frames kept on the GPU (§5:
// "storing matrices for the global set of directions on the GPU and
// setting them there in a vertex shader"). One sub-draw a direction; its
// vertex ids run over its entries of the order (back to front for the
// sweep along -w_i); an entry is a scene triangle or a piece of one.
// With VLF_ESCAPE or VLF_INIT: a triangle covering the atlas.
#include "glsl_shared.h"

#if defined(VLF_ESCAPE) || defined(VLF_INIT)
void main()
{
    vec2 p = vec2(float((gl_VertexID & 1) * 4 - 1), float((gl_VertexID & 2) * 2 - 1));
    gl_Position = vec4(p, 0.0, 1.0);
}
#else
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 14) readonly buffer VlfFrames { vec4 frames[]; };
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 16) readonly buffer VlfTriP { vec4 tri_p[]; };
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 17) readonly buffer VlfOrder { uint order[]; };
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 18) readonly buffer VlfExtra { vec4 extra[]; };
// per fixed direction: first entry of its order, entries, first piece triangle
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 20) readonly buffer VlfDirs { uvec4 dirs[]; };
struct VlfFace { vec3 n; float send_scale; vec3 kd; int nd; vec3 origin; float pad; };
struct VlfChart { vec4 t; vec4 b; uvec4 whft; }; // axes (w: density); W, H, first element, twin
struct VlfRect { ivec4 r; uvec4 o; };
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 0) readonly buffer VlfFaces { VlfFace faces[]; };
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 12) readonly buffer VlfRects { VlfRect rects[]; };
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 19) readonly buffer VlfCharts { VlfChart charts[]; };
// per signed direction: travel direction, solid angle; sky radiance
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 21) readonly buffer VlfSigned { vec4 sdir[]; };

uniform uint u_l;
uniform uint u_first_dir;   // first direction of the batch (tile 0)
uniform uint u_sign;        // 1: the sweep along -w_i (the order back to front)
uniform uint u_TX, u_TY;    // tiles across and down the atlas

// per triangle, for the fragment shader (its per-fragment lookups once a
// corner instead): the point in its chart's texels, the chart (W, H, the
// first element of the side drawn) and tile rectangle, the side's cosine
// to the travel direction, send scale and the direction's solid angle
out vec2 v_uv;
flat out uvec4 v_el;
flat out ivec4 v_rect;
flat out vec4 v_k;
out float gl_ClipDistance[4];

void main()
{
    uint k = uint(gl_VertexID) / 3u, c = uint(gl_VertexID) % 3u;
    // the direction whose entries hold k: the last whose first entry is <= k
    uint lo = 0u, hi = u_l;
    while (hi - lo > 1u) {
        uint mid = (lo + hi) >> 1;
        if (dirs[mid].x <= k)
            lo = mid;
        else
            hi = mid;
    }
    uvec4 d = dirs[lo];
    uint local = k - d.x;
#if defined(VLF_BARRIER)
    uint e = order[k]; // in layers, drawn in reverse by the draws for -w_i
#else
    uint e = order[d.x + (u_sign != 0u ? d.y - 1u - local : local)];
#endif
    uint idx = e & 0x3fffffffu;
    vec4 p = (e & 0x40000000u) != 0u ? extra[3u * (d.z + idx) + c] : tri_p[3u * idx + c];
    uint fi = floatBitsToUint(p.w);
    VlfChart ch = charts[fi];
    vec3 dq = p.xyz - faces[fi].origin;
    v_uv = vec2(dot(dq, ch.t.xyz), dot(dq, ch.b.xyz)) * ch.t.w;
    uint tf = (e & 0x80000000u) != 0u ? ch.whft.w : fi;
    VlfFace fc = faces[tf];
    vec4 sd = sdir[2u * (lo + u_sign * u_l)];
    v_k = vec4(dot(fc.n, sd.xyz), fc.send_scale, sd.w, 0.0);
    v_el = uvec4(ch.whft.x, ch.whft.y, charts[tf].whft.z, 0xffffffffu);
    v_rect = ivec4(0);
    if (fc.nd >= 0) {
        VlfRect r = rects[uint(fc.nd) * u_l + lo];
        v_el.w = r.o.x;
        v_rect = r.r;
    }
    vec3 u = frames[3u * lo].xyz, v = frames[3u * lo + 1u].xyz;
    float pu = dot(p.xyz, u), pv = dot(p.xyz, v);
    uint t = lo - u_first_dir;
    vec2 tile = vec2(float(t % u_TX), float(t / u_TX));
    gl_Position = vec4((tile.x + (pu + 1.0) * 0.5) / float(u_TX) * 2.0 - 1.0,
                       (tile.y + (pv + 1.0) * 0.5) / float(u_TY) * 2.0 - 1.0, 0.0, 1.0);
    // the scene lies in the unit sphere, so inside its tile; kept there
    gl_ClipDistance[0] = 1.0 + pu;
    gl_ClipDistance[1] = 1.0 - pu;
    gl_ClipDistance[2] = 1.0 + pv;
    gl_ClipDistance[3] = 1.0 - pv;
}
#endif
