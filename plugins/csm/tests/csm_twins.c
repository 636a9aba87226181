/* The csm plugin's direction parameterisation, map basis and projection:
 * plugins/csm/csm_cpu.c and its GLSL twin plugins/csm/shaders/csm_geom.glsl
 * on the same 4096 random inputs agree within |gpu - cpu| <= 1e-4 |cpu| +
 * 1e-5, the absolute part times 256 for the grid coordinates (up to N = 256
 * in magnitude) and times 1 + 2/R for the projection (|x - c| / R up to
 * about 35 here). Directions are kept 1e-3 away
 * from the phi = 0 seam and the poles, where a 1-ulp difference may
 * legitimately wrap phi by 2 pi. */
#include "csm_cpu.h"

#include "gi/rng.h"
#include "gi/sampling.h"
#include "gi/shader.h"

#include "csm_test_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

extern const gi_shader_source gi_csm_twin_shaders[];

#define CASES 4096
enum { IN_F = 12, IN_U = 4, OUT_F = 19 };

static const char *kernel =
    "#include \"csm_geom.glsl\"\n"
    "layout(local_size_x = 64) in;\n"
    "layout(std430, binding = 0) readonly buffer InF { float inf[]; };\n"
    "layout(std430, binding = 1) readonly buffer InU { uint inu[]; };\n"
    "layout(std430, binding = 2) writeonly buffer Out { float o[]; };\n"
    "void main() {\n"
    "    uint c = gl_GlobalInvocationID.x;\n"
    "    uint f = c * 12u, u = c * 4u, r = c * 19u;\n"
    "    float theta = inf[f], phi = inf[f + 1u];\n"
    "    vec3 x = vec3(inf[f + 2u], inf[f + 3u], inf[f + 4u]);\n"
    "    vec3 w = vec3(inf[f + 5u], inf[f + 6u], inf[f + 7u]);\n"
    "    vec4 sphere = vec4(inf[f + 8u], inf[f + 9u], inf[f + 10u], inf[f + 11u]);\n"
    "    vec2 ang = csm_cell_angles(inu[u], inu[u + 1u], inu[u + 2u], inu[u + 3u]);\n"
    "    vec3 d = csm_dir(theta, phi);\n"
    "    vec2 g = csm_grid_coords(w, inu[u], inu[u + 1u]);\n"
    "    vec3 bt, bb, bd;\n"
    "    csm_basis(theta, phi, bt, bb, bd);\n"
    "    vec3 p = csm_project(sphere, theta, phi, x);\n"
    "    float v[19] = float[19](ang.x, ang.y, d.x, d.y, d.z, g.x, g.y, bt.x, bt.y, bt.z, bb.x, "
    "bb.y, bb.z,\n"
    "                            bd.x, bd.y, bd.z, p.x, p.y, p.z);\n"
    "    for (uint i = 0u; i < 19u; i++) o[r + i] = v[i];\n"
    "}\n";

