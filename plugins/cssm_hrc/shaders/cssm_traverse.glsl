// The final gather of §4.4 on the GPU: the stack-less traversal of Fig. 10
// (§4.2: child and skip pointers, so that a shader needs no stack) with
// the oracle's Phong bound and a maximum cut size (§4.3), each gathered
// node sent from lightcuts' representative, jittered inside its texel
// (§4.5), distances clamped (§5 "Quality"), CSSM visibility
// (cssm_lookup.glsl). GLSL twin of hrc.c (cos_bound, bound_view,
// pick_leaf, transfer, gather_any), same names and operation order.
#ifndef CSSM_TRAVERSE_GLSL
#define CSSM_TRAVERSE_GLSL
#include "common.glsl"
#include "rng.glsl"
#include "sampling.glsl"
#include "cssm_lookup.glsl"

#if !defined(CSSM_PCF) || !defined(CSSM_JITTER) || !defined(CSSM_REP_CENTROID) || !defined(CSSM_GLOSSY)
#error "cssm_traverse.glsl: CSSM_PCF, CSSM_JITTER, CSSM_REP_CENTROID and CSSM_GLOSSY must be defined"
#endif
#define CSSM_FLT_MAX 3.402823466e38
#define CSSM_FLT_MIN 1.175494351e-38

// A node as cssm_node_fetch (hrc.c) gives it (float, or packed and
// decoded; gpu_gather.c's gpu_node): seven texels of a buffer texture, not
// an SSBO (issue 29: cssm_bindings.h says why), read field by field.
#define CSSM_C_R 0    // bounding sphere centre, radius
#define CSSM_P_AREA 1 // gather position, area
#define CSSM_N_CONE 2 // mean normal, cosine of the normal cone (-1: everything)
#define CSSM_I 3      // radiant intensity (rgb), w its luminance (C's gi_luminance)
#define CSSM_LINK 4   // child (-1: leaf), skip (-1: end), first leaf, leaf count
#define CSSM_REP 5    // x: representative texel
// the representative's walk (pick_leaf): left child (-1: leaf), right
// child, the probability of going left as pick_leaf computes it in C
// (float bits), first leaf
#define CSSM_WALK 6
layout(binding = CSSM_IMG_NODES, rgba32ui) readonly restrict uniform uimageBuffer cssm_nodes;
layout(binding = CSSM_IMG_LEAVES, r32ui) readonly restrict uniform uimageBuffer cssm_leaves;

vec4 cssm_node_f(int i, int k)
{
    return uintBitsToFloat(imageLoad(cssm_nodes, 7 * i + k));
}
ivec4 cssm_node_i(int i, int k)
{
    return ivec4(imageLoad(cssm_nodes, 7 * i + k));
}
uint cssm_leaf(uint k)
{
    return imageLoad(cssm_leaves, int(k)).x;
}

// cssm_receiver (cssm.h): a pixel (glossy, self -1) or an atlas texel of
// an HRC bounce (diffuse: ks 0, self its index, skipped as a sender).
struct CssmReceiver {
    vec3 x, n;
    int self;
    vec3 kd, ks;
    float lum_kd, lum_ks; // their luminance
    float exponent;
    vec3 wo;
};

// cssm_gather_opts (cssm.h); the refinement limit and 2^exposure as
// gather_any computes them once per receiver. pcf, jitter and rep_centroid
// come from the program's defines (CSSM_PCF, CSSM_JITTER,
// CSSM_REP_CENTROID; gpu_gather.c builds one program per set), and
// CSSM_GLOSSY 0 leaves out the Phong lobe where no receiver has one: on
// llvmpipe a branch no lane takes still costs its whole body (issue 29).
struct CssmOpts {
    float lim, scale;
    uint max_cut;
    float clamp_d, bias;
    bool pcf, jitter, rep_centroid;
};

// powf as C computes it where GLSL's pow is undefined (x = 0).
float cssm_pow(float x, float e)
{
    return x > 0.0 ? pow(x, e) : (e == 0.0 ? 1.0 : 0.0);
}

