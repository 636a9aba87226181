// Local and semi-local lights of the csm plugin (§4.2, §4.3, §3.3, §4.5,
// §4.6): GLSL twin of plugins/csm/csm_local.c (formulas in csm_local.h).
// Buffers (plugins/csm/csm.c uploads them), besides csm_query.glsl's:
//   binding 14 CsmLights     per light: world rectangle o, e1, e2 (o.w = kind:
//                            0 area, 1 linear, 2 point), info = (n_u, n_v,
//                            cells base, source: emissive object, or
//                            0x80000000 | punctual light index)
//   binding 15 CsmPairs      per (light j, object k) at j * csm_object_count + k:
//                            the light's rectangle in object k's local space
//                            (o.w = 1 when object k can shadow light j, else
//                            0: its own emitter, a receiver-only object, or,
//                            semi-local, an object whose bounds hold the
//                            light), info = (M, offsets base, segments base,
//                            bias in local units), M = 0 without cube maps
//   binding 16 CsmLightCells [0, csm_object_count): light of each object
//                            (0xFFFFFFFF none); then per light the enumeration
//                            index of grid cell (a, b) at cells base + b n_u + a
// Uniforms: csm_light_count, csm_semilocal (1: the orthographic maps with
// d = l - p, §4.3), csm_normal_offset_local, csm_dilate_local (1: the other
// objects' cube maps are tested with mode 3 below, occluders=dilated).
#ifndef CSM_LOCAL_GLSL
#define CSM_LOCAL_GLSL
#include "common.glsl" // gi_cube_face: the faces and tie rule of gi/algo/cubemap.h
#include "csm_query.glsl"

struct CsmLight {
    vec4 o, e1, e2;
    uvec4 info;
};
struct CsmPair {
    vec4 o, e1, e2;
    uvec4 info;
};
layout(std430, binding = 14) readonly buffer CsmLights { CsmLight csm_lights[]; };
layout(std430, binding = 15) readonly buffer CsmPairs { CsmPair csm_pairs[]; };
layout(std430, binding = 16) readonly buffer CsmLightCells { uint csm_light_cells[]; };

uniform uint csm_light_count;
uniform int csm_semilocal;
uniform float csm_normal_offset_local; // texels of the cube face at x's distance
uniform int csm_dilate_local;          // 1: occluders=dilated (README "Sub-texel occluders")

vec3 csm_light_point(vec3 o, vec3 e1, vec3 e2, uint n_u, uint n_v, uint a, uint b)
{
    float fu = (float(a) + 0.5) / float(n_u), fv = (float(b) + 0.5) / float(n_v);
    return o + (e1 * fu + e2 * fv);
}

vec2 csm_light_grid(vec3 o, vec3 e1, vec3 e2, uint n_u, uint n_v, vec3 y)
{
    vec3 q = y - o;
    float l1 = dot(e1, e1), l2 = dot(e2, e2);
    return vec2(n_u > 1u && l1 > 0.0 ? dot(q, e1) / l1 * float(n_u) - 0.5 : 0.0,
                n_v > 1u && l2 > 0.0 ? dot(q, e2) / l2 * float(n_v) - 0.5 : 0.0);
}

void csm_cube_basis(int face, out vec3 s, out vec3 t, out vec3 f)
{
    const vec3 dirs[6] = vec3[6](vec3(1, 0, 0), vec3(-1, 0, 0), vec3(0, 1, 0), vec3(0, -1, 0), vec3(0, 0, 1),
                                 vec3(0, 0, -1));
    const vec3 ups[6] = vec3[6](vec3(0, -1, 0), vec3(0, -1, 0), vec3(0, 0, 1), vec3(0, 0, -1), vec3(0, -1, 0),
                                vec3(0, -1, 0));
    f = dirs[face];
    s = cross(f, ups[face]);
    t = cross(s, f);
}

vec2 csm_cube_project(int face, vec3 d)
{
    vec3 s, t, f;
    csm_cube_basis(face, s, t, f);
    float z = dot(f, d);
    return vec2(dot(s, d) / z, dot(t, d) / z);
}

