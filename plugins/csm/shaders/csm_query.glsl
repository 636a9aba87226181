// Visibility queries on the Coherent Shadow Maps of all objects (§3.2, §4.5,
// §4.6). Buffers (plugins/csm/csm.c uploads them):
//   binding 8  CsmObjects  per object: local_from_world and world_from_local
//                          at the current time (§4.6: queries in local space),
//                          bounding sphere (local), info = (M, offsets base,
//                          segments base, bias in local units); M = 0: the
//                          object has no CSM (receiver-only, §4.6)
//   binding 9  offsets     all objects' offsets[M^2 + 1], concatenated
//   binding 10 z_avg       all objects' segments, concatenated
//   binding 11 i_end
//   binding 12 cell index  enumeration index of grid cell (a, b) at b N_phi + a
// Uniforms: csm_n_theta, csm_n_phi, csm_object_count, csm_normal_offset
// (texels), csm_filter (0 nearest, 1 pcf, 2 rr).
#ifndef CSM_QUERY_GLSL
#define CSM_QUERY_GLSL
#include "rng.glsl"
#include "csm_geom.glsl"

struct CsmObject {
    mat4 local_from_world;
    mat4 world_from_local;
    vec4 sphere;
    uvec4 info; // M, offsets base, segments base, floatBitsToUint(bias)
};
layout(std430, binding = 8) readonly buffer CsmObjects { CsmObject csm_objects[]; };
layout(std430, binding = 9) readonly buffer CsmOffsets { uint csm_offsets[]; };
layout(std430, binding = 10) readonly buffer CsmZAvg { float csm_z_avg[]; };
layout(std430, binding = 11) readonly buffer CsmIEnd { uint csm_i_end[]; };
layout(std430, binding = 12) readonly buffer CsmCells { uint csm_cell_index[]; };

uniform uint csm_n_theta;
uniform uint csm_n_phi;
uniform uint csm_object_count;
uniform float csm_normal_offset;
uniform int csm_filter;

// Debug buffer "segments" (plugins/csm/debug.c): segments in the texel
// lists this invocation's lookups read, and how many lookups; unused (and
// compiled away) in the image.
float csm_dbg_segments = 0.0, csm_dbg_lookups = 0.0;

// §3.2: the z_avg of the segment of texel (x, y) that holds map i, in the
// CSM whose offsets and segments start at offsets_base and segments_base.
float csm_lookup_at(uint offsets_base, uint segments_base, uint M, ivec2 tex, uint i)
{
    uint t = uint(tex.y) * M + uint(tex.x);
    uint lo = csm_offsets[offsets_base + t], hi = csm_offsets[offsets_base + t + 1u];
    // debug buffer "segments" (debug.c): the length of the lists read
    csm_dbg_segments += float(hi - lo);
    csm_dbg_lookups += 1.0;
    // first segment j in [lo, hi) with i_end[j] >= i (the last one has N - 1)
    while (lo < hi) {
        uint mid = (lo + hi) >> 1;
        if (csm_i_end[segments_base + mid] < i)
            lo = mid + 1u;
        else
            hi = mid;
    }
    return csm_z_avg[segments_base + lo];
}

float csm_lookup(CsmObject o, uint M, ivec2 tex, uint i)
{
    return csm_lookup_at(o.info.y, o.info.z, M, tex, i);
}

// One depth test: texel (x, y) of map (a, b); outside the map is lit.
// One binary choice of the Russian-roulette filter (§4.5): 1 with
// probability f (when r < f), and r rescaled to [0, 1) within the chosen
// part for the next choice.
int csm_rr_choose(inout float r, float f)
{
    int i = r < f ? 1 : 0;
    r = i == 1 ? r / f : (r - f) / (1.0 - f);
    return i;
}

float csm_test(CsmObject o, uint a, uint b, ivec2 tex, float depth)
{
    uint M = o.info.x;
    if (any(lessThan(tex, ivec2(0))) || any(greaterThanEqual(tex, ivec2(int(M)))))
        return 1.0;
    uint i = csm_cell_index[b * csm_n_phi + a];
    return depth <= csm_lookup(o, M, tex, i) + uintBitsToFloat(o.info.w) ? 1.0 : 0.0;
}