float cssm_cos_bound(vec3 u, vec3 w, float sin_h)
{
    float c = dot(u, w);
    if (sin_h >= 1.0)
        return 1.0;
    float cos_h = sqrt(1.0 - sin_h * sin_h);
    float s = sqrt(max(0.0, 1.0 - c * c));
    if (c >= cos_h)
        return 1.0;
    return max(0.0, c * cos_h + s * sin_h);
}

// bound_view: the oracle's upper bound (luminance) of what node i sends.
float cssm_bound(int i, CssmReceiver rc)
{
    vec4 c_r = cssm_node_f(i, CSSM_C_R);
    vec3 w = c_r.xyz - rc.x;
    float d = length(w);
    if (!(d > c_r.w))
        return CSSM_FLT_MAX; // the receiver lies inside the sphere: no bound
    w = w * (1.0 / d);
    float sin_h = c_r.w / d, dmin = d - c_r.w;
    float cr = cssm_cos_bound(rc.n, w, sin_h);
    float cs = 1.0;
    vec4 n_cone = cssm_node_f(i, CSSM_N_CONE);
    if (n_cone.w > -1.0) { // sender: the normals within the cone, widened by the sphere
        float cc = max(-1.0, min(1.0, n_cone.w));
        float sin_c = sqrt(max(0.0, 1.0 - cc * cc));
        float sh = sin_h, chh = sqrt(max(0.0, 1.0 - sh * sh));
        float cw = cc * chh - sin_c * sh, sw = sin_c * chh + cc * sh;
        float c = -dot(n_cone.xyz, w), s = sqrt(max(0.0, 1.0 - c * c));
        cs = c >= cw ? 1.0 : max(0.0, c * cw + s * sw);
    }
    float f = rc.lum_kd / GI_PI;
    if (CSSM_GLOSSY != 0 && rc.lum_ks > 0.0) {
        vec3 r = rc.n * (2.0 * dot(rc.n, rc.wo)) - rc.wo;
        float cl = cssm_cos_bound(r, w, sin_h);
        f += rc.lum_ks * (rc.exponent + 2.0) / (2.0 * GI_PI) * cssm_pow(cl, rc.exponent);
    }
    return f * cssm_node_f(i, CSSM_I).w * cr * cs / (dmin * dmin);
}

// pick_leaf: lightcuts' representative of node `index`, a walk down by
// intensity (the frame's numbers with jitter, else a fixed hash per node).
uint cssm_pick_leaf(int index, bool jitter, inout uint rng)
{
    uint fixed_rng = gi_rng_init(uint(index), 0u, 0x2e9u);
    ivec4 w = cssm_node_i(index, CSSM_WALK);
    while (w.x >= 0) {
        float u = jitter ? gi_rng_next_float(rng) : gi_rng_next_float(fixed_rng);
        w = cssm_node_i(u < intBitsToFloat(w.z) ? w.x : w.y, CSSM_WALK);
    }
    return uint(w.w);
}

