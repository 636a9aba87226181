/* The C headers and their GLSL twins agree: tests/unit/twins.comp runs every
 * function of rng/sequences/sampling/brdf/envmap/tonemap.glsl on a few
 * thousand random inputs made here, and the C versions run on the same
 * inputs. Integer outputs (rng, bit reversal, base-2 sequences, the delta
 * flag) must be bit-identical; floats must agree within
 *   |gpu - cpu| <= rtol |cpu| + atol,   rtol = 1e-4, atol = 1e-5,
 * with two documented exceptions that follow the GLSL 4.50 precision rules:
 *  - anything that goes through pow (Phong lobe, BRDF eval/pdf/sample):
 *    pow is exp2(y log2 x) with log2 only 2^-21 absolute near 1, so x^n can
 *    be off by about n ln2 2^-21 relative, and a sampled direction's error
 *    dc feeds back as n dc: rtol = 2e-4 + 1e-6 n;
 *  - envmap pdfs divide by sin(theta): rtol = 1e-4 + 1e-6 / sin(theta).
 * Inputs are kept away from the few discontinuities where a 1-ulp
 * difference legitimately flips a branch (lobe choice u3 ~ P_spec, wi at the
 * horizon, texel edges and the seam of the environment map).
 * Also run for a black environment map. */
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "gi/brdf.h"
#include "gi/envmap.h"
#include "gi/gpu.h"
#include "gi/rng.h"
#include "gi/sampling.h"
#include "gi/sequences.h"
#include "gi/shader.h"
#include "gi/tonemap.h"

#define CASES 4096

/* Input layout (per case): IN_U uints, IN_F floats. */
enum { IN_U = 4 };
enum {
    I_U1 = 0,
    I_U2 = 1,
    I_U3 = 2,
    I_U4 = 3,
    I_N = 4,
    I_EXP = 7,
    I_WO = 8,
    I_COSMAX = 11,
    I_WI = 12,
    I_EXPOSURE = 15,
    I_KD = 16,
    I_MIRROR = 19,
    I_KS = 20,
    I_LINEAR = 23,
    I_D = 24,
    I_SRGB = 27,
    I_NF = 28,
    I_FPDF = 29,
    I_NG = 30,
    I_GPDF = 31,
    IN_F = 32
};

/* Integer outputs, compared bit for bit. */
#define UINT_SLOTS(X)                                                                              \
    X(U_PCG)                                                                                       \
    X(U_INIT)                                                                                      \
    X(U_NEXT0)                                                                                     \
    X(U_NEXT1)                                                                                     \
    X(U_NEXT2)                                                                                     \
    X(U_NEXTF)                                                                                     \
    X(U_REV)                                                                                       \
    X(U_RADINV2)                                                                                   \
    X(U_SOBOL2)                                                                                    \
    X(U_R2X)                                                                                       \
    X(U_R2Y)                                                                                       \
    X(U_HALTON0)                                                                                   \
    X(U_DELTA)

