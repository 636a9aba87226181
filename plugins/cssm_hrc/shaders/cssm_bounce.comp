// The per-texel gathers of cssm_hrc (Ritschel et al. 2008) as a compute
// pass, one invocation per atlas texel, the receiver lifted along its
// normal (cssm_receiver_point), itself skipped as a sender, the stack-less
// traversal of Fig. 10 (cssm_traverse.glsl, the final gather's code),
// with CSSM_JITTER the senders jittered (§4.5); the radiance written per
// texel, read back by gpu_gather.c where the C loop keeps it:
//   CSSM_GLOSSY 0: one HRC bounce (§4.1.1, Fig. 8: "a gather step ... for
//     every texel of the illumination atlas", bounces_on=gpu), diffuse with
//     the texel's albedo over the pulled radiance of the previous bounce;
//     twin of hrc.c's gather_atlas (jittered per frame with
//     bounces_every=frame);
//   CSSM_GLOSSY 1: texel mode's final gather (Fig. 17 right, gather=gpu
//     with mode=texels): the glossy gather of the reflected light toward
//     the eye; twin of final_gather.c's cssm_texel_gather.
// Defines (gpu_gather.c program_for): CSSM_PCF, CSSM_JITTER,
// CSSM_REP_CENTROID, CSSM_GLOSSY.
#include "common.glsl"
#include "cssm_traverse.glsl"

layout(local_size_x = 64) in;

layout(std430, binding = CSSM_SSBO_STATS) buffer CssmStats { uint cssm_stats[]; };
// per texel 2 texels, float bits: albedo (w 0), Phong ks and exponent
layout(binding = CSSM_IMG_ALBEDO, rgba32ui) readonly restrict uniform uimageBuffer cssm_albedo;
layout(std430, binding = CSSM_SSBO_OUT) writeonly buffer CssmOut { float cssm_out[]; };

uniform uint u_count;   // atlas texels
uniform float u_lim;    // cssm_refine_limit(threshold)
uniform float u_scale;  // 2^exposure (exposure 0 for the bounces)
uniform uint u_max_cut; // maximum cut size (§4.4)
uniform float u_clamp;  // clamp distance, world units
uniform float u_bias;   // CSSM depth bias, world units
uniform float u_lift;   // receivers lifted 2 near planes along the normal
uniform uint u_frame;   // CSSM_JITTER: texel t's generator gi_rng_init(t, u_frame, u_stream)
uniform uint u_stream;  // the seed of the gather's streams, as the C loop's
uniform vec3 u_eye;     // CSSM_GLOSSY: the eye the texels reflect toward

// Invocation k gathers the texel of leaf rank k (the median cut's order,
// not the atlas'): llvmpipe runs eight invocations as one vector, and
// neighbours in the tree have alike cuts (a vector runs as long as its
// longest traversal, issue 29).

void main()
{
    uint k = gl_GlobalInvocationID.x;
    if (k >= u_count)
        return;
    uint t = cssm_leaf(k);
    CssmReceiver rc;
    rc.n = cssm_texel_n(t).xyz;
    rc.x = cssm_texel_p_area(t).xyz + rc.n * u_lift;
    rc.self = int(t);
    rc.kd = uintBitsToFloat(imageLoad(cssm_albedo, int(2u * t)).rgb);
    rc.lum_kd = gi_luminance(rc.kd);
#if CSSM_GLOSSY
    vec4 ph = uintBitsToFloat(imageLoad(cssm_albedo, int(2u * t + 1u)));
    rc.ks = ph.rgb;
    rc.exponent = min(ph.a, 1000.0);
    rc.wo = normalize(u_eye - cssm_texel_p_area(t).xyz);
#else
    rc.ks = vec3(0.0);
    rc.exponent = 0.0;
    rc.wo = vec3(0.0);
#endif
    rc.lum_ks = gi_luminance(rc.ks);
    CssmOpts o;
    o.lim = u_lim;
    o.scale = u_scale;
    o.max_cut = u_max_cut;
    o.clamp_d = u_clamp;
    o.bias = u_bias;
    o.pcf = CSSM_PCF != 0; // 2 x 2 PCF (the program's defines)
    o.jitter = CSSM_JITTER != 0;
    o.rep_centroid = CSSM_REP_CENTROID != 0;
    uint rng = gi_rng_init(t, u_frame, u_stream), gathered, clamped = 0u;
    vec3 L = cssm_gather(rc, o, rng, gathered, clamped);
    cssm_out[3u * t + 0u] = L.r;
    cssm_out[3u * t + 1u] = L.g;
    cssm_out[3u * t + 2u] = L.b;
    atomicAdd(cssm_stats[0], gathered);
    atomicAdd(cssm_stats[1], 1u);
    atomicAdd(cssm_stats[2], clamped);
}
