// Propagation of the light field on the GPU (plugins/vlf/vlf_gpu.c, paper
// §3.2-§3.4): the same transport as the CPU's sweep(), vlf_scatter() and
// the end of an iteration in propagate.c and scatter.c, one pass per
// define VLF_PASS:
//   0 sweep:   one invocation per radiance-interface ray and sign (y = 0:
//              along +w_i, 1: along -w_i), through the ray's fragments;
//              receivers record the interface's radiance per fragment
//              and let it go on, senders stop what reached their back and
//              send their unshot radiance on (the rule for sides);
//   1 gather:  per element (and per non-diffuse tile cell) of subfield i,
//              the recorded radiance of its fragments summed in the CPU's
//              order into the next irradiance map (and the incoming tile);
//   2 scatter: per cell of the target tiles of subfield i's reflections
//              (§3.4), the incoming tile read by backward mapping;
//   3 finish:  the end of an iteration (totals, next unshot radiance);
//   4 settle:  after the raster sweeps of subfield i (vlf_raster.c), what
//              the receivers brought (recv[] holds it: per element, then
//              per tile cell) added to the next irradiance map and made
//              the incoming tiles, in the storage format; recv[] cleared.
// Every map a pass writes is rounded to the storage format (vlf_quantise).
#include "glsl_shared.h"

layout(local_size_x = 64) in;

struct VlfFace { vec3 n; float send_scale; vec3 kd; int nd; vec3 origin; float pad; };
struct VlfRect { ivec4 r; uvec4 o; }; // x0, y0, w, h; offset
struct VlfGather { uint key; uint first; uint count; uint pad; };
struct VlfJob { uint src; uint dst; uint face; uint first_cell; vec4 c; };

layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 0) readonly buffer VlfFaces { VlfFace faces[]; };
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 1) readonly buffer VlfElemFace { uint elem_face[]; };
// each element's area, then its albedo (3 floats an element, from u_ne / 3)
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 2) readonly buffer VlfElemArea { float elem_area[]; };
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 3) readonly buffer VlfCellStart { uint cell_start[]; };
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 4) readonly buffer VlfFrag { uint frag[]; };
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 5) readonly buffer VlfFragSlot { uint frag_slot[]; };
#if VLF_PASS == 4
// the raster sweeps' sums: two words a value (fraction x 2^32, integer part)
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 6) buffer VlfAcc { uint acc[]; };
#else
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 6) buffer VlfRecv { float recv[]; };
#endif
// diffuse maps: E_next, E_tot, L_cur (3 floats an element each, u_ne apart)
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 7) buffer VlfEMap { float emap[]; };
// tile maps: out_cur, out_next, out_tot, in (3 floats a cell each, u_nc apart)
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 8) buffer VlfTMap { float tmap[]; };
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 9) buffer VlfStats { vec4 stats[]; };
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 10) readonly buffer VlfGathers { VlfGather gath[]; };
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 11) readonly buffer VlfPerm { uint perm[]; };
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 12) readonly buffer VlfRects { VlfRect rects[]; };
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 13) readonly buffer VlfCover { uint cover[]; };
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 14) readonly buffer VlfFrames { vec4 frames[]; }; // u, v, n per fixed direction
layout(std430, binding = GI_SSBO_PLUGIN_FIRST + 15) readonly buffer VlfJobs { VlfJob jobs[]; };

uniform uint u_count;       // invocations of the pass (per sign for the sweep)
uniform uint u_precision;   // 0: float32, 1: RGBA16F, 2: RGB9E5
uniform uint u_ne;          // 3 x elements
uniform uint u_nc;          // 3 x non-diffuse cells
uniform uint u_i;           // fixed direction
uniform uint u_l;
uniform uint u_N;           // subfield cells per side
uniform uint u_start_base;  // first cell_start entry of subfield i
uniform uint u_frag_base;   // first fragment of subfield i
uniform vec3 u_t[2];        // travel directions +w_i, -w_i
uniform vec3 u_sky[2];      // radiance the interfaces start with
uniform float u_w[2];       // cell area x solid angle / 3 (the flux counters' weight)
uniform float u_dW[2];      // solid angles of +w_i and -w_i
uniform float u_cell_area;  // of an interface cell
uniform float u_min_area;   // smallest element area used as divisor
uniform float u_inv_s2;     // 1 / S^2
uniform uint u_first;       // first gather entry / job of subfield i
uniform uint u_n_elem;      // of them the element entries (the rest are tile cells)

