/* The implicit_vis tests of the GPU illumination (iv_gpu.c, Sec. 4.3.1;
 * README "Tests"): the GPU gather and pull-up against iv_illuminate on
 * the same links, and the furnace with the illumination on the GPU. */
#include "iv_tests.h"
#include "iv_gpu.h"

#include "gi/shader.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

extern const gi_shader_source gi_implicit_vis_shaders[];

/* The GL context of the `gpu` part (NULL elsewhere). */
gi_gpu *iv_test_gl = NULL;

/* The GPU illumination of the links in l (the scene uploaded and its
 * punctual lights bound at t = 0; direct: NULL, or iv_lights.direct):
 * irradiance in iv_illuminate's layout.
 * Returns 0 (and counts a failure) when a step fails. */
int iv_test_gpu_illuminate(const gi_scene *s, const iv_hier *h, const iv_links *l, uint32_t bounces,
                           const float *direct, float *E)
{
    gi_error err;
    gi_gpu_scene *gs = gi_gpu_scene_upload(iv_test_gl, s, &err);
    EXPECT(gs != NULL, "upload: %s", err.text);
    if (!gs)
        return 0;
    gi_gpu_scene_set_time(gs, 0.0f);
    gi_gpu_scene_bind(gs);
    iv_gpu *g = iv_gpu_create(h, l, s->envmap, &err);
    EXPECT(g != NULL, "GPU illumination: %s", err.text);
    int ok = g != NULL;
    if (g) {
        gi_result r = iv_gpu_illuminate(g, l, h, bounces, s->light_count, direct, &err);
        EXPECT(r == GI_OK, "GPU illumination: %s", err.text);
        ok = r == GI_OK;
        if (ok)
            iv_gpu_read(g, E);
    }
    iv_gpu_free(g);
    gi_gpu_scene_free(gs);
    return ok;
}

/* One scene: the same links gathered by iv_illuminate and by the GPU
 * passes; their relative L1 difference (area-weighted, both sides, every
 * channel) must stay within `limit` (float summation order), and be far
 * below the difference one bounce makes, so that a missing or extra gather
 * could not pass. */
static void gpu_case(const char *path, uint32_t N, uint32_t bounces, int bilinear, float coverage,
                     double limit)
{
    iv_test_bilinear = bilinear;
    iv_test_coverage = coverage;
    iv_test_frame f;
    int ok = iv_test_frame_run(&f, path, 0.0f, N, bounces, 0, 1);
    EXPECT(ok, "set-up failed for %s", path);
    float *G = ok ? malloc((size_t)f.h->elem_count * 6 * sizeof(float)) : NULL;
    float *P = ok ? malloc((size_t)f.h->elem_count * 6 * sizeof(float)) : NULL;
    if (ok && G && P && iv_test_gpu_illuminate(f.s, f.h, f.l, bounces, NULL, G)) {
        iv_lights li = {f.s, 0.0f, f.s->envmap, NULL};
        if (bounces > 0)
            iv_illuminate(f.l, f.h, &li, bounces - 1,
                          P); /* one gather fewer: the answer to tell apart */
        else
            memset(P, 0, (size_t)f.h->elem_count * 6 * sizeof(float));
        double diff = 0.0, fewer = 0.0, sum = 0.0, worst = 0.0;
        for (uint32_t e = 0; e < f.h->elem_count; e++) {
            double a = f.h->area[f.h->elem_node[e]];
            for (int c = 0; c < 6; c++) {
                double d = fabs((double)G[6 * e + c] - f.E[6 * e + c]);
                diff += a * d;
                fewer += a * fabs((double)P[6 * e + c] - f.E[6 * e + c]);
                sum += a * fabs((double)f.E[6 * e + c]);
                worst = fmax(worst, d / (fabs((double)f.E[6 * e + c]) + 1e-3));
            }
        }
        double rel = sum > 0.0 ? diff / sum : 1.0, rel_fewer = sum > 0.0 ? fewer / sum : 0.0;
        printf("%s (N %u, %u bounces, weight %d, bilinear %d, coverage %.2g, %u discs): GPU "
               "against CPU relative L1 %.2e "
               "(limit %.0e), worst disc %.2e; one bounce fewer on the CPU %.2e\n",
               strrchr(path, '/') + 1, N, bounces, f.l->weight, bilinear, (double)coverage,
               f.h->elem_count, rel, limit, worst, rel_fewer);
        EXPECT(sum > 0.0, "%s: no light at all", path);
        EXPECT(rel <= limit, "%s: GPU and CPU differ by %.2e (limit %.0e)", path, rel, limit);
        EXPECT(rel_fewer >= 10.0 * limit,
               "%s: one bounce fewer differs by only %.2e: the test cannot tell", path, rel_fewer);
    }
    free(G);
    free(P);
    iv_test_frame_free(&f);
    iv_test_bilinear = 0;
    iv_test_coverage = 0.0f;
}

/* direct=traced (README "Traced direct light"): a given direct
 * irradiance replaces the first gather and stays out of the result, on
 * the CPU and on the GPU alike. Given: an arbitrary positive field over
 * the discs (the gather does not care where it came from). The two must
 * agree within `limit`, and differ from the paper's direct light along the
 * links by far more, so that a path that ignored the given light, or added
 * it to the result, could not pass. */
