/* avg_tests shade: interleaved shading (Bashford-Rogers et al. 2011 §III-C)
 * with M = 1 equals the plain sum over all VPLs computed on the CPU from
 * the G-buffer (no visibility), and M = 16 (and 9) without the filter
 * equals M times the sum over each pixel's own subset. */
#include "avg_tests.h"

#include <math.h>
#include <stdio.h>

/* EXPECT(cond, fmt, ...): CHECK_MSG of the unit tests' check.h, which
 * counts failures in gi_test_failed (this file's). */
#include "check.h"
#define EXPECT CHECK_MSG

static void shade_case(gi_gpu *gpu, int M, int filter)
{
    avg_test_fixture fx;
    if (!avg_test_load_fixture(gpu, GI_SOURCE_DIR "/scenes/cornell_box.gltf", &fx))
        return;
    const gi_scene *s = fx.s;
    gi_gpu_scene *gs = fx.gs;
    char m_kv[16], f_kv[16];
    snprintf(m_kv, sizeof m_kv, "M=%d", M);
    snprintf(f_kv, sizeof f_kv, "filter=%d", filter);
    const char *kv[] = {"vpls=256", "grid=32", m_kv, f_kv, "visibility=false"};
    avg *a = avg_test_make_avg(&fx.host, gs, kv, 5);
    if (!a) {
        EXPECT(0, "cannot make the avg instance");
        return;
    }
    uint32_t w = 30, h = 26; /* not multiples of 4: partial sub-images */
    avg_test_target t = avg_test_render_frame(a, s, w, h);
    gi_image *img = gi_gpu_read_texture(t.tex, w, h);
    avg_test_gbuffer gb = avg_test_read_gbuffer(a, w, h);
    const gi_image *pos = gb.pos, *nrm = gb.nrm, *alb = gb.alb, *emi = gb.emi;
    float dmin = a->clamp * a->grid->h;
    double worst = 0.0;
    uint32_t lit = 0;
    for (uint32_t row = 0; row < h; row++) {
        uint32_t gl_row = h - 1 - row; /* images are top row first; subsets follow GL rows */
        for (uint32_t col = 0; col < w; col++) {
            size_t i = 4 * ((size_t)row * w + col);
            if (pos->rgba[i + 3] <= 0.0f)
                continue;
            uint32_t m = (gl_row % (uint32_t)a->mx) * (uint32_t)a->mx + col % (uint32_t)a->mx;
            float n[3] = {nrm->rgba[i], nrm->rgba[i + 1], nrm->rgba[i + 2]};
            float ln = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            for (int c = 0; c < 3; c++)
                n[c] /= ln;
            double S[3] = {0, 0, 0};
            for (uint32_t j = M == 1 ? 0 : m; j < a->vpl_count; j += (uint32_t)M) {
                float c3[3];
                avg_vpl_contribution(&a->cpu_vpls[j], &pos->rgba[i], n, dmin * dmin, c3);
                for (int c = 0; c < 3; c++)
                    S[c] += c3[c];
            }
            for (int c = 0; c < 3; c++) {
                double expect = emi->rgba[i + c] + alb->rgba[i + c] / GI_PI * S[c] * M;
                double got = img->rgba[i + c];
                double rel = fabs(got - expect) / (fabs(expect) + 1e-3);
                worst = rel > worst ? rel : worst;
            }
            lit++;
        }
    }
    printf("shade M=%d filter=%d: %u pixels, %u VPLs, largest relative difference to the CPU sum "
           "%.2e\n",
           M, filter, lit, a->vpl_count, worst);
    EXPECT(lit > w * h / 2, "only %u pixels hit the scene", lit);
    EXPECT(worst < 1e-3, "GPU shading differs from the CPU sum by %.3g (relative)", worst);
    gi_image_free(img);
    avg_test_free_gbuffer(&gb);
    gi_method_entry(GI_ABI_VERSION)->destroy(a);
    avg_test_free_fixture(&fx);
}

int avg_test_shade(gi_gpu *gpu)
{
    shade_case(gpu, 1, 1);
    shade_case(gpu, 16, 0);
    shade_case(gpu, 9, 0);
    return gi_test_failed;
}