/* Float outputs: name, width, tolerance class. */
enum { TOL_DEFAULT, TOL_POW, TOL_ENV_PDF, TOL_ENV_SAMPLE_PDF };
#define FLOAT_SLOTS(X)                                                                             \
    X(S_HALTON, 1, TOL_DEFAULT)                                                                    \
    X(S_HAMMERSLEY, 2, TOL_DEFAULT)                                                                \
    X(S_CP_ROTATE, 1, TOL_DEFAULT)                                                                 \
    X(S_DISK, 2, TOL_DEFAULT)                                                                      \
    X(S_COSHEMI, 3, TOL_DEFAULT)                                                                   \
    X(S_COSPDF, 1, TOL_DEFAULT)                                                                    \
    X(S_SPHERE, 3, TOL_DEFAULT)                                                                    \
    X(S_HEMI, 3, TOL_DEFAULT)                                                                      \
    X(S_CONE, 3, TOL_DEFAULT)                                                                      \
    X(S_CONEPDF, 1, TOL_DEFAULT)                                                                   \
    X(S_TRI, 3, TOL_DEFAULT)                                                                       \
    X(S_POWER, 1, TOL_DEFAULT)                                                                     \
    X(S_ONB_T, 3, TOL_DEFAULT)                                                                     \
    X(S_ONB_B, 3, TOL_DEFAULT)                                                                     \
    X(S_TO_WORLD, 3, TOL_DEFAULT)                                                                  \
    X(S_TO_LOCAL, 3, TOL_DEFAULT)                                                                  \
    X(S_SPEC_PROB, 1, TOL_DEFAULT)                                                                 \
    X(S_REFLECT, 3, TOL_DEFAULT)                                                                   \
    X(S_LOBE_SAMPLE, 3, TOL_POW)                                                                   \
    X(S_LOBE_PDF, 1, TOL_POW)                                                                      \
    X(S_EVAL, 3, TOL_POW)                                                                          \
    X(S_PDF, 1, TOL_POW)                                                                           \
    X(S_SAMPLE_WI, 3, TOL_POW)                                                                     \
    X(S_SAMPLE_PDF, 1, TOL_POW)                                                                    \
    X(S_SAMPLE_WEIGHT, 3, TOL_POW)                                                                 \
    X(S_SRGB_ENC, 1, TOL_DEFAULT)                                                                  \
    X(S_SRGB_DEC, 1, TOL_DEFAULT)                                                                  \
    X(S_TONEMAP, 1, TOL_DEFAULT)                                                                   \
    X(S_ENV_UV, 2, TOL_DEFAULT)                                                                    \
    X(S_ENV_DIR, 3, TOL_DEFAULT)                                                                   \
    X(S_ENV_EVAL, 3, TOL_DEFAULT)                                                                  \
    X(S_ENV_PDF, 1, TOL_ENV_PDF)                                                                   \
    X(S_ENV_SAMPLE_DIR, 3, TOL_DEFAULT)                                                            \
    X(S_ENV_SAMPLE_PDF, 1, TOL_ENV_SAMPLE_PDF)

#define UINT_ENUM(name) name,
enum { UINT_SLOTS(UINT_ENUM) OUT_U };
#define FLOAT_ID(name, width, tol) name##_ID,
enum { FLOAT_SLOTS(FLOAT_ID) FLOAT_SLOT_COUNT };
#define FLOAT_INFO(name, width, tol) {#name, width, tol},
static const struct {
    const char *name;
    int width, tol;
} float_slots[] = {FLOAT_SLOTS(FLOAT_INFO)};

/* Offsets of the float slots, filled by layout_slots(). */
typedef struct slots {
    int off[FLOAT_SLOT_COUNT];
    int out_f;
} slots;

static void layout_slots(slots *s)
{
    int o = 0;
    for (int i = 0; i < FLOAT_SLOT_COUNT; i++) {
        s->off[i] = o;
        o += float_slots[i].width;
    }
    s->out_f = o;
}

static void put(const slots *s, float *out, int id, const float *v)
{
    memcpy(out + s->off[id], v, sizeof(float) * (size_t)float_slots[id].width);
}
static void put1(const slots *s, float *out, int id, float v)
{
    put(s, out, id, &v);
}
static void put3(const slots *s, float *out, int id, gi_vec3 v)
{
    float a[3] = {v.x, v.y, v.z};
    put(s, out, id, a);
}

static uint32_t float_bits(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}

/* Appends "#define NAME VALUEu\n". */
static void add_define(char **text, size_t *len, const char *name, int value)
{
    char line[96];
    int n = snprintf(line, sizeof line, "#define %s %du\n", name, value);
    *text = realloc(*text, *len + (size_t)n + 1);
    memcpy(*text + *len, line, (size_t)n + 1);
    *len += (size_t)n;
}