uint vlf_index()
{
    return gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x;
}

// IEEE half of a float, rounded to nearest even, clamped at 65504
// (float_to_half in precision.c).
uint vlf_f2h(float f)
{
    uint x = floatBitsToUint(f);
    uint sgn = (x >> 16) & 0x8000u, ax = x & 0x7fffffffu;
    if (ax > 0x7f800000u)
        return 0u;
    if (ax >= 0x477fe000u)
        return sgn | 0x7bffu;
    if (ax < 0x38800000u) {
        if (ax < 0x33000000u)
            return sgn;
        uint e = ax >> 23, m = (ax & 0x7fffffu) | 0x800000u, shift = 126u - e;
        uint h = m >> shift, rem = m & ((1u << shift) - 1u), halfway = 1u << (shift - 1u);
        if (rem > halfway || (rem == halfway && (h & 1u) != 0u))
            h++;
        return sgn | h;
    }
    uint h = (ax - 0x38000000u) >> 13, rem = ax & 0x1fffu;
    if (rem > 0x1000u || (rem == 0x1000u && (h & 1u) != 0u))
        h++;
    if (h >= 0x7c00u)
        h = 0x7bffu;
    return sgn | h;
}

float vlf_h2f(uint h)
{
    uint e = (h >> 10) & 0x1fu, m = h & 0x3ffu;
    float f = e == 0u ? ldexp(float(m), -24) : ldexp(float(m | 0x400u), int(e) - 25);
    return (h & 0x8000u) != 0u ? -f : f;
}

// RGB9E5 as GL packs it and back (pack_9e5 / unpack_9e5 in precision.c);
// the scales are powers of two, so ldexp keeps the divisions exact.
vec3 vlf_9e5(vec3 c)
{
    const float maxv = 511.0 / 512.0 * 65536.0;
    vec3 v = vec3(c.x > 0.0 ? min(c.x, maxv) : 0.0, c.y > 0.0 ? min(c.y, maxv) : 0.0, c.z > 0.0 ? min(c.z, maxv) : 0.0);
    float mx = max(v.x, max(v.y, v.z));
    int e2 = -16;
    if (mx > 0.0) {
        int ex;
        frexp(mx, ex);
        e2 = max(ex - 1, -16);
    }
    int es = e2 + 1 + 15;
    if (int(floor(ldexp(mx, 24 - es) + 0.5)) == 512)
        es++;
    vec3 m = min(floor(vec3(ldexp(v.x, 24 - es), ldexp(v.y, 24 - es), ldexp(v.z, 24 - es)) + 0.5), vec3(511.0));
    return m * ldexp(1.0, es - 24);
}

// What the storage format keeps of a value (vlf_quantise).
vec3 vlf_q(vec3 c)
{
    if (u_precision == 1u)
        return vec3(vlf_h2f(vlf_f2h(c.x)), vlf_h2f(vlf_f2h(c.y)), vlf_h2f(vlf_f2h(c.z)));
    if (u_precision == 2u)
        return vlf_9e5(c);
    return c;
}

vec3 e_get(uint map, uint e) { uint b = map * u_ne + 3u * e; return vec3(emap[b], emap[b + 1u], emap[b + 2u]); }
void e_set(uint map, uint e, vec3 v) { uint b = map * u_ne + 3u * e; emap[b] = v.x; emap[b + 1u] = v.y; emap[b + 2u] = v.z; }
vec3 t_get(uint map, uint c) { uint b = map * u_nc + 3u * c; return vec3(tmap[b], tmap[b + 1u], tmap[b + 2u]); }
void t_set(uint map, uint c, vec3 v) { uint b = map * u_nc + 3u * c; tmap[b] = v.x; tmap[b + 1u] = v.y; tmap[b + 2u] = v.z; }