int main(void)
{
    gi_gpu *gpu = csm_test_gpu(gi_csm_twin_shaders);
    if (!gpu)
        return 1;
    gi_error err;
    GLuint prog =
        gi_program_build_compute_text("plugins/csm/tests/csm_twins.comp", kernel, NULL, &err);
    if (!prog) {
        fprintf(stderr, "%s\n", err.text);
        return 1;
    }
    float *inf = malloc(sizeof(float) * CASES * IN_F), *cpu = malloc(sizeof(float) * CASES * OUT_F),
          *gpu_out = malloc(sizeof(float) * CASES * OUT_F);
    uint32_t *inu = malloc(sizeof(uint32_t) * CASES * IN_U);
    uint32_t rng = gi_rng_init(3, 0, 11);
    for (int c = 0; c < CASES; c++) {
        float *f = inf + c * IN_F;
        uint32_t *u = inu + c * IN_U;
        f[0] = GI_PI * gi_rng_next_float(&rng);
        f[1] = 2.0f * GI_PI * gi_rng_next_float(&rng);
        for (int i = 0; i < 3; i++)
            f[2 + i] = 4.0f * gi_rng_next_float(&rng) - 2.0f;
        gi_vec3 w;
        float phi;
        do {
            w = gi_sample_uniform_sphere(gi_rng_next_float(&rng), gi_rng_next_float(&rng));
            phi = atan2f(w.z, w.x);
        } while (fabsf(phi) < 1e-3f || fabsf(w.y) > 0.999f);
        f[5] = w.x, f[6] = w.y, f[7] = w.z;
        for (int i = 0; i < 3; i++)
            f[8 + i] = gi_rng_next_float(&rng) - 0.5f;
        f[11] = 0.1f + 3.0f * gi_rng_next_float(&rng);
        u[0] = 2 + gi_rng_next_u32(&rng) % 255, u[1] = 2 + gi_rng_next_u32(&rng) % 255;
        u[2] = gi_rng_next_u32(&rng) % u[1], u[3] = gi_rng_next_u32(&rng) % u[0];

        float *o = cpu + c * OUT_F;
        csm_cell_angles(u[0], u[1], u[2], u[3], &o[0], &o[1]);
        gi_vec3 d = csm_dir(f[0], f[1]);
        o[2] = d.x, o[3] = d.y, o[4] = d.z;
        csm_grid_coords(w, u[0], u[1], &o[5], &o[6]);
        gi_vec3 t, b;
        csm_basis(f[0], f[1], &t, &b, &d);
        o[7] = t.x, o[8] = t.y, o[9] = t.z, o[10] = b.x, o[11] = b.y, o[12] = b.z, o[13] = d.x,
        o[14] = d.y, o[15] = d.z;
        gi_vec3 p = csm_project(f + 8, f[0], f[1], gi_v3(f[2], f[3], f[4]));
        o[16] = p.x, o[17] = p.y, o[18] = p.z;
    }
    GLuint bufs[3];
    glCreateBuffers(3, bufs);
    glNamedBufferStorage(bufs[0], (GLsizeiptr)(sizeof(float) * CASES * IN_F), inf, 0);
    glNamedBufferStorage(bufs[1], (GLsizeiptr)(sizeof(uint32_t) * CASES * IN_U), inu, 0);
    glNamedBufferStorage(bufs[2], (GLsizeiptr)(sizeof(float) * CASES * OUT_F), NULL,
                         GL_DYNAMIC_STORAGE_BIT);
    for (GLuint i = 0; i < 3; i++)
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, i, bufs[i]);
    glUseProgram(prog);
    csm_test_dispatch_read(CASES, bufs[2], (GLsizeiptr)(sizeof(float) * CASES * OUT_F), gpu_out);
    static const char *names[OUT_F] = {
        "cell theta", "cell phi", "dir.x",      "dir.y",      "dir.z",        "grid u", "grid v",
        "t.x",        "t.y",      "t.z",        "b.x",        "b.y",          "b.z",    "d.x",
        "d.y",        "d.z",      "project sx", "project sy", "project depth"};
    int bad = 0;
    double worst = 0;
    for (int c = 0; c < CASES; c++)
        for (int i = 0; i < OUT_F; i++) {
            float want = cpu[c * OUT_F + i], got = gpu_out[c * OUT_F + i];
            float scale =
                i >= 16 ? 1.0f + 2.0f / inf[c * IN_F + 11] : 1.0f; /* |x - c| / R up to ~35 */
            float tol = (1e-4f * fabsf(want) + 1e-5f) * scale * (i == 5 || i == 6 ? 256.0f : 1.0f);
            double e = fabs((double)got - want);
            if (e > worst)
                worst = e;
            if (!(e <= tol)) {
                if (bad++ < 10)
                    fprintf(stderr, "case %d %s: cpu %.9g gpu %.9g\n", c, names[i], (double)want,
                            (double)got);
            }
        }
    printf(
        "csm geometry twins: %d of %d values differ beyond tolerance (largest difference %.3g)\n",
        bad, CASES * OUT_F, worst);
    glDeleteBuffers(3, bufs);
    glDeleteProgram(prog);
    free(inf);
    free(cpu);
    free(gpu_out);
    free(inu);
    gi_gpu_destroy(gpu);
    return bad ? 1 : 0;
}
