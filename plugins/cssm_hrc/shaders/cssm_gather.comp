// The per-pixel final gather of cssm_hrc (Ritschel et al. 2008, §4.4,
// §4.5) as a compute pass, every frame (gather=gpu): per pixel the
// G-buffer's surface as a glossy receiver lifted along its normal, the
// stack-less traversal of the hierarchy (cssm_traverse.glsl) with the
// frame's jitter, plus the emission seen directly, averaged over frames
// (accumulate.glsl). GLSL twin of final_gather.c's shade_surface for the
// configurations gpu_gather.c admits (no punctual lights, environment,
// direct=csm, texel mode, indirect=mc or moving objects).
#include "common.glsl"
#include "gbuffer_read.glsl"
#include "accumulate.glsl"
#include "cssm_traverse.glsl"


#define CSSM_VEC_W 4u
layout(local_size_x = 64) in;

// The pixel of this invocation in its 8 x 8 tile: llvmpipe runs eight
// consecutive invocations as one vector, so eight consecutive ones cover
// a CSSM_VEC_W x (8 / CSSM_VEC_W) block of neighbours, whose cuts are
// alike (issue 29: a vector runs as long as its longest traversal).
ivec2 cssm_pixel()
{
    uint l = gl_LocalInvocationIndex, lane = l & 7u, block = l >> 3u;
    const uint vh = 8u / CSSM_VEC_W, bx = 8u / CSSM_VEC_W; // vector rows, vectors a row
    uvec2 in_tile = uvec2((block % bx) * CSSM_VEC_W + lane % CSSM_VEC_W,
                          (block / bx) * vh + lane / CSSM_VEC_W);
    return ivec2(gl_WorkGroupID.xy * 8u + in_tile);
}

layout(std430, binding = CSSM_SSBO_STATS) buffer CssmStats { uint cssm_stats[]; };

uniform float u_lim;      // cssm_refine_limit(threshold)
uniform float u_scale;    // 2^exposure
uniform uint u_max_cut;   // maximum cut size (§4.4)
uniform float u_clamp;    // clamp distance, world units
uniform float u_bias;     // CSSM depth bias, world units
uniform float u_lift;     // receivers lifted 2 near planes along the normal (cssm_receiver_point)

void main()
{
    ivec2 px = cssm_pixel();
    if (px.x >= u_size.x || px.y >= u_size.y)
        return;
    uint p = uint(px.y) * uint(u_size.x) + uint(px.x);
    vec3 L = vec3(0.0);
    vec4 P = texelFetch(gi_gbuffer_position, px, 0);
    if (P.w > 0.0) {
        vec3 nor = texelFetch(gi_gbuffer_normal, px, 0).xyz;
        vec4 alb = texelFetch(gi_gbuffer_albedo, px, 0);
        vec4 ph = texelFetch(gi_gbuffer_phong, px, 0);
        CssmReceiver rc;
        rc.n = normalize(nor);
        rc.x = P.xyz + rc.n * u_lift;
        rc.self = -1;
        rc.kd = alb.rgb;
        rc.ks = ph.rgb;
        rc.lum_kd = gi_luminance(rc.kd);
        rc.lum_ks = gi_luminance(rc.ks);
        rc.exponent = alb.a > 0.5 ? min(ph.a, 1000.0) : ph.a; // mirrors: their Phong lobe
        rc.wo = normalize(u_eye - P.xyz);
        CssmOpts o;
        o.lim = u_lim;
        o.scale = u_scale;
        o.max_cut = u_max_cut;
        o.clamp_d = u_clamp;
        o.bias = u_bias;
        o.pcf = CSSM_PCF != 0;                   // 2 x 2 PCF
        o.jitter = CSSM_JITTER != 0;             // frames differ: jitter (§4.5)
        o.rep_centroid = CSSM_REP_CENTROID != 0; // rep=centroid
        uint rng = gi_rng_init(p, u_frame, u_seed ^ 0xc55u);
        uint gathered, clamped = 0u;
        L = cssm_gather(rc, o, rng, gathered, clamped);
        L += texelFetch(gi_gbuffer_emission, px, 0).rgb;
        atomicAdd(cssm_stats[0], gathered);
        atomicAdd(cssm_stats[1], 1u);
        atomicAdd(cssm_stats[2], clamped);
    }
    gi_accumulate_store(px, L);
}
