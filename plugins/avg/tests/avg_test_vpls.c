/* avg_tests vpls: the VPLs of the light paths (Bashford-Rogers et al. 2011
 * §III-B): the VPL set of two frames of a static scene is identical; it
 * changes when the scene moves and comes back when the scene does; the
 * light VPLs of AVG and exact tracing agree (same quasi-random numbers). */
#include "avg_tests.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* EXPECT(cond, fmt, ...): CHECK_MSG of the unit tests' check.h, which
 * counts failures in gi_test_failed (this file's). */
#include "check.h"
#define EXPECT CHECK_MSG

static void vpls_case(gi_gpu *gpu)
{
    avg_test_fixture fx;
    if (!avg_test_load_fixture(gpu, GI_SOURCE_DIR "/scenes/cornell_moving.gltf", &fx))
        return;
    const gi_scene *s = fx.s;
    gi_gpu_scene *gs = fx.gs;
    const char *kv[] = {"vpls=512", "grid=32", "M=4"};
    avg *a = avg_test_make_avg(&fx.host, gs, kv, 3);
    const char *kx[] = {"vpls=512", "grid=32", "M=4", "tracing=exact"};
    avg *x = avg_test_make_avg(&fx.host, gs, kx, 4);
    if (!a || !x) {
        EXPECT(0, "cannot make the avg instances");
        return;
    }
    avg_test_target t = avg_test_make_target(32, 32);
    gi_view v;
    avg_test_make_view(s, 0.0f, 32, 32, &v);
    size_t bytes = a->slots * sizeof(avg_vpl);
    avg_vpl *first = malloc(bytes), *moved = malloc(bytes);
    EXPECT(avg_test_render(a, &v, &t), "frame 1");
    memcpy(first, a->cpu_slots, bytes);
    uint32_t live = a->vpl_count;
    EXPECT(avg_test_render(a, &v, &t), "frame 2");
    EXPECT(memcmp(first, a->cpu_slots, bytes) == 0,
           "the VPL slots differ between two frames of a still scene");
    EXPECT(a->vpl_count == live && live > a->paths, "live VPLs %u then %u (paths %u)", live,
           a->vpl_count, a->paths);
    /* The bunny moves: the VPLs that hit it move too; back at t = 0 they return. */
    gi_gpu_scene_set_time(gs, 1.3f);
    gi_changes ch = {GI_CHANGED_TRANSFORMS, 1.3f, ~0ull};
    gi_method_entry(GI_ABI_VERSION)->update(a, gs, &ch);
    avg_test_make_view(s, 1.3f, 32, 32, &v);
    EXPECT(avg_test_render(a, &v, &t), "moved frame");
    memcpy(moved, a->cpu_slots, bytes);
    EXPECT(memcmp(first, moved, bytes) != 0, "the VPLs did not change when the bunny moved");
    gi_gpu_scene_set_time(gs, 0.0f);
    avg_test_make_view(s, 0.0f, 32, 32, &v);
    EXPECT(avg_test_render(a, &v, &t), "frame back at t = 0");
    EXPECT(memcmp(first, a->cpu_slots, bytes) == 0,
           "the VPLs at t = 0 differ after the scene moved and came back");

    /* AVG and exact tracing share the light VPLs (slot 0 of every path):
     * same light choice, same quasi-random numbers, same emitter records. */
    EXPECT(avg_test_render(x, &v, &t), "exact frame");
    uint32_t stride = (uint32_t)a->bounces + 1, same = 0, hits_a = 0, hits_x = 0;
    double pow_a = 0, pow_x = 0;
    for (uint32_t i = 0; i < a->paths; i++) {
        const avg_vpl *va = &first[i * stride], *vx = &x->cpu_slots[i * stride];
        float dmax = 0.0f;
        for (int c = 0; c < 3; c++) {
            dmax = fmaxf(dmax, fabsf(va->position[c] - vx->position[c]));
            dmax = fmaxf(dmax, fabsf(va->power[c] - vx->power[c]) /
                                   fmaxf(fabsf(vx->power[c]), 1e-6f) * 1e-2f);
        }
        same += dmax < 1e-4f && va->kind == vx->kind;
        for (uint32_t k = 1; k < stride; k++) {
            hits_a += first[i * stride + k].power[0] > 0.0f;
            hits_x += x->cpu_slots[i * stride + k].power[0] > 0.0f;
            pow_a += gi_luminance(first[i * stride + k].power);
            pow_x += gi_luminance(x->cpu_slots[i * stride + k].power);
        }
    }
    printf("vpls: %u slots, %u live; light VPLs equal in AVG and exact tracing: %u of %u; bounce "
           "VPLs %u (AVG) vs "
           "%u (exact), their total power %.4g vs %.4g (%+.1f %%)\n",
           a->slots, live, same, a->paths, hits_a, hits_x, pow_a, pow_x,
           100.0 * (pow_a - pow_x) / pow_x);
    EXPECT(same == a->paths, "only %u of %u light VPLs agree between AVG and exact tracing", same,
           a->paths);
    EXPECT(fabs(pow_a - pow_x) < 0.25 * pow_x, "bounce VPL power differs by more than 25 %%");
    const gi_method *m = gi_method_entry(GI_ABI_VERSION);
    m->destroy(a);
    m->destroy(x);
    free(first);
    free(moved);
    avg_test_free_fixture(&fx);
}

int avg_test_vpls(gi_gpu *gpu)
{
    vpls_case(gpu);
    return gi_test_failed;
}
