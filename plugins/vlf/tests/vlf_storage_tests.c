/* The vlf plugin's storage formats (paper §3.1, §6) and its propagation
 * on the GPU against independent computations (the plugin's CPU sources
 * and vlf_gpu.c are compiled in; see plugins/vlf/README.md "Tests"):
 *
 *   vlf_storage_tests precision  the storage formats (RGBA16F, RGB9E5):
 *                                encoders, the propagated maps against
 *                                float32 on the glossy Cornell box, and the
 *                                reported memory against the packed bytes;
 *   vlf_storage_tests gpu        propagation by the GL compute passes
 *                                equals the CPU's (glossy Cornell box in
 *                                the three storage formats, a sky-lit
 *                                scene, a textured one with a double-sided
 *                                teapot). */
#include "vlf_field.h"
#include "vlf_gpu.h"
#include "vlf_test_util.h"

#include "gi/gpu.h"
#include "gi/shader.h"
#include "gi/scene.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

extern const gi_shader_source gi_vlf_shaders[];

/* Relative L1 difference of two maps of count RGB values: sum |a - b| / sum |b|. */
static double rel_l1(const float *a, const float *b, size_t count)
{
    double num = 0.0, den = 0.0;
    for (size_t k = 0; k < 3 * count; k++)
        num += fabs((double)a[k] - b[k]), den += fabs((double)b[k]);
    return den > 0.0 ? num / den : 0.0;
}

/* Storage precision (§3.1, §6): the encoders against known values and
 * their rounding bounds; the glossy Cornell box propagated with maps in
 * RGBA16F and RGB9E5 against float32 (irradiance atlas and non-diffuse
 * tiles, relative L1 within 0.2 % and 1 %; the black map scores 100 %);
 * the maps hold only values of their format, and their packed bytes are
 * the memory reported (8 and 4 bytes a value against 12). */
