/* Stage timers: nesting, recurring stages adding up, warm-up frames
 * dropped, median/min/max; the GL modes against a real context. */
#define _POSIX_C_SOURCE 200809L
#include "check.h"
#include "gi/gpu.h"
#include "gi/timer.h"

#include <string.h>
#include <stdlib.h>
#include <time.h>

static void sleep_ms(double ms)
{
    struct timespec ts = {0, (long)(ms * 1e6)};
    nanosleep(&ts, NULL);
}

static double cpu_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static const gi_stage_stats *find(const gi_stage_stats *st, uint32_t n, const char *name)
{
    for (uint32_t i = 0; i < n; i++)
        if (strcmp(st[i].name, name) == 0)
            return &st[i];
    return NULL;
}

int main(void)
{
    double v[5] = {5, 1, 4, 2, 3};
    CHECK(gi_median(v, 5) == 3.0);
    double w[4] = {4, 1, 3, 2};
    CHECK(gi_median(w, 4) == 2.5);

    gi_timer *t = gi_timer_create(GI_TIMER_CPU_ONLY, 1);
    for (int f = 0; f < 4; f++) {
        gi_timer_frame_begin(t);
        gi_timer_begin(t, "outer");
        gi_timer_begin(t, "inner");
        sleep_ms(f == 0 ? 30 : 4); /* the warm-up frame is slow and dropped */
        gi_timer_end(t, "inner");
        gi_timer_begin(t, "inner"); /* recurs: adds up within the frame */
        sleep_ms(2);
        gi_timer_end(t, "inner");
        gi_timer_end(t, "outer");
        gi_timer_frame_end(t);
    }
    gi_stage_stats st[8];
    uint32_t n = gi_timer_stats(t, st, 8);
    CHECK(n == 3);
    const gi_stage_stats *inner = find(st, n, "inner"), *outer = find(st, n, "outer"),
                         *frame = find(st, n, "frame");
    CHECK(inner && outer && frame);
    if (inner && outer && frame) {
        CHECK(inner->samples == 3 && outer->samples == 3 && frame->samples == 3);
        CHECK(inner->median_ms >= 6.0 && inner->max_ms < 25.0);
        CHECK(outer->median_ms >= inner->median_ms);
        CHECK(frame->median_ms >= outer->median_ms);
        CHECK(inner->min_ms <= inner->median_ms && inner->median_ms <= inner->max_ms);
    }
    uint32_t count = 0;
    CHECK(gi_timer_samples(t, "inner", &count) != NULL && count == 3);
    CHECK(gi_timer_samples(t, "nope", &count) == NULL && count == 0);
    gi_timer_free(t);

    /* With a GL context: both GL-backed modes time a compute-free wait. */
    gi_error err;
    gi_gpu *gpu = gi_gpu_create(NULL, &err);
    CHECK_MSG(gpu != NULL, "%s", err.text);
    if (gpu) {
        CHECK(gi_timer_mode_for(1) == GI_TIMER_CPU_FINISH || getenv("GIBENCH_TIMER"));
        gi_timer_mode modes[2] = {GI_TIMER_CPU_FINISH, GI_TIMER_GL_QUERY};
        GLuint buf;
        glCreateBuffers(1, &buf);
        glNamedBufferStorage(buf, 1 << 20, NULL, 0);
        for (int m = 0; m < 2; m++) {
            t = gi_timer_create(modes[m], 0);
            for (int f = 0; f < 3; f++) {
                gi_timer_frame_begin(t);
                gi_timer_begin(t, "clear");
                glClearNamedBufferData(buf, GL_R32F, GL_RED, GL_FLOAT, NULL);
                gi_timer_end(t, "clear");
                gi_timer_frame_end(t);
            }
            n = gi_timer_stats(t, st, 8);
            const gi_stage_stats *c = find(st, n, "clear");
            CHECK(c && c->samples == 3 && c->min_ms >= 0.0);
            printf("%s: clear median %.4f ms\n", gi_timer_mode_name(modes[m]),
                   c ? c->median_ms : -1.0);
            gi_timer_free(t);
        }
        glDeleteBuffers(1, &buf);
        /* CPU-time mode: a sleep costs (almost) nothing, busy work does. */
        t = gi_timer_create(GI_TIMER_CPU_TIME, 0);
        gi_timer_frame_begin(t);
        gi_timer_begin(t, "sleep");
        sleep_ms(50);
        gi_timer_end(t, "sleep");
        gi_timer_begin(t, "busy");
        volatile double acc = 0.0; /* spin until this process has used 30 ms of CPU */
        for (double c0 = cpu_seconds(); cpu_seconds() - c0 < 0.03;)
            acc += 1.0;
        gi_timer_end(t, "busy");
        gi_timer_frame_end(t);
        n = gi_timer_stats(t, st, 8);
        const gi_stage_stats *sl = find(st, n, "sleep"), *bu = find(st, n, "busy");
        CHECK_MSG(sl && sl->median_ms < 10.0, "a 50 ms sleep cost %.2f ms of CPU time",
                  sl ? sl->median_ms : -1.0);
        CHECK_MSG(bu && bu->median_ms > 25.0, "30 ms of busy work cost %.2f ms of CPU time",
                  bu ? bu->median_ms : -1.0);
        CHECK(strcmp(gi_timer_mode_name(GI_TIMER_CPU_TIME), "process-cpu-time-around-glFinish") ==
              0);
        gi_timer_free(t);
        CHECK(gi_gl_check("timer", &err) == GI_OK);
        gi_gpu_destroy(gpu);
    }
    return gi_test_finish();
}