// Visibility of world point x (shading normal n, or vec3(0)) toward world
// direction w through object k's CSM with filter `mode` (0 nearest, 1 pcf,
// 2 rr); u_rr in [0, 1) drives the RR filter.
float csm_visibility_object(uint k, vec3 x, vec3 n, vec3 w, int mode, float u_rr)
{
    CsmObject o = csm_objects[k];
    if (o.info.x == 0u)
        return 1.0; // receiver-only object: no CSM
    float M = float(o.info.x);
    vec3 xl = (o.local_from_world * vec4(x, 1.0)).xyz;
    vec3 wl = normalize(mat3(o.local_from_world) * w);
    if (dot(n, n) > 0.0) {
        // normal offset of csm_normal_offset texels (local units)
        vec3 nl = normalize(n * mat3(o.world_from_local)); // transpose(mat3(world_from_local)) n
        xl += nl * (csm_normal_offset * 2.0 * o.sphere.w / M);
    }
    vec2 g = csm_grid_coords(wl, csm_n_theta, csm_n_phi);
    int nphi = int(csm_n_phi), nth = int(csm_n_theta);
    if (mode == 0) {
        uint a = uint(int(floor(g.x + 0.5)) % nphi);
        uint b = uint(clamp(int(floor(g.y + 0.5)), 0, nth - 1));
        vec2 ang = csm_cell_angles(csm_n_theta, csm_n_phi, a, b);
        vec3 p = csm_project(o.sphere, ang.x, ang.y, xl);
        if (abs(p.x) >= 1.0 || abs(p.y) >= 1.0)
            return 1.0;
        ivec2 tex = min(ivec2((p.xy * 0.5 + 0.5) * M), ivec2(int(M) - 1));
        return csm_test(o, a, b, tex, p.z);
    }
    // §4.5: the 4 nearest maps (bilinear in (phi, theta)) x 4 texels (bilinear).
    vec2 g0 = floor(g);
    vec2 fg = g - g0;
    int a0 = int(g0.x), b0 = int(g0.y);
    uint as[2] = uint[2](uint(((a0 % nphi) + nphi) % nphi), uint((((a0 + 1) % nphi) + nphi) % nphi));
    uint bs[2] = uint[2](uint(clamp(b0, 0, nth - 1)), uint(clamp(b0 + 1, 0, nth - 1)));
    if (mode == 2) {
        // Russian roulette: one of the 16 tests with probability = its weight,
        // chosen by four successive binary choices from one random number.
        float r = u_rr;
        int ia = csm_rr_choose(r, fg.x);
        int ib = csm_rr_choose(r, fg.y);
        vec2 ang = csm_cell_angles(csm_n_theta, csm_n_phi, as[ia], bs[ib]);
        vec3 p = csm_project(o.sphere, ang.x, ang.y, xl);
        vec2 tc = (p.xy * 0.5 + 0.5) * M - 0.5;
        vec2 t0 = floor(tc), ft = tc - t0;
        int ix = csm_rr_choose(r, ft.x);
        int iy = csm_rr_choose(r, ft.y);
        return csm_test(o, as[ia], bs[ib], ivec2(t0) + ivec2(ix, iy), p.z);
    }
    float v = 0.0;
    for (int ja = 0; ja < 2; ja++)
        for (int jb = 0; jb < 2; jb++) {
            float wm = (ja == 1 ? fg.x : 1.0 - fg.x) * (jb == 1 ? fg.y : 1.0 - fg.y);
            if (wm <= 0.0)
                continue;
            vec2 ang = csm_cell_angles(csm_n_theta, csm_n_phi, as[ja], bs[jb]);
            vec3 p = csm_project(o.sphere, ang.x, ang.y, xl);
            vec2 tc = (p.xy * 0.5 + 0.5) * M - 0.5;
            vec2 t0 = floor(tc), ft = tc - t0;
            ivec2 i0 = ivec2(t0);
            float s = (1.0 - ft.x) * (1.0 - ft.y) * csm_test(o, as[ja], bs[jb], i0, p.z) +
                      ft.x * (1.0 - ft.y) * csm_test(o, as[ja], bs[jb], i0 + ivec2(1, 0), p.z) +
                      (1.0 - ft.x) * ft.y * csm_test(o, as[ja], bs[jb], i0 + ivec2(0, 1), p.z) +
                      ft.x * ft.y * csm_test(o, as[ja], bs[jb], i0 + ivec2(1, 1), p.z);
            v += wm * s;
        }
    return v;
}

// Visibility through every object's CSM (product; §4.6).
float csm_visibility(vec3 x, vec3 n, vec3 w, inout uint rng)
{
    float v = 1.0;
    for (uint k = 0u; k < csm_object_count && v > 0.0; k++)
        v *= csm_visibility_object(k, x, n, w, csm_filter, csm_filter == 2 ? gi_rng_next_float(rng) : 0.0);
    return v;
}

#endif
