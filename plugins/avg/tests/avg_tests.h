/* What the files of avg_tests share (avg_tests.c lists the subjects): a
 * minimal host and the fixtures that drive the method in-process
 * (avg_test_fixture.c), and each subject's entry point. check.h's counters
 * are shared by all the files. */
#ifndef AVG_TESTS_H
#define AVG_TESTS_H

#include "avg.h"

#include "gi/image.h"

/* Subjects (the ctest names integration.avg_<subject>): each runs its
 * cases and returns the failed checks so far (gi_test_failed). */
int avg_test_voxel(gi_gpu *gpu);
int avg_test_deform(gi_gpu *gpu);
int avg_test_march(gi_gpu *gpu);
int avg_test_vpls(gi_gpu *gpu);
int avg_test_shade(gi_gpu *gpu);
int avg_test_visibility(gi_gpu *gpu);
int avg_test_punctual(gi_gpu *gpu);

/* The view of the scene's first camera (or the default view) at time t,
 * seed 1. */
void avg_test_make_view(const gi_scene *s, float t, uint32_t w, uint32_t h, gi_view *v);

/* Creates and prepares an avg instance with "k=v" parameters. */
avg *avg_test_make_avg(const gi_host *host, const gi_gpu_scene *gs, const char *const *kv,
                       uint32_t n);

typedef struct avg_test_target {
    GLuint tex, fbo;
    uint32_t w, h;
} avg_test_target;

avg_test_target avg_test_make_target(uint32_t w, uint32_t h);
/* One frame of `a` into t; 0 after a message when render() fails. */
int avg_test_render(avg *a, const gi_view *v, const avg_test_target *t);

/* A scene loaded and uploaded at t = 0, with a host around it. */
typedef struct avg_test_fixture {
    gi_scene *s;
    gi_gpu_scene *gs;
    gi_host host;
} avg_test_fixture;

int avg_test_load_fixture(gi_gpu *gpu, const char *scene_path, avg_test_fixture *f);
void avg_test_free_fixture(avg_test_fixture *f);

/* Renders one w x h frame of `a` at t = 0 into a new target. */
avg_test_target avg_test_render_frame(avg *a, const gi_scene *s, uint32_t w, uint32_t h);

/* The G-buffer of the last frame of `a`, read back. */
typedef struct avg_test_gbuffer {
    gi_image *pos, *nrm, *alb, *emi;
} avg_test_gbuffer;

avg_test_gbuffer avg_test_read_gbuffer(const avg *a, uint32_t w, uint32_t h);
void avg_test_free_gbuffer(avg_test_gbuffer *g);

#endif
