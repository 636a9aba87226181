/* Named stage timers.
 *
 * GPU time through GL_TIMESTAMP queries where the driver is trustworthy;
 * on software rasterisers (llvmpipe) GL_TIME_ELAPSED/GL_TIMESTAMP do not
 * measure compute work, so there each begin/end is a glFinish followed by a
 * CPU wall-clock read (CLOCK_MONOTONIC). The mode is chosen from the GL
 * renderer when the timer is created and reported in every result.
 *
 * A frame: gi_timer_frame_begin; any number of stage begin/end pairs (may
 * nest; a name that recurs adds up); gi_timer_frame_end resolves the
 * queries and appends one sample per stage, plus the whole frame as
 * "frame". Samples of the first `warmup` frames are dropped. Statistics
 * (median, min, max, mean) come from gi_timer_stats.
 */
#ifndef GI_TIMER_H
#define GI_TIMER_H

#include "gi/common.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum gi_timer_mode {
    GI_TIMER_GL_QUERY = 0,
    GI_TIMER_CPU_FINISH = 1, /* glFinish + wall clock */
    GI_TIMER_CPU_ONLY = 2,   /* wall clock, no GL (CPU-only work, tests) */
    /* glFinish + the process's CPU time (all its threads, llvmpipe's
     * workers included): the work done rather than the time waited, so
     * that ratios hold on a shared, oversubscribed machine. Software
     * renderers only (a GPU's work is not the process's CPU time). */
    GI_TIMER_CPU_TIME = 3,
} gi_timer_mode;

typedef struct gi_timer gi_timer;

#define GI_TIMER_MAX_STAGES 32
#define GI_TIMER_NAME_MAX 32

typedef struct gi_stage_stats {
    char name[GI_TIMER_NAME_MAX];
    uint32_t samples;
    double median_ms, min_ms, max_ms, mean_ms;
} gi_stage_stats;

gi_timer *gi_timer_create(gi_timer_mode mode, uint32_t warmup);
void gi_timer_free(gi_timer *t);
gi_timer_mode gi_timer_get_mode(const gi_timer *t);
const char *gi_timer_mode_name(gi_timer_mode mode);
/* Picks GI_TIMER_CPU_FINISH for software renderers, GL queries otherwise;
 * GIBENCH_TIMER=query|finish|cputime overrides. */
gi_timer_mode gi_timer_mode_for(int gl_is_software);
/* GI_OK when GIBENCH_TIMER is unset, empty or one of query, finish,
 * cputime; else GI_ERR_INVALID_ARGUMENT with a message listing them (a
 * misspelt mode would otherwise be ignored and time with the default). */
gi_result gi_timer_env_check(gi_error *err);

void gi_timer_frame_begin(gi_timer *t);
void gi_timer_frame_end(gi_timer *t);
void gi_timer_begin(gi_timer *t, const char *stage);
void gi_timer_end(gi_timer *t, const char *stage);
/* Stages in first-seen order; returns the count written (<= max). */
uint32_t gi_timer_stats(const gi_timer *t, gi_stage_stats *out, uint32_t max);
/* Per-frame samples of one stage in milliseconds (NULL if unknown). */
const double *gi_timer_samples(const gi_timer *t, const char *stage, uint32_t *count);

/* Monotonic wall clock in seconds. */
double gi_now(void);
/* Median of n doubles (the array is sorted in place). */
double gi_median(double *v, uint32_t n);

#ifdef __cplusplus
}
#endif
#endif