static char *make_defines(const slots *s)
{
    char *text = NULL;
    size_t len = 0;
    add_define(&text, &len, "CASES", CASES);
    add_define(&text, &len, "IN_U", IN_U);
    add_define(&text, &len, "IN_F", IN_F);
    add_define(&text, &len, "OUT_U", OUT_U);
    add_define(&text, &len, "OUT_F", s->out_f);
#define DEF_IN(name) add_define(&text, &len, #name, name)
    DEF_IN(I_U1);
    DEF_IN(I_U2);
    DEF_IN(I_U3);
    DEF_IN(I_U4);
    DEF_IN(I_N);
    DEF_IN(I_EXP);
    DEF_IN(I_WO);
    DEF_IN(I_COSMAX);
    DEF_IN(I_WI);
    DEF_IN(I_EXPOSURE);
    DEF_IN(I_KD);
    DEF_IN(I_MIRROR);
    DEF_IN(I_KS);
    DEF_IN(I_LINEAR);
    DEF_IN(I_D);
    DEF_IN(I_SRGB);
    DEF_IN(I_NF);
    DEF_IN(I_FPDF);
    DEF_IN(I_NG);
    DEF_IN(I_GPDF);
#define DEF_U(name) add_define(&text, &len, #name, name);
    UINT_SLOTS(DEF_U)
    for (int i = 0; i < FLOAT_SLOT_COUNT; i++)
        add_define(&text, &len, float_slots[i].name, s->off[i]);
    return text;
}

static gi_vec3 rand_dir(uint32_t *st)
{
    return gi_sample_uniform_sphere(gi_rng_next_float(st), gi_rng_next_float(st));
}

/* Distance of x from the nearest multiple of 1/n, in units of 1/n. */
static float edge_distance(float x, uint32_t n)
{
    float f = x * (float)n;
    f -= floorf(f);
    return fminf(f, 1.0f - f);
}

