// One HRC bounce of cssm_hrc (Ritschel et al. 2008, §4.1.1, Fig. 8: "a
// gather step ... for every texel of the illumination atlas") as a compute
// pass (bounces_on=gpu): per atlas texel the receiver lifted along its
// normal (cssm_receiver_point), diffuse with the texel's albedo, itself
// skipped as a sender, the stack-less traversal of Fig. 10 over the
// pulled radiance of the previous bounce (cssm_traverse.glsl) without
// jitter, the reflected radiance kd/pi sum written per texel. GLSL twin
// of hrc.c's gather_atlas; gpu_gather.c reads the result back where the
// C loop keeps it.
#define CSSM_JITTER 0 // no jitter in the bounces
#define CSSM_GLOSSY 0 // diffuse receivers
#include "common.glsl"
#include "cssm_traverse.glsl"

layout(local_size_x = 64) in;

layout(std430, binding = CSSM_SSBO_STATS) buffer CssmStats { uint cssm_stats[]; };
layout(binding = CSSM_IMG_ALBEDO, rgba32ui) readonly restrict uniform uimageBuffer cssm_albedo; // float bits
layout(std430, binding = CSSM_SSBO_OUT) writeonly buffer CssmOut { float cssm_out[]; };

uniform uint u_count;   // atlas texels
uniform float u_lim;    // cssm_refine_limit(threshold)
uniform float u_scale;  // 2^exposure (exposure 0 for the bounces)
uniform uint u_max_cut; // maximum cut size (§4.4)
uniform float u_clamp;  // clamp distance, world units
uniform float u_bias;   // CSSM depth bias, world units
uniform float u_lift;   // receivers lifted 2 near planes along the normal

void main()
{
    uint t = gl_GlobalInvocationID.x;
    if (t >= u_count)
        return;
    CssmReceiver rc;
    rc.n = cssm_texel_n(t).xyz;
    rc.x = cssm_texel_p_area(t).xyz + rc.n * u_lift;
    rc.self = int(t);
    rc.kd = uintBitsToFloat(imageLoad(cssm_albedo, int(t)).rgb);
    rc.ks = vec3(0.0);
    rc.lum_kd = gi_luminance(rc.kd);
    rc.lum_ks = 0.0;
    rc.exponent = 0.0;
    rc.wo = vec3(0.0);
    CssmOpts o;
    o.lim = u_lim;
    o.scale = u_scale;
    o.max_cut = u_max_cut;
    o.clamp_d = u_clamp;
    o.bias = u_bias;
    o.pcf = CSSM_PCF != 0; // 2 x 2 PCF (the program's defines)
    o.jitter = false;
    o.rep_centroid = CSSM_REP_CENTROID != 0;
    uint rng = 0u, gathered, clamped = 0u;
    vec3 L = cssm_gather(rc, o, rng, gathered, clamped);
    cssm_out[3u * t + 0u] = L.r;
    cssm_out[3u * t + 1u] = L.g;
    cssm_out[3u * t + 2u] = L.b;
    atomicAdd(cssm_stats[0], gathered);
    atomicAdd(cssm_stats[1], 1u);
    atomicAdd(cssm_stats[2], clamped);
}
