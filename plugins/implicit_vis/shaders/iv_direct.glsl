// Look-ups of the direct light through a leaf's bins (Sec. 4.3, 4.4),
// shared by the gather (iv_gather.comp) and the glossy display
// (iv_display.comp): the bin of a direction, a leaf's receiving link in a
// bin, and a punctual light seen through its bin. The includer declares
// the receiving links iv_link (IV_SSBO_LINKS) before including this file.
#ifndef IV_DIRECT_GLSL
#define IV_DIRECT_GLSL
#include "lights.glsl"

uniform uint u_n; // bins per cube side

const float IV_FLT_MAX = 3.402823466e38;

// Bin of direction d (iv_bin_of in bins.c).
uint iv_bin_of(vec3 d)
{
    int ax = 0;
    if (abs(d.y) > abs(d[ax]))
        ax = 1;
    if (abs(d.z) > abs(d[ax]))
        ax = 2;
    float m = abs(d[ax]);
    if (!(m > 0.0))
        return 0u;
    uint face = 2u * uint(ax) + (d[ax] < 0.0 ? 1u : 0u);
    float u = d[(ax + 1) % 3] / m, v = d[(ax + 2) % 3] / m;
    int col = int(floor((u + 1.0) * 0.5 * float(u_n))), row = int(floor((v + 1.0) * 0.5 * float(u_n)));
    col = clamp(col, 0, int(u_n) - 1);
    row = clamp(row, 0, int(u_n) - 1);
    return face * u_n * u_n + uint(row) * u_n + uint(col);
}

// The receiving link in bin b among links lo .. hi - 1 (one leaf's, sorted by bin), or -1.
int find_bin(uint lo, uint hi, uint b)
{
    while (lo < hi) {
        uint mid = (lo + hi) >> 1;
        uint mb = iv_link[mid].x;
        if (mb == b)
            return int(mid);
        if (mb < b)
            lo = mid + 1u;
        else
            hi = mid;
    }
    return -1;
}

// A punctual light (the scene's GiLight fields) seen from p: its direction
// wl and the factor `scale` of its intensity reaching p (distance, range,
// spot cone); false where it is at p or the bin toward it holds a nearer
// link of the leaf (links lo .. hi - 1), the implicit shadow test.
bool iv_punctual_seen(vec3 position, uint type, vec3 direction, float range, float cos_inner, float cos_outer,
                      vec3 p, uint lo, uint hi, out vec3 wl, out float scale)
{
    float r = IV_FLT_MAX;
    if (type == GI_LIGHT_TYPE_DIRECTIONAL) {
        wl = normalize(-direction);
        scale = 1.0;
    } else {
        vec3 d = position - p;
        r = length(d);
        wl = vec3(0.0);
        scale = 0.0;
        if (!(r > 0.0))
            return false;
        wl = d * (1.0 / r);
        scale = gi_range_window(r, range) / (r * r);
        if (type == GI_LIGHT_TYPE_SPOT)
            scale *= gi_spot_falloff(-dot(wl, normalize(direction)), cos_inner, cos_outer);
    }
    int k = find_bin(lo, hi, iv_bin_of(wl));
    return !(k >= 0 && uintBitsToFloat(iv_link[k].w) < r);
}
#endif
