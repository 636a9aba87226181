/* Named stage timers (see timer.h): GL timestamp queries, or glFinish +
 * wall clock on software renderers where GL timers are wrong for compute. */
#define _POSIX_C_SOURCE 200809L
#include "gi/timer.h"
#include "gi/log.h"

#include <epoxy/gl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define MAX_OPEN 64

typedef struct stage {
    char name[GI_TIMER_NAME_MAX];
    double frame_ms; /* accumulated within the current frame */
    int used;        /* seen in the current frame */
    double *samples;
    uint32_t count, cap;
} stage;

/* A begin or end mark of the current frame: a GL query or a CPU time. */
typedef struct mark {
    int stage;
    int is_end;
    GLuint query;
    double cpu;
} mark;

struct gi_timer {
    gi_timer_mode mode;
    uint32_t warmup, frames;
    stage stages[GI_TIMER_MAX_STAGES + 1]; /* last one is "frame" */
    uint32_t stage_count;
    mark *marks;
    uint32_t mark_count, mark_cap;
    GLuint *pool;
    uint32_t pool_count;
    double frame_start;
    GLuint frame_query[2];
    int in_frame;
};

double gi_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

double gi_median(double *v, uint32_t n)
{
    if (n == 0)
        return 0.0;
    qsort(v, n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

const char *gi_timer_mode_name(gi_timer_mode mode)
{
    switch (mode) {
    case GI_TIMER_GL_QUERY:
        return "gl-timestamp-query";
    case GI_TIMER_CPU_FINISH:
        return "cpu-wall-clock-around-glFinish";
    case GI_TIMER_CPU_ONLY:
        return "cpu-wall-clock";
    case GI_TIMER_CPU_TIME:
        return "process-cpu-time-around-glFinish";
    }
    return "?";
}

gi_timer_mode gi_timer_mode_for(int gl_is_software)
{
    const char *env = getenv("GIBENCH_TIMER");
    if (env && strcmp(env, "query") == 0)
        return GI_TIMER_GL_QUERY;
    if (env && strcmp(env, "finish") == 0)
        return GI_TIMER_CPU_FINISH;
    if (env && strcmp(env, "cputime") == 0)
        return GI_TIMER_CPU_TIME;
    return gl_is_software ? GI_TIMER_CPU_FINISH : GI_TIMER_GL_QUERY;
}

gi_result gi_timer_env_check(gi_error *err)
{
    const char *env = getenv("GIBENCH_TIMER");
    if (!env || !*env || !strcmp(env, "query") || !strcmp(env, "finish") || !strcmp(env, "cputime"))
        return GI_OK;
    return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                        "GIBENCH_TIMER='%.64s' is not a timer mode: query, finish or cputime", env);
}

gi_timer *gi_timer_create(gi_timer_mode mode, uint32_t warmup)
{
    gi_timer *t = calloc(1, sizeof *t);
    if (!t)
        return NULL;
    t->mode = mode;
    t->warmup = warmup;
    if (mode == GI_TIMER_GL_QUERY)
        glCreateQueries(GL_TIMESTAMP, 2, t->frame_query);
    return t;
}

void gi_timer_free(gi_timer *t)
{
    if (!t)
        return;
    for (uint32_t i = 0; i <= GI_TIMER_MAX_STAGES; i++)
        free(t->stages[i].samples);
    if (t->mode == GI_TIMER_GL_QUERY) {
        if (t->pool_count)
            glDeleteQueries((GLsizei)t->pool_count, t->pool);
        glDeleteQueries(2, t->frame_query);
    }
    free(t->pool);
    free(t->marks);
    free(t);
}

gi_timer_mode gi_timer_get_mode(const gi_timer *t)
{
    return t->mode;
}

static int find_stage(gi_timer *t, const char *name, int create)
{
    for (uint32_t i = 0; i < t->stage_count; i++)
        if (strncmp(t->stages[i].name, name, GI_TIMER_NAME_MAX - 1) == 0)
            return (int)i;
    if (!create || t->stage_count >= GI_TIMER_MAX_STAGES)
        return -1;
    stage *s = &t->stages[t->stage_count];
    snprintf(s->name, sizeof s->name, "%s", name);
    return (int)t->stage_count++;
}

static double cpu_mark(const gi_timer *t)
{
    if (t->mode == GI_TIMER_CPU_FINISH || t->mode == GI_TIMER_CPU_TIME)
        glFinish();
    if (t->mode == GI_TIMER_CPU_TIME) {
        struct timespec ts;
        clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
        return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
    }
    return gi_now();
}

static void add_mark(gi_timer *t, int stage_index, int is_end)
{
    if (t->mark_count == t->mark_cap) {
        uint32_t cap = t->mark_cap ? t->mark_cap * 2 : 64;
        mark *m = realloc(t->marks, cap * sizeof *m);
        if (!m)
            return;
        t->marks = m;
        t->mark_cap = cap;
    }
    mark *m = &t->marks[t->mark_count];
    m->stage = stage_index;
    m->is_end = is_end;
    m->query = 0;
    m->cpu = 0.0;
    if (t->mode == GI_TIMER_GL_QUERY) {
        if (t->mark_count >= t->pool_count) {
            uint32_t n = t->mark_cap;
            GLuint *p = realloc(t->pool, n * sizeof *p);
            if (!p)
                return;
            t->pool = p;
            glCreateQueries(GL_TIMESTAMP, (GLsizei)(n - t->pool_count), t->pool + t->pool_count);
            t->pool_count = n;
        }
        m->query = t->pool[t->mark_count];
        glQueryCounter(m->query, GL_TIMESTAMP);
    } else {
        m->cpu = cpu_mark(t);
    }
    t->mark_count++;
}

void gi_timer_frame_begin(gi_timer *t)
{
    t->mark_count = 0;
    for (uint32_t i = 0; i < t->stage_count; i++) {
        t->stages[i].frame_ms = 0.0;
        t->stages[i].used = 0;
    }
    t->in_frame = 1;
    if (t->mode == GI_TIMER_GL_QUERY)
        glQueryCounter(t->frame_query[0], GL_TIMESTAMP);
    else
        t->frame_start = cpu_mark(t);
}

void gi_timer_begin(gi_timer *t, const char *name)
{
    int s = find_stage(t, name, 1);
    if (s < 0) {
        gi_log(GI_LOG_WARN, "timer: too many stages, '%s' not timed", name);
        return;
    }
    add_mark(t, s, 0);
}

void gi_timer_end(gi_timer *t, const char *name)
{
    int s = find_stage(t, name, 0);
    if (s < 0) {
        gi_log(GI_LOG_WARN, "timer: end of stage '%s' that never began", name);
        return;
    }
    add_mark(t, s, 1);
}

static void push_sample(stage *s, double ms)
{
    if (s->count == s->cap) {
        uint32_t cap = s->cap ? s->cap * 2 : 16;
        double *p = realloc(s->samples, cap * sizeof *p);
        if (!p)
            return;
        s->samples = p;
        s->cap = cap;
    }
    s->samples[s->count++] = ms;
}

/* Time of mark i in ms relative to an arbitrary origin. */
static double mark_ms(const gi_timer *t, const mark *m)
{
    if (t->mode == GI_TIMER_GL_QUERY) {
        GLuint64 ns = 0;
        glGetQueryObjectui64v(m->query, GL_QUERY_RESULT, &ns);
        return (double)ns * 1e-6;
    }
    return m->cpu * 1e3;
}

void gi_timer_frame_end(gi_timer *t)
{
    double frame_ms;
    if (t->mode == GI_TIMER_GL_QUERY) {
        glQueryCounter(t->frame_query[1], GL_TIMESTAMP);
        GLuint64 a = 0, b = 0;
        glGetQueryObjectui64v(t->frame_query[0], GL_QUERY_RESULT, &a);
        glGetQueryObjectui64v(t->frame_query[1], GL_QUERY_RESULT, &b);
        frame_ms = (double)(b - a) * 1e-6;
    } else {
        frame_ms = (cpu_mark(t) - t->frame_start) * 1e3;
    }
    /* Pair each end with the latest unmatched begin of the same stage. */
    double open[MAX_OPEN];
    int open_stage[MAX_OPEN], depth = 0;
    for (uint32_t i = 0; i < t->mark_count; i++) {
        const mark *m = &t->marks[i];
        double ms = mark_ms(t, m);
        if (!m->is_end) {
            if (depth < MAX_OPEN) {
                open[depth] = ms;
                open_stage[depth++] = m->stage;
            }
            continue;
        }
        for (int d = depth - 1; d >= 0; d--)
            if (open_stage[d] == m->stage) {
                t->stages[m->stage].frame_ms += ms - open[d];
                t->stages[m->stage].used = 1;
                memmove(open + d, open + d + 1, (size_t)(depth - d - 1) * sizeof *open);
                memmove(open_stage + d, open_stage + d + 1,
                        (size_t)(depth - d - 1) * sizeof *open_stage);
                depth--;
                break;
            }
    }
    t->in_frame = 0;
    if (t->frames++ < t->warmup)
        return;
    for (uint32_t i = 0; i < t->stage_count; i++)
        if (t->stages[i].used)
            push_sample(&t->stages[i], t->stages[i].frame_ms);
    stage *f = &t->stages[GI_TIMER_MAX_STAGES];
    snprintf(f->name, sizeof f->name, "frame");
    push_sample(f, frame_ms);
}

static void fill_stats(const stage *s, gi_stage_stats *out)
{
    memset(out, 0, sizeof *out);
    snprintf(out->name, sizeof out->name, "%s", s->name);
    out->samples = s->count;
    if (!s->count)
        return;
    double *v = malloc(s->count * sizeof *v);
    if (!v)
        return;
    memcpy(v, s->samples, s->count * sizeof *v);
    double sum = 0;
    for (uint32_t i = 0; i < s->count; i++)
        sum += v[i];
    out->median_ms = gi_median(v, s->count);
    out->min_ms = v[0];
    out->max_ms = v[s->count - 1];
    out->mean_ms = sum / s->count;
    free(v);
}

uint32_t gi_timer_stats(const gi_timer *t, gi_stage_stats *out, uint32_t max)
{
    uint32_t n = 0;
    for (uint32_t i = 0; i < t->stage_count && n < max; i++)
        if (t->stages[i].count)
            fill_stats(&t->stages[i], &out[n++]);
    if (n < max && t->stages[GI_TIMER_MAX_STAGES].count)
        fill_stats(&t->stages[GI_TIMER_MAX_STAGES], &out[n++]);
    return n;
}

const double *gi_timer_samples(const gi_timer *t, const char *name, uint32_t *count)
{
    for (uint32_t i = 0; i <= GI_TIMER_MAX_STAGES; i++)
        if (t->stages[i].count && strcmp(t->stages[i].name, name) == 0) {
            *count = t->stages[i].count;
            return t->stages[i].samples;
        }
    *count = 0;
    return NULL;
}