// One depth test of local point x against cube map (a, b) of pair p: mode 0
// the nearest texel; 1 the 4 texels around x bilinearly weighted (clamped
// to the face); 2 one of those 4 chosen by rr; 3 (occluders=dilated, not
// the paper's) lit only where all 4 are, so that an occluder narrower than
// a texel, which the texel centres can miss, still shadows.
float csm_cube_test(CsmPair p, CsmLight l, uint a, uint b, vec3 x, int mode, float rr)
{
    uint n_u = l.info.x, n_v = l.info.y, M = p.info.x;
    vec3 lp = csm_light_point(p.o.xyz, p.e1.xyz, p.e2.xyz, n_u, n_v, a, b);
    vec3 d = x - lp;
    float depth = length(d);
    if (!(depth > 0.0))
        return 1.0;
    int face = gi_cube_face(d);
    vec2 sc = csm_cube_project(face, d);
    uint i = uint(face) * n_u * n_v + csm_light_cells[l.info.z + b * n_u + a];
    float z_bias = uintBitsToFloat(p.info.w);
    int last = int(M) - 1;
    if (mode == 0) {
        ivec2 tex = clamp(ivec2((sc * 0.5 + 0.5) * float(M)), ivec2(0), ivec2(last));
        return depth <= csm_lookup_at(p.info.y, p.info.z, M, tex, i) + z_bias ? 1.0 : 0.0;
    }
    vec2 tc = (sc * 0.5 + 0.5) * float(M) - 0.5;
    vec2 t0 = floor(tc), ft = tc - t0;
    ivec2 i0 = ivec2(t0);
    if (mode == 2) {
        float r = rr;
        int ix = csm_rr_choose(r, ft.x);
        int iy = csm_rr_choose(r, ft.y);
        ivec2 tex = clamp(i0 + ivec2(ix, iy), ivec2(0), ivec2(last));
        return depth <= csm_lookup_at(p.info.y, p.info.z, M, tex, i) + z_bias ? 1.0 : 0.0;
    }
    if (mode == 3) {
        for (int j = 0; j < 4; j++) {
            ivec2 tex = clamp(i0 + ivec2(j & 1, j >> 1), ivec2(0), ivec2(last));
            if (!(depth <= csm_lookup_at(p.info.y, p.info.z, M, tex, i) + z_bias))
                return 0.0;
        }
        return 1.0;
    }
    float v = 0.0;
    for (int j = 0; j < 4; j++) {
        ivec2 o = ivec2(j & 1, j >> 1);
        float w = (o.x == 1 ? ft.x : 1.0 - ft.x) * (o.y == 1 ? ft.y : 1.0 - ft.y);
        if (w <= 0.0)
            continue;
        ivec2 tex = clamp(i0 + o, ivec2(0), ivec2(last));
        v += w * (depth <= csm_lookup_at(p.info.y, p.info.z, M, tex, i) + z_bias ? 1.0 : 0.0);
    }
    return v;
}

