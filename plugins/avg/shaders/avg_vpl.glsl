// Virtual point lights (§III-B/C): the record the tracer writes and the
// shading pass reads (avg.h's avg_vpl), the fixed quasi-random numbers of the
// light paths, and a VPL's unshadowed contribution to a receiver.
#ifndef AVG_VPL_GLSL
#define AVG_VPL_GLSL
#include "common.glsl"
#include "rng.glsl"
#include "sequences.glsl"
#include "lights.glsl"

const uint AVG_VPL_DIFFUSE = 0u;
const uint AVG_VPL_POINT = 1u;
const uint AVG_VPL_SPOT = 2u;
// kind flag: a punctual light's VPL that covers one face of a cube about the
// light (the world axis `normal`), not a hemisphere (avg.c, punctual_parts)
const uint AVG_VPL_FACE = 0x20000u;
// kind flag: one of a punctual light's cover VPLs (avg.c, punctual_parts),
// shaded at every pixel, outside the interleaving and the filter
const uint AVG_VPL_WHOLE = 0x40000u;

struct AvgVpl {
    vec3 position; uint kind;   // kind | bounce << 8 | double-sided emitter << 16 | AVG_VPL_FACE | light entry << 24
    vec3 normal; float cos_inner; // surface normal, or the hemisphere (cube face) a light VPL covers
    vec3 power; float cos_outer;  // diffuse: flux (intensity = power cos / pi); point/spot: intensity
    vec3 spot_dir; float range;
};

// A bijection of [0, mask] chosen by the seed p: Kensler's hash
// permutation ("Correlated Multi-Jittered Sampling", 2013) on a power of
// two, so no cycle walking is needed. Unlike an XOR with a constant it is
// not linear in the bits of i. C twin: avg_permute in avg_trace_cpu.c.
uint avg_permute(uint i, uint mask, uint p)
{
    uint w = mask;
    i ^= p; i *= 0xe170893du;
    i ^= p >> 16;
    i ^= (i & w) >> 4;
    i ^= p >> 8; i *= 0x0929eb3fu;
    i ^= p >> 23;
    i ^= (i & w) >> 1; i *= 1u | (p >> 27);
    i *= 0x6935fa69u;
    i ^= (i & w) >> 11; i *= 0x74dcb303u;
    i ^= (i & w) >> 2; i *= 0x9e501cc3u;
    i ^= (i & w) >> 2; i *= 0xc860a3dfu;
    i &= w;
    i ^= i >> 5;
    return (i + p) & w;
}

// Quasi-random pair `pair` of light path i: the Sobol (0,2) point of the
// path's index permuted per pair (Kollig-Keller padding of the dimensions),
// mask = 2^k - 1 >= paths - 1. Each pair's points over all paths are the
// whole (0,2)-net when the path count is a power of two. The permutation
// must not be linear in the bits of i: with the former XOR by a constant,
// pair 2k+1's Russian-roulette number was a fixed bit flip of pair 2k-1's,
// so at albedo 1/2 every path that survived one roulette died at the next
// and the third bounce's VPLs never existed. Fixed across frames, so a
// static scene gets the same VPLs every frame (§III-B). C twin: avg_qr in
// avg_trace_cpu.c.
vec2 avg_qr(uint i, uint pair, uint mask, uint seed)
{
    // seed 1 (the default run seed) leaves the permutation of earlier versions
    uint j = avg_permute(i, mask, gi_pcg_hash(pair * 0x9E3779B9u + 0x632BE5ABu) ^ gi_pcg_hash(seed) ^ gi_pcg_hash(1u));
    return vec2(gi_radical_inverse2(j), gi_sobol2(j));
}

// What VPL v sends to a receiver at x with unit normal n, without
// visibility: the irradiance-like S such that the reflected radiance is
// (albedo / pi) S. The squared distance is clamped below by dmin2 (the
// geometry term's clamping of instant radiosity).
vec3 avg_vpl_contribution(AvgVpl v, vec3 x, vec3 n, float dmin2)
{
    vec3 d = v.position - x;
    float d2 = dot(d, d);
    if (!(d2 > 0.0))
        return vec3(0.0);
    vec3 w = d * inversesqrt(d2);
    float cos_x = dot(n, w);
    float cos_v = dot(v.normal, -w);
    if (cos_x <= 0.0)
        return vec3(0.0);
    uint kind = v.kind & 0xFFu;
    if (kind == AVG_VPL_DIFFUSE) {
        if (cos_v <= 0.0)
            return vec3(0.0);
        return v.power * (cos_v * GI_INV_PI * cos_x / max(d2, dmin2));
    }
    // A punctual light's VPL covers one hemisphere about `normal`, or with
    // the face flag the cube face whose axis `normal` is.
    if ((v.kind & AVG_VPL_FACE) != 0u ? gi_cube_face(-w) != gi_cube_face(v.normal) : cos_v <= 0.0)
        return vec3(0.0);
    float f = cos_x / max(d2, dmin2) * gi_range_window(sqrt(d2), v.range);
    if (kind == AVG_VPL_SPOT)
        f *= gi_spot_falloff(dot(-w, v.spot_dir), v.cos_inner, v.cos_outer);
    return v.power * f;
}
#endif
