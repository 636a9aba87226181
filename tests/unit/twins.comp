// Kernel of test_twins.c: evaluates every shared GLSL function (rng,
// sequences, sampling, brdf, envmap, tonemap) on the inputs the C side
// generated, one invocation per case. Input/output offsets (I_*, U_*, S_*)
// and sizes come from the C side as #defines, so the two cannot drift.
#include "rng.glsl"
#include "sequences.glsl"
#include "sampling.glsl"
#include "brdf.glsl"
#include "envmap.glsl"
#include "tonemap.glsl"

layout(local_size_x = 64) in;
layout(std430, binding = 8) readonly buffer InU { uint in_u[]; };
layout(std430, binding = 9) readonly buffer InF { float in_f[]; };
layout(std430, binding = 10) writeonly buffer OutU { uint out_u[]; };
layout(std430, binding = 11) writeonly buffer OutF { float out_f[]; };

uint g_fi, g_of;

float inf1(uint i) { return in_f[g_fi + i]; }
vec3 inf3(uint i) { return vec3(in_f[g_fi + i], in_f[g_fi + i + 1u], in_f[g_fi + i + 2u]); }
void put1(uint s, float v) { out_f[g_of + s] = v; }
void put2(uint s, vec2 v) { out_f[g_of + s] = v.x; out_f[g_of + s + 1u] = v.y; }
void put3(uint s, vec3 v)
{
    out_f[g_of + s] = v.x;
    out_f[g_of + s + 1u] = v.y;
    out_f[g_of + s + 2u] = v.z;
}

void main()
{
    uint k = gl_GlobalInvocationID.x;
    if (k >= uint(CASES))
        return;
    uint iu = k * uint(IN_U), ou = k * uint(OUT_U);
    g_fi = k * uint(IN_F);
    g_of = k * uint(OUT_F);
    uint pixel = in_u[iu + 0u], smp = in_u[iu + 1u], seed = in_u[iu + 2u], idx = in_u[iu + 3u];
    float u1 = inf1(I_U1), u2 = inf1(I_U2), u3 = inf1(I_U3);

    // rng.glsl
    out_u[ou + U_PCG] = gi_pcg_hash(pixel);
    uint st = gi_rng_init(pixel, smp, seed);
    out_u[ou + U_INIT] = st;
    out_u[ou + U_NEXT0] = gi_rng_next_u32(st);
    out_u[ou + U_NEXT1] = gi_rng_next_u32(st);
    out_u[ou + U_NEXT2] = gi_rng_next_u32(st);
    out_u[ou + U_NEXTF] = floatBitsToUint(gi_rng_next_float(st));

    // sequences.glsl
    out_u[ou + U_REV] = gi_reverse_bits32(idx);
    out_u[ou + U_RADINV2] = floatBitsToUint(gi_radical_inverse2(idx));
    out_u[ou + U_SOBOL2] = floatBitsToUint(gi_sobol2(idx));
    vec2 r2 = gi_r2(idx);
    out_u[ou + U_R2X] = floatBitsToUint(r2.x);
    out_u[ou + U_R2Y] = floatBitsToUint(r2.y);
    out_u[ou + U_HALTON0] = floatBitsToUint(gi_halton(0u, idx));
    put1(S_HALTON, gi_halton(1u + pixel % 7u, idx % 100000u));
    put2(S_HAMMERSLEY, gi_hammersley(idx % 4096u, 4096u));
    put1(S_CP_ROTATE, gi_cp_rotate(u1, u2));

    // sampling.glsl
    vec3 N = inf3(I_N), wo = inf3(I_WO), wi = inf3(I_WI);
    float cos_max = inf1(I_COSMAX);
    put2(S_DISK, gi_sample_concentric_disk(u1, u2));
    vec3 ch = gi_sample_cosine_hemisphere(u1, u2);
    put3(S_COSHEMI, ch);
    put1(S_COSPDF, gi_cosine_hemisphere_pdf(wi.z));
    put3(S_SPHERE, gi_sample_uniform_sphere(u1, u2));
    put3(S_HEMI, gi_sample_uniform_hemisphere(u1, u2));
    put3(S_CONE, gi_sample_uniform_cone(u1, u2, cos_max));
    put1(S_CONEPDF, gi_uniform_cone_pdf(cos_max));
    put3(S_TRI, gi_sample_uniform_triangle(u1, u2));
    put1(S_POWER, gi_power_heuristic(inf1(I_NF), inf1(I_FPDF), inf1(I_NG), inf1(I_GPDF)));
    vec3 t, b;
    gi_onb(N, t, b);
    put3(S_ONB_T, t);
    put3(S_ONB_B, b);
    put3(S_TO_WORLD, gi_to_world(wi, N));
    put3(S_TO_LOCAL, gi_to_local(wi, N));

    // brdf.glsl
    gi_brdf m = gi_brdf(inf3(I_KD), inf3(I_KS), inf1(I_EXP), int(inf1(I_MIRROR)));
    put1(S_SPEC_PROB, gi_brdf_spec_prob(m));
    vec3 r = gi_reflect(wo, N);
    put3(S_REFLECT, r);
    put3(S_LOBE_SAMPLE, gi_phong_lobe_sample(r, m.n, u1, u2));
    put1(S_LOBE_PDF, gi_phong_lobe_pdf(r, m.n, wi));
    put3(S_EVAL, gi_brdf_eval(m, N, wo, wi));
    put1(S_PDF, gi_brdf_pdf(m, N, wo, wi));
    vec3 swi, weight;
    float spdf;
    bool delta;
    gi_brdf_sample(m, N, wo, u1, u2, u3, swi, spdf, weight, delta);
    put3(S_SAMPLE_WI, swi);
    put1(S_SAMPLE_PDF, spdf);
    put3(S_SAMPLE_WEIGHT, weight);
    out_u[ou + U_DELTA] = delta ? 1u : 0u;

    // tonemap.glsl
    put1(S_SRGB_ENC, gi_srgb_encode(inf1(I_LINEAR)));
    put1(S_SRGB_DEC, gi_srgb_decode(inf1(I_SRGB)));
    put1(S_TONEMAP, gi_tonemap(inf1(I_LINEAR), inf1(I_EXPOSURE)));

    // envmap.glsl
    vec3 d = inf3(I_D);
    put2(S_ENV_UV, gi_envmap_dir_to_uv(d));
    put3(S_ENV_DIR, gi_envmap_uv_to_dir(vec2(u1, u2)));
    put3(S_ENV_EVAL, gi_envmap_eval(d));
    put1(S_ENV_PDF, gi_envmap_pdf(d));
    vec3 sdir;
    float epdf = gi_envmap_sample(u1, u2, sdir);
    put3(S_ENV_SAMPLE_DIR, sdir);
    put1(S_ENV_SAMPLE_PDF, epdf);
}