// Visibility between world point x (shading normal n or vec3(0)) and world
// point y on light j through object k's cube-map CSM (§4.2), with filter
// `mode` (0 nearest grid point and texel; 1 generalised PCF over the 2^d
// nearest grid points x 4 texels; 2 Russian roulette over those, driven by
// u_rr in [0, 1); 3 the nearest grid point, lit where all 4 texels are).
float csm_local_visibility_object(uint j, uint k, vec3 x, vec3 n, vec3 y, int mode, float u_rr)
{
    CsmPair p = csm_pairs[j * csm_object_count + k];
    if (p.o.w == 0.0 || p.info.x == 0u)
        return 1.0;
    CsmLight l = csm_lights[j];
    CsmObject ob = csm_objects[k];
    vec3 xl = (ob.local_from_world * vec4(x, 1.0)).xyz;
    vec2 g = csm_light_grid(l.o.xyz, l.e1.xyz, l.e2.xyz, l.info.x, l.info.y, y);
    int nu = int(l.info.x), nv = int(l.info.y);
    if (dot(n, n) > 0.0) {
        // normal offset of csm_normal_offset_local texels at x's distance
        vec3 lc = csm_light_point(p.o.xyz, p.e1.xyz, p.e2.xyz, l.info.x, l.info.y,
                                  uint(clamp(int(floor(g.x + 0.5)), 0, nu - 1)),
                                  uint(clamp(int(floor(g.y + 0.5)), 0, nv - 1)));
        vec3 nl = normalize(n * mat3(ob.world_from_local));
        xl += nl * (csm_normal_offset_local * 2.0 * length(xl - lc) / float(p.info.x));
    }
    if (mode == 0 || mode == 3) {
        uint a = uint(clamp(int(floor(g.x + 0.5)), 0, nu - 1)), b = uint(clamp(int(floor(g.y + 0.5)), 0, nv - 1));
        return csm_cube_test(p, l, a, b, xl, mode, 0.0);
    }
    vec2 g0 = floor(g), fg = g - g0;
    uint as[2] = uint[2](uint(clamp(int(g0.x), 0, nu - 1)), uint(clamp(int(g0.x) + 1, 0, nu - 1)));
    uint bs[2] = uint[2](uint(clamp(int(g0.y), 0, nv - 1)), uint(clamp(int(g0.y) + 1, 0, nv - 1)));
    if (mode == 2) {
        float r = u_rr;
        int ia = csm_rr_choose(r, fg.x);
        int ib = csm_rr_choose(r, fg.y);
        return csm_cube_test(p, l, as[ia], bs[ib], xl, 2, r);
    }
    float v = 0.0;
    for (int ja = 0; ja < 2; ja++)
        for (int jb = 0; jb < 2; jb++) {
            float wm = (ja == 1 ? fg.x : 1.0 - fg.x) * (jb == 1 ? fg.y : 1.0 - fg.y);
            if (wm > 0.0)
                v += wm * csm_cube_test(p, l, as[ja], bs[jb], xl, 1, 0.0);
        }
    return v;
}

// Visibility through one object for light j: its cube maps (local), or
// with csm_semilocal its orthographic maps along y - x (§4.3). `other`:
// k is not the receiver's own object; with csm_dilate_local its cube maps
// then take mode 3 (a receiver's own surface is left to the paper's test:
// its neighbouring texels hold the receiver's own surface at other depths,
// and the 4-texel minimum would shadow it at grazing angles). Only point
// and spot lights (kind 2) are dilated: their shadows are hard, so one
// missed texel gives a pixel the light's full contribution, while an area
// light averages its points and the grown shadows cost more than they save.
float csm_light_visibility_object(uint j, uint k, vec3 x, vec3 n, vec3 y, float u_rr, bool other)
{
    if (csm_semilocal != 0) {
        if (csm_pairs[j * csm_object_count + k].o.w == 0.0)
            return 1.0;
        return csm_visibility_object(k, x, n, normalize(y - x), csm_filter, u_rr);
    }
    bool dilate = other && csm_dilate_local != 0 && csm_lights[j].o.w == 2.0;
    return csm_local_visibility_object(j, k, x, n, y, dilate ? 3 : csm_filter, u_rr);
}

// Visibility of light point y from x on object `own` (0xFFFFFFFF: none):
// the receiver's own CSM first, then the other objects' (§4.6), product.
float csm_light_visibility(uint j, vec3 x, vec3 n, vec3 y, uint own, inout uint rng)
{
    float v = 1.0;
    if (own < csm_object_count)
        v = csm_light_visibility_object(j, own, x, n, y, csm_filter == 2 ? gi_rng_next_float(rng) : 0.0, false);
    for (uint k = 0u; k < csm_object_count && v > 0.0; k++)
        if (k != own)
            v *= csm_light_visibility_object(j, k, x, n, y, csm_filter == 2 ? gi_rng_next_float(rng) : 0.0, true);
    return v;
}

#endif