/* Random inputs, nudged away from branch flips (see the file comment). */
static void make_inputs(const gi_envmap *env, uint32_t *in_u, float *in_f)
{
    uint32_t st = gi_rng_init(12, 34, 56);
    const gi_vec3 special_n[4] = {{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {1, 0, -0.0f}};
    for (int k = 0; k < CASES; k++) {
        uint32_t *u = in_u + k * IN_U;
        float *f = in_f + k * IN_F;
        for (int i = 0; i < IN_U; i++)
            u[i] = gi_rng_next_u32(&st);
        if (k < 16)
            u[3] = (uint32_t)k; /* small sequence indices too */
        for (int i = 0; i < 4; i++)
            f[I_U1 + i] = gi_rng_next_float(&st);
        gi_vec3 N = k < 4 ? special_n[k] : rand_dir(&st);
        gi_v3_store(N, f + I_N);
        /* Exponents log-uniform in [1, 1000]; some mirrors by flag. */
        f[I_EXP] = powf(1000.0f, gi_rng_next_float(&st));
        f[I_MIRROR] = gi_rng_next_float(&st) < 0.1f ? 1.0f : 0.0f;
        for (int c = 0; c < 3; c++) {
            f[I_KD + c] = gi_rng_next_float(&st);
            f[I_KS + c] = k % 5 == 0 ? 0.0f : gi_rng_next_float(&st);
        }
        /* wo mostly above the surface, wi away from the horizon and from the
         * edge of the Phong lobe (c^n with n < 1 jumps there). */
        gi_vec3 wo = rand_dir(&st);
        if (k % 8 != 0 && gi_v3_dot(wo, N) < 0.0f)
            wo = gi_v3_scale(wo, -1.0f);
        while (fabsf(gi_v3_dot(wo, N)) < 1e-3f)
            wo = rand_dir(&st);
        gi_vec3 r = gi_reflect(wo, N), wi;
        do {
            wi = rand_dir(&st);
            if (k % 8 != 1 && gi_v3_dot(wi, N) < 0.0f)
                wi = gi_v3_scale(wi, -1.0f);
        } while (fabsf(gi_v3_dot(wi, N)) < 1e-3f || fabsf(gi_v3_dot(wi, r)) < 1e-3f);
        gi_v3_store(wo, f + I_WO);
        gi_v3_store(wi, f + I_WI);
        /* Lobe choice: keep u3 clear of P_spec. */
        gi_brdf b = {{f[I_KD], f[I_KD + 1], f[I_KD + 2]},
                     {f[I_KS], f[I_KS + 1], f[I_KS + 2]},
                     f[I_EXP],
                     (int)f[I_MIRROR]};
        float ps = gi_brdf_spec_prob(&b);
        if (fabsf(f[I_U3] - ps) < 1e-4f)
            f[I_U3] = ps < 0.5f ? ps + 0.25f : ps - 0.25f;
        f[I_COSMAX] = 2.0f * gi_rng_next_float(&st) - 1.0f;
        f[I_EXPOSURE] = 8.0f * gi_rng_next_float(&st) - 4.0f;
        float lin = 2.0f * gi_rng_next_float(&st);
        if (k % 97 == 0)
            lin = NAN;
        else if (k % 89 == 0)
            lin = INFINITY;
        else if (k % 83 == 0)
            lin = -0.5f;
        f[I_LINEAR] = lin;
        f[I_SRGB] = gi_rng_next_float(&st);
        f[I_NF] = 1.0f + (float)(k % 3);
        f[I_FPDF] = k % 50 == 0 ? 0.0f : 10.0f * gi_rng_next_float(&st);
        f[I_NG] = 1.0f;
        f[I_GPDF] = 10.0f * gi_rng_next_float(&st);
        /* Environment direction: off texel edges, the seam and the poles. */
        gi_vec3 d;
        float du, dv;
        do {
            d = rand_dir(&st);
            gi_envmap_dir_to_uv(env, d, &du, &dv);
        } while (fabsf(d.y) > 0.999f || edge_distance(du, env->width) < 1e-3f ||
                 edge_distance(dv, env->height) < 1e-3f);
        gi_v3_store(d, f + I_D);
    }
}

/* The C side of twins.comp, case by case. */
static void eval_cpu(const slots *s, const gi_envmap *env, const uint32_t *u, const float *f,
                     uint32_t *ou, float *of)
{
    uint32_t pixel = u[0], smp = u[1], seed = u[2], idx = u[3];
    float u1 = f[I_U1], u2 = f[I_U2], u3 = f[I_U3];
    ou[U_PCG] = gi_pcg_hash(pixel);
    uint32_t st = gi_rng_init(pixel, smp, seed);
    ou[U_INIT] = st;
    ou[U_NEXT0] = gi_rng_next_u32(&st);
    ou[U_NEXT1] = gi_rng_next_u32(&st);
    ou[U_NEXT2] = gi_rng_next_u32(&st);
    ou[U_NEXTF] = float_bits(gi_rng_next_float(&st));

    ou[U_REV] = gi_reverse_bits32(idx);
    ou[U_RADINV2] = float_bits(gi_radical_inverse2(idx));
    ou[U_SOBOL2] = float_bits(gi_sobol2(idx));
    float r2[2];
    gi_r2(idx, r2);
    ou[U_R2X] = float_bits(r2[0]);
    ou[U_R2Y] = float_bits(r2[1]);
    ou[U_HALTON0] = float_bits(gi_halton(0, idx));
    put1(s, of, S_HALTON_ID, gi_halton(1 + pixel % 7, idx % 100000));
    float hm[2];
    gi_hammersley(idx % 4096, 4096, hm);
    put(s, of, S_HAMMERSLEY_ID, hm);
    put1(s, of, S_CP_ROTATE_ID, gi_cp_rotate(u1, u2));

    gi_vec3 N = gi_v3_load(f + I_N), wo = gi_v3_load(f + I_WO), wi = gi_v3_load(f + I_WI);
    float disk[2];
    gi_sample_concentric_disk(u1, u2, &disk[0], &disk[1]);
    put(s, of, S_DISK_ID, disk);
    put3(s, of, S_COSHEMI_ID, gi_sample_cosine_hemisphere(u1, u2));
    put1(s, of, S_COSPDF_ID, gi_cosine_hemisphere_pdf(wi.z));
    put3(s, of, S_SPHERE_ID, gi_sample_uniform_sphere(u1, u2));
    put3(s, of, S_HEMI_ID, gi_sample_uniform_hemisphere(u1, u2));
    put3(s, of, S_CONE_ID, gi_sample_uniform_cone(u1, u2, f[I_COSMAX]));
    put1(s, of, S_CONEPDF_ID, gi_uniform_cone_pdf(f[I_COSMAX]));
    float tri[3];
    gi_sample_uniform_triangle(u1, u2, tri);
    put(s, of, S_TRI_ID, tri);
    put1(s, of, S_POWER_ID, gi_power_heuristic(f[I_NF], f[I_FPDF], f[I_NG], f[I_GPDF]));
    gi_vec3 t, b;
    gi_onb(N, &t, &b);
    put3(s, of, S_ONB_T_ID, t);
    put3(s, of, S_ONB_B_ID, b);
    put3(s, of, S_TO_WORLD_ID, gi_to_world(wi, N));
    put3(s, of, S_TO_LOCAL_ID, gi_to_local(wi, N));

    gi_brdf m = {{f[I_KD], f[I_KD + 1], f[I_KD + 2]},
                 {f[I_KS], f[I_KS + 1], f[I_KS + 2]},
                 f[I_EXP],
                 (int)f[I_MIRROR]};
    put1(s, of, S_SPEC_PROB_ID, gi_brdf_spec_prob(&m));
    gi_vec3 r = gi_reflect(wo, N);
    put3(s, of, S_REFLECT_ID, r);
    put3(s, of, S_LOBE_SAMPLE_ID, gi_phong_lobe_sample(r, m.n, u1, u2));
    put1(s, of, S_LOBE_PDF_ID, gi_phong_lobe_pdf(r, m.n, wi));
    float fe[3];
    gi_brdf_eval(&m, N, wo, wi, fe);
    put(s, of, S_EVAL_ID, fe);
    put1(s, of, S_PDF_ID, gi_brdf_pdf(&m, N, wo, wi));
    gi_vec3 swi;
    float spdf, weight[3];
    int delta;
    gi_brdf_sample(&m, N, wo, u1, u2, u3, &swi, &spdf, weight, &delta);
    put3(s, of, S_SAMPLE_WI_ID, swi);
    put1(s, of, S_SAMPLE_PDF_ID, spdf);
    put(s, of, S_SAMPLE_WEIGHT_ID, weight);
    ou[U_DELTA] = (uint32_t)delta;

    put1(s, of, S_SRGB_ENC_ID, gi_srgb_encode(f[I_LINEAR]));
    put1(s, of, S_SRGB_DEC_ID, gi_srgb_decode(f[I_SRGB]));
    put1(s, of, S_TONEMAP_ID, gi_tonemap(f[I_LINEAR], f[I_EXPOSURE]));

    gi_vec3 d = gi_v3_load(f + I_D);
    float uv[2];
    gi_envmap_dir_to_uv(env, d, &uv[0], &uv[1]);
    put(s, of, S_ENV_UV_ID, uv);
    put3(s, of, S_ENV_DIR_ID, gi_envmap_uv_to_dir(env, u1, u2));
    float L[3];
    gi_envmap_eval(env, d, L);
    put(s, of, S_ENV_EVAL_ID, L);
    put1(s, of, S_ENV_PDF_ID, gi_envmap_pdf(env, d));
    gi_vec3 sdir;
    float epdf = gi_envmap_sample(env, u1, u2, &sdir);
    put3(s, of, S_ENV_SAMPLE_DIR_ID, sdir);
    put1(s, of, S_ENV_SAMPLE_PDF_ID, epdf);
}

/* Cases whose C sample landed where a 1-ulp difference flips a branch: at
 * the horizon, or on the edge of the Phong lobe. */
static int sample_is_fragile(const float *f, const float *of, const slots *s)
{
    gi_vec3 N = gi_v3_load(f + I_N), wo = gi_v3_load(f + I_WO);
    gi_vec3 swi = gi_v3_load(of + s->off[S_SAMPLE_WI_ID]);
    gi_vec3 r = gi_reflect(wo, N);
    return fabsf(gi_v3_dot(N, swi)) < 1e-4f || fabsf(gi_v3_dot(r, swi)) < 1e-3f;
}

static GLuint make_texture(GLenum internal, uint32_t w, uint32_t h, GLenum format,
                           const float *data)
{
    GLuint t;
    glCreateTextures(GL_TEXTURE_2D, 1, &t);
    glTextureStorage2D(t, 1, internal, (GLsizei)w, (GLsizei)h);
    glTextureSubImage2D(t, 0, 0, 0, (GLsizei)w, (GLsizei)h, format, GL_FLOAT, data);
    glTextureParameteri(t, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(t, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    return t;
}

static GLuint make_buffer(GLuint binding, size_t size, const void *data)
{
    GLuint b;
    glCreateBuffers(1, &b);
    glNamedBufferStorage(b, (GLsizeiptr)size, data, 0);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, binding, b);
    return b;
}

static char *read_text(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *text = malloc((size_t)n + 1);
    if (fread(text, 1, (size_t)n, f) != (size_t)n)
        n = 0;
    text[n] = '\0';
    fclose(f);
    return text;
}

/* One run of the kernel against one environment map. */
static void run_case_set(GLuint prog, const slots *s, const gi_envmap *env, const char *label)
{
    /* The environment textures exactly as gpu_scene.c uploads them. */
    size_t texels = (size_t)env->width * env->height;
    float *rgba = malloc(texels * 4 * sizeof(float));
    for (size_t i = 0; i < texels; i++) {
        memcpy(rgba + i * 4, env->rgb + i * 3, 3 * sizeof(float));
        rgba[i * 4 + 3] = 1.0f;
    }
    GLuint tex[3] = {
        make_texture(GL_RGBA32F, env->width, env->height, GL_RGBA, rgba),
        make_texture(GL_R32F, env->width + 1, env->height, GL_RED, env->cond_cdf),
        make_texture(GL_R32F, env->height + 1, 1, GL_RED, env->marg_cdf),
    };
    free(rgba);
    glBindTextureUnit(GI_TEX_ENV, tex[0]);
    glBindTextureUnit(GI_TEX_ENV_COND, tex[1]);
    glBindTextureUnit(GI_TEX_ENV_MARG, tex[2]);
    GLint loc = glGetUniformLocation(prog, "gi_env_rotation");
    CHECK_MSG(loc >= 0, "uniform gi_env_rotation not found");
    glProgramUniform1f(prog, loc, env->rotation);

    uint32_t *in_u = calloc(CASES * IN_U, sizeof(uint32_t));
    float *in_f = calloc(CASES * IN_F, sizeof(float));
    make_inputs(env, in_u, in_f);
    size_t nu = (size_t)CASES * OUT_U, nf = (size_t)CASES * s->out_f;
    uint32_t *cpu_u = calloc(nu, sizeof(uint32_t)), *gpu_u = calloc(nu, sizeof(uint32_t));
    float *cpu_f = calloc(nf, sizeof(float)), *gpu_f = calloc(nf, sizeof(float));
    for (int k = 0; k < CASES; k++)
        eval_cpu(s, env, in_u + k * IN_U, in_f + k * IN_F, cpu_u + (size_t)k * OUT_U,
                 cpu_f + (size_t)k * s->out_f);

    GLuint bufs[4] = {
        make_buffer(8, sizeof(uint32_t) * CASES * IN_U, in_u),
        make_buffer(9, sizeof(float) * CASES * IN_F, in_f),
        make_buffer(10, sizeof(uint32_t) * nu, NULL),
        make_buffer(11, sizeof(float) * nf, NULL),
    };
    glUseProgram(prog);
    glDispatchCompute(CASES / 64, 1, 1);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    glGetNamedBufferSubData(bufs[2], 0, (GLsizeiptr)(sizeof(uint32_t) * nu), gpu_u);
    glGetNamedBufferSubData(bufs[3], 0, (GLsizeiptr)(sizeof(float) * nf), gpu_f);
    gi_error err;
    CHECK_MSG(gi_gl_check("twins dispatch", &err) == GI_OK, "%s", err.text);

    /* Integers: bit for bit. */
    for (int slot = 0; slot < OUT_U; slot++) {
        int bad = 0, first = -1;
        for (int k = 0; k < CASES; k++)
            if (cpu_u[(size_t)k * OUT_U + slot] != gpu_u[(size_t)k * OUT_U + slot]) {
                bad++;
                first = first < 0 ? k : first;
            }
        CHECK_MSG(bad == 0, "%s: uint slot %d differs in %d cases (first %d: %u vs %u)", label,
                  slot, bad, first, first >= 0 ? cpu_u[(size_t)first * OUT_U + slot] : 0,
                  first >= 0 ? gpu_u[(size_t)first * OUT_U + slot] : 0);
    }

    /* Floats within their class tolerance. */
    printf("%s: %-18s %12s %12s %9s\n", label, "function", "max |diff|", "max rel", "fails");
    for (int id = 0; id < FLOAT_SLOT_COUNT; id++) {
        double max_abs = 0, max_rel = 0;
        int bad = 0, skipped = 0, first = -1, first_c = 0;
        for (int k = 0; k < CASES; k++) {
            const float *f = in_f + k * IN_F;
            const float *cf = cpu_f + (size_t)k * s->out_f, *gf = gpu_f + (size_t)k * s->out_f;
            int tol = float_slots[id].tol;
            int is_sample =
                id == S_SAMPLE_WI_ID || id == S_SAMPLE_PDF_ID || id == S_SAMPLE_WEIGHT_ID;
            if (is_sample && sample_is_fragile(f, cf, s)) {
                skipped++;
                continue;
            }
            double rtol = 1e-4, atol = 1e-5;
            if (tol == TOL_POW)
                rtol = 2e-4 + 1e-6 * f[I_EXP];
            if (tol == TOL_ENV_PDF || tol == TOL_ENV_SAMPLE_PDF) {
                const float *dir = tol == TOL_ENV_PDF ? f + I_D : cf + s->off[S_ENV_SAMPLE_DIR_ID];
                double sin_t = sqrt(fmax(1e-12, 1.0 - (double)dir[1] * dir[1]));
                rtol = 1e-4 + 1e-6 / sin_t;
            }
            for (int c = 0; c < float_slots[id].width; c++) {
                double a = cf[s->off[id] + c], g = gf[s->off[id] + c];
                double diff = fabs(a - g);
                if (a != a || g != g)
                    diff = (a != a && g != g) ? 0.0 : INFINITY;
                if (a == g) /* also equal infinities */
                    diff = 0.0;
                max_abs = fmax(max_abs, diff);
                if (fabs(a) > 1e-3)
                    max_rel = fmax(max_rel, diff / fabs(a));
                if (!(diff <= rtol * fabs(a) + atol)) {
                    bad++;
                    if (first < 0)
                        first = k, first_c = c;
                }
            }
        }
        printf("%s: %-18s %12.3g %12.3g %9d%s\n", label, float_slots[id].name + 2, max_abs, max_rel,
               bad, skipped ? " (fragile samples skipped)" : "");
        if (bad)
            fprintf(stderr, "  first failing case %d component %d: cpu %.9g gpu %.9g (n %.4g)\n",
                    first, first_c, cpu_f[(size_t)first * s->out_f + s->off[id] + first_c],
                    gpu_f[(size_t)first * s->out_f + s->off[id] + first_c],
                    in_f[first * IN_F + I_EXP]);
        CHECK_MSG(bad == 0, "%s: %s differs in %d components", label, float_slots[id].name, bad);
        if (id == S_SAMPLE_WI_ID)
            CHECK_MSG(skipped < CASES / 50, "%s: %d fragile samples skipped", label, skipped);
    }

    glDeleteBuffers(4, bufs);
    glDeleteTextures(3, tex);
    free(in_u);
    free(in_f);
    free(cpu_u);
    free(gpu_u);
    free(cpu_f);
    free(gpu_f);
}

/* All shared files together with the scene's: scene.glsl defines
 * GI_ENV_ROTATION (the scene-info block), which replaces the
 * gi_env_rotation uniform of envmap.glsl. */
static void check_combined_build(void)
{
    const char *text =
        "#include \"scene.glsl\"\n"
        "#include \"lights.glsl\"\n"
        "#include \"common.glsl\"\n"
        "#include \"tonemap.glsl\"\n"
        "#include \"envmap.glsl\"\n"
        "#include \"brdf.glsl\"\n"
        "#include \"sequences.glsl\"\n"
        "#include \"rng.glsl\"\n"
        "layout(local_size_x = 1) in;\n"
        "layout(std430, binding = 8) buffer Out { vec4 o[]; };\n"
        "void main()\n"
        "{\n"
        "    uint s = gi_rng_init(0u, 0u, 0u);\n"
        "    vec3 d;\n"
        "    float p = gi_envmap_sample(gi_rng_next_float(s), gi_halton(2u, 5u), d);\n"
        "    gi_brdf b = gi_brdf(vec3(0.5), vec3(0.5), 10.0, 0);\n"
        "    vec3 f = gi_brdf_eval(b, vec3(0.0, 1.0, 0.0), d, d);\n"
        "    o[0] = vec4(gi_tonemap(f + gi_envmap_eval(d), 0.0), p);\n"
        "}\n";
    gi_error err;
    GLuint prog = gi_program_build_compute_text("tests/unit/combined.comp", text, NULL, &err);
    CHECK_MSG(prog != 0, "%s", err.text);
    if (prog) {
        CHECK(glGetUniformLocation(prog, "gi_env_rotation") < 0);
        glDeleteProgram(prog);
    }
}

int main(void)
{
    gi_error err;
    gi_gpu *gpu = gi_gpu_create(NULL, &err);
    CHECK_MSG(gpu != NULL, "%s", err.text);
    if (!gpu)
        return gi_test_finish();
    printf("renderer: %s\n", gi_gpu_renderer(gpu));

    check_combined_build();
    slots s;
    layout_slots(&s);
    char *defines = make_defines(&s);
    char *text = read_text(GI_SOURCE_DIR "/tests/unit/twins.comp");
    CHECK_MSG(text != NULL, "cannot read tests/unit/twins.comp");
    GLuint prog =
        text ? gi_program_build_compute_text("tests/unit/twins.comp", text, defines, &err) : 0;
    CHECK_MSG(prog != 0, "%s", err.text);
    if (prog) {
        /* A random non-uniform 16 x 8 map (a black row, hot texels), rotated. */
        const uint32_t w = 16, h = 8;
        float *rgba = malloc(w * h * 4 * sizeof(float));
        uint32_t st = gi_rng_init(1, 1, 1);
        for (uint32_t k = 0; k < w * h; k++) {
            float scale = gi_rng_next_float(&st) < 0.1f ? 30.0f : 1.0f;
            for (int c = 0; c < 3; c++)
                rgba[k * 4 + c] = (k / w == 3) ? 0.0f : scale * gi_rng_next_float(&st);
            rgba[k * 4 + 3] = 1.0f;
        }
        gi_envmap *env = gi_envmap_create(rgba, w, h, 1.7f, 40.0f);
        run_case_set(prog, &s, env, "lit map");
        gi_envmap_free(env);
        memset(rgba, 0, w * h * 4 * sizeof(float));
        env = gi_envmap_create(rgba, w, h, 1.0f, -15.0f);
        run_case_set(prog, &s, env, "black map");
        gi_envmap_free(env);
        free(rgba);
        glDeleteProgram(prog);
    }
    free(text);
    free(defines);
    gi_gpu_destroy(gpu);
    return gi_test_finish();
}
