/* What the implicit_vis test files share (iv_tests.c holds main() and
 * these helpers; each part's file is listed there): loading a scene, the
 * link modes, one frame of the CPU stages, the GPU illumination, the
 * hierarchy checks, and every part's entry point. */
#ifndef IV_TESTS_H
#define IV_TESTS_H

#include "iv.h"

#include "gi/gpu.h"

#include "check.h"
#define EXPECT CHECK_MSG

/* ---- iv_tests.c ---- */

gi_scene *iv_test_load(const char *path);

/* The link modes iv_test_modes sets (iv_tests.c). */
extern int iv_test_bilinear;
extern int iv_test_weight; /* IV_WEIGHT_* */
extern float iv_test_coverage;
void iv_test_modes(iv_links *l);

extern int iv_test_remesher;

/* One frame of the CPU stages at t = 0, direct light and `bounces`. */
typedef struct iv_test_frame {
    gi_scene *s;
    iv_hier *h;
    iv_links *l;
    float *E;
} iv_test_frame;

int iv_test_frame_run(iv_test_frame *f, const char *path, float edge, uint32_t N, uint32_t bounces,
                      int brute, int splat);
void iv_test_frame_free(iv_test_frame *f);

/* ---- iv_tests_gpu.c ---- */

extern gi_gpu *iv_test_gl;
int iv_test_gpu_illuminate(const gi_scene *s, const iv_hier *h, const iv_links *l, uint32_t bounces,
                           const float *direct, float *E);

/* ---- iv_tests_structure.c ---- */

void iv_test_check_hierarchy(const iv_hier *h, const gi_scene *s, float t, const char *what,
                             double area_tol);

/* ---- the parts (iv_tests <part>) ---- */

void iv_test_bins(void);
void iv_test_hierarchy(void);
void iv_test_links(void);
void iv_test_furnace(void);
void iv_test_direct(void);
void iv_test_brute(void);
void iv_test_leak(void);
void iv_test_remesh(void);
void iv_test_threads(void);
void iv_test_gpu(void);
void iv_test_layout(void);

#endif