static void gpu_traced_case(const char *path, uint32_t N, uint32_t bounces, double limit)
{
    iv_test_frame f;
    int ok = iv_test_frame_run(&f, path, 0.0f, N, bounces, 0, 1);
    EXPECT(ok, "set-up failed for %s", path);
    size_t n = ok ? (size_t)f.h->elem_count * 6 : 0;
    float *D = ok ? malloc(n * sizeof(float)) : NULL, *G = ok ? malloc(n * sizeof(float)) : NULL;
    float *C = ok ? malloc(n * sizeof(float)) : NULL;
    if (ok && D && G && C) {
        for (uint32_t e = 0; e < f.h->elem_count; e++)
            for (int c = 0; c < 6; c++)
                D[6 * e + c] = c < 3 || f.h->elem_two_sided_emit[e]
                                   ? 1.0f + 0.5f * sinf(0.37f * (float)e + (float)c)
                                   : 0.0f;
        iv_lights li = {f.s, 0.0f, f.s->envmap, D};
        iv_illuminate(f.l, f.h, &li, bounces, C);
        if (iv_test_gpu_illuminate(f.s, f.h, f.l, bounces, D, G)) {
            double diff = 0.0, paper = 0.0, sum = 0.0;
            for (uint32_t e = 0; e < f.h->elem_count; e++) {
                double a = f.h->area[f.h->elem_node[e]];
                for (int c = 0; c < 6; c++) {
                    diff += a * fabs((double)G[6 * e + c] - C[6 * e + c]);
                    paper += a * fabs((double)f.E[6 * e + c] - C[6 * e + c]);
                    sum += a * fabs((double)C[6 * e + c]);
                }
            }
            double rel = sum > 0.0 ? diff / sum : 1.0, rel_paper = sum > 0.0 ? paper / sum : 0.0;
            printf("%s (N %u, %u bounces, traced direct light given): GPU against CPU relative L1 "
                   "%.2e (limit %.0e); the paper's direct light along the links differs by %.2e\n",
                   strrchr(path, '/') + 1, N, bounces, rel, limit, rel_paper);
            EXPECT(sum > 0.0, "%s: no indirect light at all", path);
            EXPECT(rel <= limit, "%s: traced, GPU and CPU differ by %.2e (limit %.0e)", path, rel,
                   limit);
            EXPECT(rel_paper >= 10.0 * limit,
                   "%s: the given direct light changes nothing (%.2e): the test cannot tell", path,
                   rel_paper);
        }
    }
    free(D), free(G), free(C);
    iv_test_frame_free(&f);
}

void iv_test_gpu(void)
{
    gi_error err;
    iv_test_gl = gi_gpu_create(NULL, &err);
    EXPECT(iv_test_gl != NULL, "no GL context: %s", err.text);
    if (!iv_test_gl)
        return;
    EXPECT(gi_shader_register(gi_implicit_vis_shaders, &err) == GI_OK, "shaders: %s", err.text);
    printf("GL renderer: %s\n", gi_gpu_renderer(iv_test_gl));
    const double limit = 1e-4;
    gpu_case(GI_SOURCE_DIR "/scenes/cornell_box.gltf", 12, 3, 0, 0.0f, limit);
    gpu_case(GI_SOURCE_DIR "/scenes/cornell_box.gltf", 8, 1, 1, 0.7f, limit);
    gpu_case(GI_SOURCE_DIR "/tests/data/conformance/furnace_050.gltf", 12, 3, 0, 0.0f, limit);
    /* the other weights (README "Weights"): the bin rule, and Eq. 4 over the
     * nearest surface, whose open share of a bin passes the environment */
    iv_test_weight = IV_WEIGHT_BIN;
    gpu_case(GI_SOURCE_DIR "/tests/data/conformance/one_object_area_point.gltf", 8, 1, 0, 0.0f,
             limit);
    iv_test_weight = IV_WEIGHT_SURFACE;
    gpu_case(GI_SOURCE_DIR "/tests/data/conformance/furnace_080.gltf", 8, 2, 0, 0.0f, limit);
    gpu_case(GI_SOURCE_DIR "/scenes/teapot_plane.glb", 8, 1, 0, 0.0f, limit);
    iv_test_weight = IV_WEIGHT_EQ5;
    gpu_case(GI_SOURCE_DIR "/scenes/teapot_plane.glb", 8, 1, 0, 0.0f, limit);
    gpu_traced_case(GI_SOURCE_DIR "/scenes/cornell_box.gltf", 8, 1, limit);
    iv_test_weight = IV_WEIGHT_SURFACE;
    gpu_traced_case(GI_SOURCE_DIR "/tests/data/truth/sphere_out_ds.gltf", 8, 1, limit);
    iv_test_weight = IV_WEIGHT_EQ5;
    /* the furnace through the GPU passes: Le sum rho^k within 2 % */
    iv_test_furnace();
    gi_gpu_destroy(iv_test_gl);
    iv_test_gl = NULL;
}