static void test_precision(void)
{
    float one[3] = {1.0f, 0.5f, 0.25f}, back[3];
    uint16_t h[4];
    vlf_pack(VLF_PREC_16F, one, 1, h);
    EXPECT(h[0] == 0x3c00 && h[1] == 0x3800 && h[2] == 0x3400 && h[3] == 0,
           "half of 1, 0.5, 0.25: %04x %04x %04x", h[0], h[1], h[2]);
    uint32_t w;
    vlf_pack(VLF_PREC_RGB9E5, one, 1, &w);
    vlf_unpack(VLF_PREC_RGB9E5, &w, 1, back);
    EXPECT(back[0] == 1.0f && back[1] == 0.5f && back[2] == 0.25f,
           "rgb9e5 of 1, 0.5, 0.25: %g %g %g", back[0], back[1], back[2]);
    float big[3] = {1e6f, 70000.0f, 0.0f};
    vlf_quantise(VLF_PREC_16F, big, 1);
    EXPECT(big[0] == 65504.0f && big[1] == 65504.0f && big[2] == 0.0f,
           "half clamps to 65504: %g %g", big[0], big[1]);
    uint32_t seed = 99u;
    double worst16 = 0.0, worst9 = 0.0;
    for (int q = 0; q < 100000; q++) {
        float v[3], a[3], b[3];
        for (int k = 0; k < 3; k++)
            v[k] = ldexpf(frand(&seed), (int)(frand(&seed) * 20.0f) - 10);
        memcpy(a, v, sizeof v);
        memcpy(b, v, sizeof v);
        vlf_quantise(VLF_PREC_16F, a, 1);
        vlf_quantise(VLF_PREC_RGB9E5, b, 1);
        float mx = fmaxf(v[0], fmaxf(v[1], v[2]));
        for (int k = 0; k < 3; k++) {
            if (v[k] >= ldexpf(1.0f, -14))
                worst16 = fmax(worst16, fabs(a[k] - v[k]) / v[k]);
            worst9 = fmax(worst9, fabs(b[k] - v[k]) / mx);
        }
    }
    printf("precision: largest rounding error, half %.3g of the value (bound 2^-11 = %.3g), rgb9e5 "
           "%.3g of the largest "
           "channel (bound 2^-9 = %.3g)\n",
           worst16, ldexp(1, -11), worst9, ldexp(1, -9));
    EXPECT(worst16 <= ldexp(1, -11) * 1.0001, "half rounding %.3g", worst16);
    EXPECT(worst9 <= ldexp(1, -9) * 1.0001, "rgb9e5 rounding %.3g", worst9);

    gi_scene *s = load("scenes/cornell_glossy.gltf");
    if (!s)
        return;
    vlf_field f[3];
    gi_error err;
    const char *name[3] = {"32f", "16f", "rgb9e5"};
    const double bound_E[3] = {0.0, 0.002, 0.01}, bound_T[3] = {0.0, 0.002, 0.01};
    int ok[3] = {0, 0, 0};
    for (uint32_t k = 0; k < 3; k++) {
        vlf_settings p = defaults();
        p.l = 32, p.N = 32, p.density = 8, p.iterations = 4, p.precision = k;
        ok[k] = vlf_field_build(&f[k], s, 0.0f, &p, &err) == GI_OK;
        EXPECT(ok[k], "%s", err.text);
        if (!ok[k])
            continue;
        vlf_field_propagate(&f[k], NULL, NULL, NULL);
        size_t bpv = vlf_precision_bytes(k), count = (size_t)f[k].elem_count + f[k].nd_cells;
        /* the maps as packed for rendering: the reported bytes, and nothing lost */
        uint8_t *buf = malloc(count * bpv + 1);
        float *un = malloc(count * 3 * sizeof *un + 1);
        vlf_pack(k, f[k].E_tot, f[k].elem_count, buf);
        vlf_pack(k, f[k].out_tot, f[k].nd_cells, buf + (size_t)f[k].elem_count * bpv);
        vlf_unpack(k, buf, f[k].elem_count, un);
        vlf_unpack(k, buf + (size_t)f[k].elem_count * bpv, f[k].nd_cells,
                   un + 3 * (size_t)f[k].elem_count);
        int exact = memcmp(un, f[k].E_tot, (size_t)f[k].elem_count * 3 * sizeof *un) == 0 &&
                    memcmp(un + 3 * (size_t)f[k].elem_count, f[k].out_tot,
                           (size_t)f[k].nd_cells * 3 * sizeof *un) == 0;
        EXPECT(exact, "%s: the maps hold values the format cannot store", name[k]);
        EXPECT(f[k].st.bytes_maps_render == count * bpv,
               "%s: reported %zu bytes for the maps, packed %zu", name[k],
               f[k].st.bytes_maps_render, count * bpv);
        free(buf);
        free(un);
        printf("precision %-6s: %u elements + %u tile cells, maps %zu bytes (%zu a value), "
               "propagation %zu bytes, "
               "rendering %zu bytes, propagate %.2f s",
               name[k], f[k].elem_count, f[k].nd_cells, f[k].st.bytes_maps_render, bpv,
               f[k].st.bytes_propagate, f[k].st.bytes_render, f[k].st.propagate_s);
        if (k > 0 && ok[0]) {
            double eE = rel_l1(f[k].E_tot, f[0].E_tot, f[k].elem_count);
            double eT = rel_l1(f[k].out_tot, f[0].out_tot, f[k].nd_cells);
            float *zero = calloc((size_t)f[0].elem_count * 3 + 1, sizeof *zero);
            double black = rel_l1(zero, f[0].E_tot, f[0].elem_count);
            free(zero);
            printf("; against 32f: irradiance %.4f %%, tiles %.4f %% (black: %.0f %%)", 100 * eE,
                   100 * eT, 100 * black);
            EXPECT(eE < bound_E[k], "%s: irradiance differs from 32f by %.3g", name[k], eE);
            EXPECT(eT < bound_T[k], "%s: tiles differ from 32f by %.3g", name[k], eT);
            EXPECT(f[k].nd_cells > 0 &&
                       f[0].st.bytes_maps_render * bpv == f[k].st.bytes_maps_render * 12,
                   "%s: map bytes not in the ratio %zu : 12", name[k], bpv);
        }
        printf("\n");
    }
    for (int k = 0; k < 3; k++)
        if (ok[k])
            vlf_field_free(&f[k]);
    gi_scene_free(s);
}

/* Propagation on the GPU (vlf_gpu.c): the same field propagated by the
 * CPU's sweeps and by the compute passes, on the glossy Cornell box (mirror
 * and glossy faces: sweeps, gathers, scattering) in the three storage
 * formats, on a sky-lit scene and on a textured one. The GPU's irradiance
 * atlas and tiles must lie within a relative L1 of 1e-4 (32f) / 2e-3 (16f, rgb9e5) of the
 * CPU's, and at least 10x closer than the CPU's own field one iteration
 * short (a wrong answer near the right one; the black map scores 100 %);
 * the flux counters agree within 1e-4. Prints both propagation times and
 * the GL renderer. */
