// Propagation by the rasteriser (plugins/vlf/vlf_raster.c, paper §3.2,
// §3.3, Fig. 5): one fragment per interface ray and face, in the order the
// faces are drawn (the depth order), each reading the radiance interface
// as the faces before it left it (framebuffer fetch: the rasteriser keeps
// the primitives' order per pixel). A receiver (front side against the
// travel direction) takes the interface's radiance into its element and
// its incoming tile (flux L A_cell dOmega / A_element; the S^2 rays of a
// tile cell averaged) and lets it go on (the sums in 64-bit fixed point,
// so that they do not depend on the order the rasteriser's threads add
// in: the field is the same bit for bit run after run); a sender stops
// what reached its back and puts its unshot radiance on the interface (the
// rule for sides, as propagate.c's sweep()). Counters per ray (shot,
// received, back, escaped) accumulate in the second attachment over the
// whole propagation. VLF_INIT: each tile's interface set to its sky;
// VLF_ESCAPE: what is left on it counted as escaped. VLF_BARRIER: the
// portable variant (GL 4.5 core): the interface and the counters read as
// textures at the fragment's own texel, the faces drawn in layers in which
// no two cover a pixel, a texture barrier between (vlf_layers.c), so each
// texel is read and written once between barriers (GL 4.5 §9.3.1).
#if !defined(VLF_BARRIER)
#extension GL_EXT_shader_framebuffer_fetch : require
#endif
#include "glsl_shared.h"

#if defined(VLF_BARRIER)
layout(location = 0) out vec4 ri;
layout(location = 1) out vec4 cnt;
layout(binding = GI_TEX_PLUGIN_FIRST + 1) uniform sampler2D vlf_ri;
layout(binding = GI_TEX_PLUGIN_FIRST + 2) uniform sampler2D vlf_cnt;
#define VLF_LOAD()                                      \
    ri = texelFetch(vlf_ri, ivec2(gl_FragCoord.xy), 0); \
    cnt = texelFetch(vlf_cnt, ivec2(gl_FragCoord.xy), 0)
#else
layout(location = 0) inout vec4 ri;
layout(location = 1) inout vec4 cnt;
#define VLF_LOAD()
#endif

// per signed direction: travel direction, solid angle; sky radiance
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 21) readonly buffer VlfSigned { vec4 sdir[]; };

uniform uint u_l;
uniform uint u_first_dir;   // first direction of the batch (tile 0)
uniform uint u_sign;        // 0: along +w_i, 1: along -w_i
uniform uint u_NS;          // interface rays per side of a tile
uniform uint u_TX;          // tiles across the atlas
uniform float u_cell_area;  // of an interface cell

// the signed direction of this tile (u_l * 2 outside the batch's tiles)
uint tile_dir(uvec2 px)
{
    uvec2 t = px / u_NS;
    uint i = u_first_dir + t.y * u_TX + t.x;
    return i < u_l ? i + u_sign * u_l : 2u * u_l;
}

#if defined(VLF_INIT)
void main()
{
    uint sd = tile_dir(uvec2(gl_FragCoord.xy));
    ri = sd < 2u * u_l ? vec4(sdir[2u * sd + 1u].rgb, 0.0) : vec4(0.0);
}
#elif defined(VLF_ESCAPE)
void main()
{
    VLF_LOAD();
    uint sd = tile_dir(uvec2(gl_FragCoord.xy));
    if (sd < 2u * u_l)
        cnt.w += (ri.r + ri.g + ri.b) * u_cell_area * sdir[2u * sd].w / 3.0;
}
#else
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 2) readonly buffer VlfElemArea { float elem_area[]; };
// what the receivers bring: per element (u_ne values), then per tile
// cell, each value two words (fraction x 2^32, integer part)
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 6) buffer VlfAcc { uint acc[]; };
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 7) readonly buffer VlfEMap { float emap[]; };
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 8) readonly buffer VlfTMap { float tmap[]; };

uniform uint u_S;           // interface rays per subfield cell and side
uniform uint u_ne;          // 3 x elements
uniform float u_min_area;   // smallest element area used as divisor
uniform float u_inv_s2;     // 1 / S^2

// what is constant over a triangle comes flat from the vertex shader
// (shaders/vlf_raster.vert), so a fragment reads only its element's and
// tile cell's values
in vec2 v_uv;         // the point in its chart's texels
flat in uvec4 v_el;   // chart W, H, first element (the side's), tile offset (~0: none)
flat in ivec4 v_rect; // the tile's rectangle of the direction: x0, y0, w
flat in vec4 v_k;     // cos to the travel direction, send scale, dOmega

// Adds v >= 0 to value k of acc: a 64-bit fixed-point add from two 32-bit
// atomics, the carry out of the low word into the high one (integer sums
// are exact, hence independent of order; a zero word is not added).
void acc_add(uint k, float v)
{
    float fl = floor(v);
    uint hi = uint(fl);
    uint lo = uint(min((v - fl) * 4294967296.0, 4294967040.0));
    if (lo != 0u) {
        uint old = atomicAdd(acc[2u * k], lo);
        if (old + lo < old)
            hi++;
    }
    if (hi != 0u)
        atomicAdd(acc[2u * k + 1u], hi);
}

void main()
{
    VLF_LOAD();
    // the element holding the ray's point (vlf_element_at): the face's
    // chart, on the twin's side its twin's elements (the same chart)
    int ix = clamp(int(floor(v_uv.x)), 0, int(v_el.x) - 1);
    int iy = clamp(int(floor(v_uv.y)), 0, int(v_el.y) - 1);
    uint el = v_el.z + uint(iy) * v_el.x + uint(ix);
    float cs = v_k.x, w = u_cell_area * v_k.z / 3.0;
    uint slot = 0xffffffffu;
    if (v_el.w != 0xffffffffu) {
        ivec2 c = ivec2((uvec2(gl_FragCoord.xy) % u_NS) / u_S);
        slot = v_el.w + uint(c.y - v_rect.y) * uint(v_rect.z) + uint(c.x - v_rect.x);
    }
    vec3 L = ri.rgb;
    vec4 k = cnt;
    float lum = L.r + L.g + L.b;
    if (cs < 0.0) {
        float s = u_cell_area * v_k.z / max(elem_area[el], u_min_area);
        for (uint q = 0u; q < 3u; q++)
            acc_add(3u * el + q, L[q] * s);
        if (slot != 0xffffffffu)
            for (uint q = 0u; q < 3u; q++)
                acc_add(u_ne + 3u * slot + q, L[q] * u_inv_s2);
        k.y += lum * w; // and it goes on (the rule for sides)
    } else if (cs > 0.0) {
        k.z += lum * w;
        uint b = 2u * u_ne + 3u * el; // L_cur
        vec3 own = vec3(emap[b], emap[b + 1u], emap[b + 2u]) * v_k.y;
        if (slot != 0xffffffffu)
            own += vec3(tmap[3u * slot], tmap[3u * slot + 1u], tmap[3u * slot + 2u]); // out_cur
        L = own;
        k.x += (own.r + own.g + own.b) * w;
    }
    // both written on every path
    ri = vec4(L, 0.0);
    cnt = k;
}
#endif