const uint E_NEXT = 0u, E_TOT = 1u, L_CUR = 2u;
const uint OUT_CUR = 0u, OUT_NEXT = 1u, OUT_TOT = 2u, IN = 3u;

#if VLF_PASS == 0
void main()
{
    uint ray = vlf_index();
    uint s = gl_GlobalInvocationID.z;
    if (ray >= u_count)
        return;
    uint a = cell_start[u_start_base + ray], e = cell_start[u_start_base + ray + 1u];
    vec3 t = u_t[s];
    vec3 L = u_sky[s];
    float shot = 0.0, rcv = 0.0, back = 0.0;
    for (uint j = 0u; j < e - a; j++) {
        uint k = s == 0u ? a + j : e - 1u - j; // local fragment index
        uint el = frag[u_frag_base + k];
        VlfFace fc = faces[elem_face[el]];
        float cs = dot(fc.n, t);
        float lum = L.x + L.y + L.z;
        if (cs < 0.0) {
            recv[3u * k] = L.x, recv[3u * k + 1u] = L.y, recv[3u * k + 2u] = L.z;
            rcv += lum; // and it goes on (propagate.c: the rule for sides)
        } else if (cs > 0.0) {
            // sender: what arrived on its back stops (a ray from downstream
            // meets its front); it sends its unshot radiance on
            back += lum;
            L = vec3(0.0);
            vec3 own = e_get(L_CUR, el) * fc.send_scale;
            uint slot = frag_slot[u_frag_base + k];
            if (slot != 0xffffffffu)
                own += t_get(OUT_CUR, slot);
            L += own;
            shot += own.x + own.y + own.z;
        } else if (s == 0u) {
            recv[3u * k] = 0.0, recv[3u * k + 1u] = 0.0, recv[3u * k + 2u] = 0.0;
        }
    }
    stats[s * u_count + ray] += vec4(shot, rcv, back, L.x + L.y + L.z) * u_w[s];
}
#elif VLF_PASS == 1
void main()
{
    uint idx = vlf_index();
    if (idx >= u_count)
        return;
    VlfGather g = gath[u_first + idx];
    if (idx < u_n_elem) {
        // an element: sum in the order the CPU's sweep visits its fragments
        VlfFace fc = faces[elem_face[g.key]];
        float dW = dot(fc.n, u_t[0]) < 0.0 ? u_dW[0] : u_dW[1];
        float sc = u_cell_area * dW / max(elem_area[g.key], u_min_area);
        vec3 E = e_get(E_NEXT, g.key);
        for (uint j = 0u; j < g.count; j++) {
            uint k = perm[g.first + j];
            E += vec3(recv[3u * k], recv[3u * k + 1u], recv[3u * k + 2u]) * sc;
        }
        e_set(E_NEXT, g.key, vlf_q(E));
    } else {
        // a covered cell of a non-diffuse tile: its S^2 interface rays
        vec3 L = vec3(0.0);
        for (uint j = 0u; j < g.count; j++) {
            uint k = perm[g.first + j];
            L += vec3(recv[3u * k], recv[3u * k + 1u], recv[3u * k + 2u]) * u_inv_s2;
        }
        t_set(IN, g.key, vlf_q(L));
    }
}
#elif VLF_PASS == 2
bool covered(uint slot) { return ((cover[slot >> 2] >> (8u * (slot & 3u))) & 0xffu) != 0u; }

// Bilinear read of the incoming tile rect r at cell position (x, y) over
// its covered cells (read_in in scatter.c).
bool read_in(VlfRect r, float x, float y, out vec3 o)
{
    float fx = x - 0.5 - float(r.r.x), fy = y - 0.5 - float(r.r.y);
    int ix = int(floor(fx)), iy = int(floor(fy));
    float ax = fx - float(ix), ay = fy - float(iy);
    float wsum = 0.0;
    o = vec3(0.0);
    for (int dy = 0; dy < 2; dy++)
        for (int dx = 0; dx < 2; dx++) {
            int X = ix + dx, Y = iy + dy;
            if (X < 0 || Y < 0 || X >= r.r.z || Y >= r.r.w)
                continue;
            uint slot = r.o.x + uint(Y) * uint(r.r.z) + uint(X);
            if (!covered(slot))
                continue;
            float wt = (dx != 0 ? ax : 1.0 - ax) * (dy != 0 ? ay : 1.0 - ay) + 1e-6;
            o += wt * t_get(IN, slot);
            wsum += wt;
        }
    if (wsum <= 0.0)
        return false;
    o /= wsum;
    return true;
}