static void gpu_case(vlf_gpu *gp, const char *scene, uint32_t prec, double bound)
{
    gi_scene *s = load(scene);
    if (!s)
        return;
    static const char *name[3] = {"32f", "16f", "rgb9e5"};
    vlf_settings p = defaults();
    p.l = 32, p.N = 32, p.density = 8, p.iterations = 4, p.precision = prec;
    vlf_field cpu, gpu, shortf;
    gi_error err;
    int ok = vlf_field_build(&cpu, s, 0.0f, &p, &err) == GI_OK;
    EXPECT(ok, "%s", err.text);
    ok = ok && vlf_field_build(&gpu, s, 0.0f, &p, &err) == GI_OK;
    EXPECT(ok, "%s", err.text);
    vlf_settings ps = p;
    ps.iterations = p.iterations - 1;
    ok = ok && vlf_field_build(&shortf, s, 0.0f, &ps, &err) == GI_OK;
    EXPECT(ok, "%s", err.text);
    if (!ok) {
        gi_scene_free(s);
        return;
    }
    EXPECT(vlf_field_propagate(&cpu, NULL, NULL, NULL) == GI_OK, "CPU propagation failed");
    EXPECT(vlf_field_propagate(&shortf, NULL, NULL, NULL) == GI_OK, "CPU propagation failed");
    vlf_gpu *g = gp;
    int gok = vlf_gpu_setup(g, &gpu, &err) == GI_OK;
    EXPECT(gok, "%s", err.text);
    if (gok) {
        gok = vlf_gpu_propagate(g, &gpu, NULL, NULL, &err) == GI_OK;
        EXPECT(gok, "%s", err.text);
    }
    if (gok) {
        double eE = rel_l1(gpu.E_tot, cpu.E_tot, cpu.elem_count);
        double eT = rel_l1(gpu.out_tot, cpu.out_tot, cpu.nd_cells);
        double sE = rel_l1(shortf.E_tot, cpu.E_tot, cpu.elem_count);
        double sT = cpu.nd_cells ? rel_l1(shortf.out_tot, cpu.out_tot, cpu.nd_cells) : 0.0;
        double dshot = fabs(gpu.st.flux_shot - cpu.st.flux_shot) / fmax(cpu.st.flux_shot, 1e-30);
        double drecv =
            fabs(gpu.st.flux_received - cpu.st.flux_received) / fmax(cpu.st.flux_received, 1e-30);
        printf("gpu %s %-6s: %u elements, %u tile cells; GPU against CPU: irradiance %.2e, tiles "
               "%.2e (one iteration "
               "short: %.2e, %.2e); shot %.2e, received %.2e; propagate CPU %.3f s, GPU %.3f s "
               "(set-up %.3f s, "
               "read-back %.3f s): CPU/GPU %.2f\n",
               scene, name[prec], cpu.elem_count, cpu.nd_cells, eE, eT, sE, sT, dshot, drecv,
               cpu.st.propagate_s, gpu.st.propagate_s, g->setup_s, g->readback_s,
               cpu.st.propagate_s / fmax(gpu.st.propagate_s + g->setup_s, 1e-9));
        EXPECT(eE < bound && eE * 10.0 < sE,
               "%s %s: GPU irradiance differs from the CPU's by %.3g (bound %.3g, "
               "one iteration short %.3g)",
               scene, name[prec], eE, bound, sE);
        if (cpu.nd_cells)
            EXPECT(eT < bound && eT * 10.0 < sT,
                   "%s %s: GPU tiles differ from the CPU's by %.3g (bound %.3g, one "
                   "iteration short %.3g)",
                   scene, name[prec], eT, bound, sT);
        EXPECT(dshot < 1e-4 && drecv < 1e-4, "%s: flux counters differ: shot %.3g, received %.3g",
               scene, dshot, drecv);
        EXPECT(gpu.st.samples == cpu.st.samples, "samples %llu vs %llu",
               (unsigned long long)gpu.st.samples, (unsigned long long)cpu.st.samples);
    }
    vlf_field_free(&cpu);
    vlf_field_free(&gpu);
    vlf_field_free(&shortf);
    gi_scene_free(s);
}

static void test_gpu(void)
{
    gi_error e;
    gi_gpu *ctx = gi_gpu_create(NULL, &e);
    EXPECT(ctx != NULL, "no GL context: %s", e.text);
    if (!ctx)
        return;
    EXPECT(gi_shader_register(gi_vlf_shaders, &e) == GI_OK, "shaders: %s", e.text);
    printf("gpu: GL renderer %s\n", gi_gpu_renderer(ctx));
    vlf_gpu g;
    gi_error err;
    int ok = vlf_gpu_init(&g, 0, VLF_SYNC_AUTO, &err) == GI_OK;
    EXPECT(ok, "%s", err.text);
    if (ok) {
        gpu_case(&g, "scenes/cornell_glossy.gltf", VLF_PREC_32F, 1e-4);
        gpu_case(&g, "scenes/cornell_glossy.gltf", VLF_PREC_16F, 2e-3);
        gpu_case(&g, "scenes/cornell_glossy.gltf", VLF_PREC_RGB9E5, 2e-3);
        gpu_case(&g, "scenes/bunny_alone_env.glb", VLF_PREC_32F, 1e-4);
        gpu_case(&g, "scenes/teapot_plane.glb", VLF_PREC_32F, 1e-4); /* a double-sided teapot */
        vlf_gpu_free(&g);
    }
    gi_gpu_destroy(ctx);
}

int main(int argc, char **argv)
{
    static const vlf_test_part parts[] = {{"precision", test_precision}, {"gpu", test_gpu}};
    return vlf_test_main("vlf_storage_tests", parts, sizeof parts / sizeof parts[0], argc, argv);
}