// transfer: what node `index` sends to the receiver, f I G V.
vec3 cssm_transfer(int index, CssmReceiver rc, CssmOpts o, inout uint rng, inout uint clamped)
{
    vec3 y = cssm_node_f(index, CSSM_P_AREA).xyz, ny = cssm_node_f(index, CSSM_N_CONE).xyz;
    uint vis_texel = uint(cssm_node_i(index, CSSM_REP).x);
    if (!o.rep_centroid) {
        vis_texel = cssm_leaf(cssm_pick_leaf(index, o.jitter, rng));
        y = cssm_texel_p_area(vis_texel).xyz;
        ny = cssm_texel_n(vis_texel).xyz;
    } else if (o.jitter) { // a uniform leaf below the node
        uint first = uint(cssm_node_i(index, CSSM_LINK).z), count = uint(cssm_node_i(index, CSSM_LINK).w);
        uint k = first + uint(gi_rng_next_float(rng) * float(count));
        if (k >= first + count)
            k = first + count - 1u;
        vis_texel = cssm_leaf(k);
        if (count == 1u)
            ny = cssm_texel_n(vis_texel).xyz;
    }
    if (o.jitter) { // §4.5: a random point of the texel
        vec4 pa = cssm_texel_p_area(vis_texel);
        vec3 tu, tv;
        gi_onb(cssm_texel_n(vis_texel).xyz, tu, tv);
        float side = sqrt(pa.w);
        float u1 = gi_rng_next_float(rng) - 0.5;
        float u2 = gi_rng_next_float(rng) - 0.5;
        y = pa.xyz + (tu * (u1 * side) + tv * (u2 * side));
    }
    vec3 w = y - rc.x;
    float d2 = dot(w, w);
    if (!(d2 > 0.0))
        return vec3(0.0);
    float d = sqrt(d2);
    w = w * (1.0 / d);
    float cr = dot(rc.n, w), cs = -dot(ny, w);
    if (cr <= 0.0 || cs <= 0.0)
        return vec3(0.0);
    float c2 = o.clamp_d * o.clamp_d;
    if (d2 < c2) {
        d2 = c2;
        clamped++;
    }
    float v = cssm_visible(vis_texel, rc.x, o.bias, o.pcf);
    if (v <= 0.0)
        return vec3(0.0);
    float g = cr * cs / d2 * v;
    vec3 f = rc.kd / GI_PI;
    if (CSSM_GLOSSY != 0 && rc.lum_ks > 0.0) {
        vec3 r = rc.n * (2.0 * dot(rc.n, rc.wo)) - rc.wo;
        float cl = dot(r, w);
        float lobe = cl > 0.0 ? (rc.exponent + 2.0) / (2.0 * GI_PI) * pow(cl, rc.exponent) : 0.0;
        f += rc.ks * lobe;
    }
    return f * cssm_node_f(index, CSSM_I).rgb * g;
}

// cssm_next: the walk of gather_any (Fig. 10) from node i up to the next
// lit node to gather, returned (-1: the traversal ended): refine by the
// child pointer; leave by the skip pointer the receiver itself and the
// unlit nodes (gathered, nothing sent). `pending` counts the subtrees
// still to be visited, so that gathered + pending is the size the cut
// reaches at least.
int cssm_next(int i, CssmReceiver rc, CssmOpts o, inout uint pending, inout uint gathered)
{
    while (i >= 0) {
        ivec4 link = cssm_node_i(i, CSSM_LINK);
        if (link.x < 0 && rc.self >= 0 && cssm_leaf(uint(link.z)) == uint(rc.self)) {
            pending--;
            i = link.y; // no transfer to itself
            continue;
        }
        bool lit = any(greaterThan(cssm_node_f(i, CSSM_I).rgb, vec3(0.0)));
        if (!lit) {
            gathered++;
            pending--;
            i = link.y;
            continue;
        }
        bool refine = false;
        if (link.x >= 0 && gathered + pending + 1u <= o.max_cut) {
            float b = cssm_bound(i, rc);
            refine = b >= CSSM_FLT_MAX || b * o.scale > o.lim;
        }
        if (!refine)
            return i;
        pending++;
        i = link.x;
    }
    return -1;
}

// gather_any (Fig. 10): every node of the cut gathered in the C order.
// The walk to the next gathered node is a loop of its own (cssm_next), the
// transfer outside it: on a SIMD machine (llvmpipe runs eight pixels a
// vector) the costly transfer then runs once for all lanes' next node,
// not once in every step where some lane gathers while others refine
// (issue 29; Aila and Laine's "while-while" traversal).
vec3 cssm_gather(CssmReceiver rc, CssmOpts o, inout uint rng, out uint gathered, inout uint clamped)
{
    vec3 sum = vec3(0.0);
    uint pending = 1u;
    gathered = 0u;
    int i = cssm_next(0, rc, o, pending, gathered);
    while (i >= 0) {
        sum += cssm_transfer(i, rc, o, rng, clamped);
        gathered++;
        pending--;
        i = cssm_next(cssm_node_i(i, CSSM_LINK).y, rc, o, pending, gathered);
    }
    return sum;
}
#endif