void main()
{
    uint idx = vlf_index();
    if (idx >= u_count)
        return;
    // the job holding cell idx: the last whose first cell is <= idx
    uint lo = 0u, hi = u_n_elem; // u_n_elem: jobs of subfield i
    while (hi - lo > 1u) {
        uint mid = (lo + hi) >> 1;
        if (jobs[u_first + mid].first_cell <= idx)
            lo = mid;
        else
            hi = mid;
    }
    VlfJob jb = jobs[u_first + lo];
    VlfRect rj = rects[jb.dst];
    uint local = idx - jb.first_cell;
    uint slot = rj.o.x + local;
    if (!covered(slot))
        return;
    uint pj = jb.dst % u_l;
    VlfFace fc = faces[jb.face];
    vec3 Pu = frames[3u * pj].xyz, Pv = frames[3u * pj + 1u].xyz, Pn = frames[3u * pj + 2u].xyz;
    float dn = dot(Pn, fc.n);
    uint xx = local % uint(rj.r.z), yy = local / uint(rj.r.z);
    float N = float(u_N);
    float U = (float(rj.r.x + int(xx)) + 0.5) / N * 2.0 - 1.0;
    float V = (float(rj.r.y + int(yy)) + 0.5) / N * 2.0 - 1.0;
    vec3 o = Pu * U + Pv * V;
    float tt = dot(fc.n, fc.origin - o) / dn;
    vec3 q = o + Pn * tt;
    vec3 iu = frames[3u * u_i].xyz, iv = frames[3u * u_i + 1u].xyz;
    float x = (dot(q, iu) + 1.0) * 0.5 * N, y = (dot(q, iv) + 1.0) * 0.5 * N;
    vec3 Lin;
    if (!read_in(rects[jb.src], x, y, Lin))
        return;
    t_set(OUT_NEXT, slot, vlf_q(t_get(OUT_NEXT, slot) + jb.c.xyz * Lin));
}
#elif VLF_PASS == 4
// Fixed-point value k of acc as a float, and cleared.
vec3 take(uint k)
{
    vec3 v;
    for (uint q = 0u; q < 3u; q++) {
        uint w = 2u * (k + q);
        v[q] = float(double(acc[w + 1u]) + double(acc[w]) * (1.0LF / 4294967296.0LF));
        acc[w] = 0u, acc[w + 1u] = 0u;
    }
    return v;
}

void main()
{
    uint idx = vlf_index();
    if (idx >= u_count)
        return;
    if (3u * idx < u_ne)
        e_set(E_NEXT, idx, vlf_q(e_get(E_NEXT, idx) + take(3u * idx)));
    if (3u * idx < u_nc)
        t_set(IN, idx, vlf_q(take(u_ne + 3u * idx)));
}
#else
void main()
{
    uint idx = vlf_index();
    if (idx >= u_count)
        return;
    if (3u * idx < u_ne) {
        uint kb = u_ne / 3u + 3u * idx;
        vec3 kd = vec3(elem_area[kb], elem_area[kb + 1u], elem_area[kb + 2u]);
        vec3 En = e_get(E_NEXT, idx);
        e_set(E_TOT, idx, vlf_q(e_get(E_TOT, idx) + En));
        e_set(L_CUR, idx, vlf_q(kd * 0.318309886 * En));
        e_set(E_NEXT, idx, vec3(0.0));
    }
    if (3u * idx < u_nc) {
        vec3 On = t_get(OUT_NEXT, idx);
        t_set(OUT_TOT, idx, vlf_q(t_get(OUT_TOT, idx) + On));
        t_set(OUT_CUR, idx, On);
        t_set(OUT_NEXT, idx, vec3(0.0));
    }
}
#endif
