/* The reference renderer around the path integrator: progressive passes
 * over the image by a pool of pthreads working through 8x8 tiles, and the
 * per-pixel accumulation of mean and variance in double.
 *
 * Determinism: a pixel belongs to one tile and a tile to one thread per
 * pass; within the pixel, samples are added in sample order, each from its
 * own stream gi_rng_init(pixel, sample, seed). The sums after N samples are
 * thus the same bits for any thread count and any split into passes. */
#define _POSIX_C_SOURCE 200809L
#include "gi/limits.h"
#include "ref_internal.h"

#include "gi/timer.h"
#include "gi/rng.h"

#include <assert.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#define TILE 8
#define MAX_THREADS 1024

/* Per pixel: sum of R, G, B; sum of their squares; sum of squared
 * luminance; number of finite samples. */
enum { ACC_SUM = 0, ACC_SQ = 3, ACC_LUM_SQ = 6, ACC_N = 7, ACC_SIZE = 8 };

struct gi_ref {
    ref_scene rs;
    uint32_t threads;
    double *acc;
    uint64_t spp;
    uint64_t nonfinite, rays;
    double build_seconds, render_seconds, render_cpu_seconds;
    char renderer[64];
};

/* Rec. 709 luminance in double, the weights of gi_luminance. */
static inline double lum_d(double r, double g, double b)
{
    return 0.2126 * r + 0.7152 * g + 0.0722 * b;
}

void gi_ref_desc_init(gi_ref_desc *d)
{
    assert(d);
    memset(d, 0, sizeof *d);
    d->seed = 1;
    d->max_bounces = GI_REF_UNLIMITED;
    d->strategy = GI_REF_STRATEGY_MIS;
}

const char *gi_ref_strategy_name(gi_ref_strategy s)
{
    switch (s) {
    case GI_REF_STRATEGY_MIS:
        return "mis";
    case GI_REF_STRATEGY_LIGHT:
        return "light";
    case GI_REF_STRATEGY_BSDF:
        return "bsdf";
    }
    return "?";
}

int gi_ref_strategy_parse(const char *name)
{
    for (int s = GI_REF_STRATEGY_MIS; s <= GI_REF_STRATEGY_BSDF; s++)
        if (name && strcmp(name, gi_ref_strategy_name((gi_ref_strategy)s)) == 0)
            return s;
    return -1;
}

/* Worker threads when none are asked for: the CPUs a Slurm job was given
 * (SLURM_CPUS_PER_TASK; a batch node has more cores than the job may use),
 * else every online CPU. */
static uint32_t default_threads(void)
{
    const char *slurm = getenv("SLURM_CPUS_PER_TASK");
    char *end = NULL;
    long n = slurm && *slurm ? strtol(slurm, &end, 10) : 0;
    if (!end || *end != '\0' || n <= 0)
        n = sysconf(_SC_NPROCESSORS_ONLN);
    return n > 0 ? (uint32_t)(n < MAX_THREADS ? n : MAX_THREADS) : 1u;
}

gi_result gi_ref_create(const gi_ref_desc *d, gi_ref **out, gi_error *err)
{
    assert(d && out);
    *out = NULL;
    if (!d->scene)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "reference: no scene");
    if (!gi_image_size_ok(d->width, d->height))
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "reference: size %ux%u is not " GI_IMAGE_SIZE_RULE, d->width,
                            d->height);
    if (d->max_bounces < GI_REF_UNLIMITED)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "reference: max_bounces %d is below -1 (unlimited)", d->max_bounces);
    if ((int)d->strategy < GI_REF_STRATEGY_MIS || (int)d->strategy > GI_REF_STRATEGY_BSDF)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "reference: unknown strategy %d",
                            (int)d->strategy);
    if (d->threads > MAX_THREADS)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "reference: %u threads exceed %d",
                            d->threads, MAX_THREADS);
    double t0 = gi_now();
    gi_ref *r = calloc(1, sizeof *r);
    if (!r)
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "reference: out of memory");
    r->acc = calloc((size_t)d->width * d->height * ACC_SIZE, sizeof(double));
    if (!r->acc) {
        free(r);
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY,
                            "reference: out of memory (%ux%u accumulation buffer)", d->width,
                            d->height);
    }
    gi_result res = ref_scene_build(&r->rs, d, err);
    if (res != GI_OK) {
        gi_ref_free(r);
        return res;
    }
    r->threads = d->threads ? d->threads : default_threads();
    snprintf(r->renderer, sizeof r->renderer, "%s cpu", gi_rt_version(r->rs.rt));
    r->build_seconds = gi_now() - t0;
    *out = r;
    return GI_OK;
}

void gi_ref_free(gi_ref *r)
{
    if (!r)
        return;
    ref_scene_release(&r->rs);
    free(r->acc);
    free(r);
}

/* ---- passes ---------------------------------------------------------- */

typedef struct pass {
    gi_ref *r;
    uint32_t first_sample, spp;
    uint32_t tiles_x, tile_count;
    atomic_uint next_tile;
} pass;

typedef struct worker {
    pass *job;
    pthread_t thread;
    uint64_t nonfinite;
    ref_counters counters;
} worker;

/* Camera rays traced together (gi_rt_intersect8_tuv). */
#define PACKET 8

static void render_tile(pass *job, uint32_t tile, worker *w)
{
    gi_ref *r = job->r;
    const ref_scene *rs = &r->rs;
    uint32_t x0 = (tile % job->tiles_x) * TILE, y0 = (tile / job->tiles_x) * TILE;
    uint32_t x1 = x0 + TILE < rs->width ? x0 + TILE : rs->width;
    uint32_t y1 = y0 + TILE < rs->height ? y0 + TILE : rs->height;
    for (uint32_t y = y0; y < y1; y++)
        for (uint32_t x = x0; x < x1; x++) {
            uint32_t pixel = y * rs->width + x;
            double *a = r->acc + (size_t)pixel * ACC_SIZE;
            /* A pixel's samples 8 at a time: their camera rays start at
             * the eye and point alike, so they are traced as one packet
             * (Embree's coherent packet traversal); each path then goes on
             * by itself. Every sample keeps its own random stream, so the
             * image does not depend on the grouping. */
            for (uint32_t k0 = 0; k0 < job->spp; k0 += PACKET) {
                uint32_t n = job->spp - k0 < PACKET ? job->spp - k0 : PACKET;
                uint32_t rng[PACKET];
                ref_ray ray[PACKET];
                gi_vec3 o[PACKET], d[PACKET];
                float tn[PACKET], tf[PACKET], t[PACKET], u[PACKET], v[PACKET];
                uint32_t prim[PACKET];
                int hit[PACKET];
                for (uint32_t i = 0; i < n; i++) {
                    rng[i] = gi_rng_init(pixel, job->first_sample + k0 + i, rs->seed);
                    ref_camera_ray(rs, x, y, &rng[i], &ray[i]);
                    o[i] = ray[i].o, d[i] = ray[i].d, tn[i] = ray[i].tnear, tf[i] = ray[i].tfar;
                }
                gi_rt_intersect8_tuv(rs->rt, n, o, d, tn, tf, hit, t, u, v, prim);
                for (uint32_t i = 0; i < n; i++) {
                    ref_hit first = {t[i], u[i], v[i], prim[i]};
                    float L[3];
                    ref_path_trace(rs, &ray[i], &first, hit[i], &rng[i], L, &w->counters);
                    if (!isfinite(L[0]) || !isfinite(L[1]) || !isfinite(L[2])) {
                        w->nonfinite++;
                        continue;
                    }
                    double l = lum_d(L[0], L[1], L[2]);
                    for (int c = 0; c < 3; c++) {
                        a[ACC_SUM + c] += L[c];
                        a[ACC_SQ + c] += (double)L[c] * L[c];
                    }
                    a[ACC_LUM_SQ] += l * l;
                    a[ACC_N] += 1.0;
                }
            }
        }
}

static void *work(void *arg)
{
    worker *w = arg;
    pass *job = w->job;
    for (;;) {
        unsigned t = atomic_fetch_add(&job->next_tile, 1u);
        if (t >= job->tile_count)
            break;
        render_tile(job, t, w);
    }
    return NULL;
}

/* CPU time of the whole process (all its threads), in seconds. */
static double process_cpu_seconds(void)
{
    struct timespec ts;
    if (clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts) != 0)
        return 0.0;
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

gi_result gi_ref_render(gi_ref *r, uint32_t spp, gi_error *err)
{
    assert(r);
    if (spp == 0)
        return GI_OK;
    if (r->spp + spp > 0xFFFFFFFFull)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "reference: more than 2^32 - 1 samples per pixel");
    double t0 = gi_now(), c0 = process_cpu_seconds();
    pass job;
    job.r = r;
    job.first_sample = (uint32_t)r->spp;
    job.spp = spp;
    job.tiles_x = (r->rs.width + TILE - 1) / TILE;
    job.tile_count = job.tiles_x * ((r->rs.height + TILE - 1) / TILE);
    atomic_init(&job.next_tile, 0u);
    uint32_t n = r->threads < job.tile_count ? r->threads : job.tile_count;
    worker *ws = calloc(n, sizeof *ws);
    if (!ws)
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "reference: out of memory (threads)");
    /* The calling thread is worker 0; a thread that cannot start only
     * leaves more tiles to the others (the result does not change). */
    uint32_t started = 1;
    for (uint32_t i = 0; i < n; i++)
        ws[i].job = &job;
    for (uint32_t i = 1; i < n; i++) {
        if (pthread_create(&ws[started].thread, NULL, work, &ws[started]) != 0)
            break;
        started++;
    }
    work(&ws[0]);
    for (uint32_t i = 1; i < started; i++)
        pthread_join(ws[i].thread, NULL);
    for (uint32_t i = 0; i < started; i++) {
        r->nonfinite += ws[i].nonfinite;
        r->rays += ws[i].counters.rays;
    }
    free(ws);
    r->spp += spp;
    r->render_seconds += gi_now() - t0;
    r->render_cpu_seconds += process_cpu_seconds() - c0;
    return GI_OK;
}

uint64_t gi_ref_spp(const gi_ref *r)
{
    assert(r);
    return r->spp;
}

/* ---- results --------------------------------------------------------- */

gi_image *gi_ref_mean_image(const gi_ref *r)
{
    assert(r);
    gi_image *img = gi_image_create(r->rs.width, r->rs.height);
    if (!img)
        return NULL;
    size_t n = (size_t)r->rs.width * r->rs.height;
    for (size_t i = 0; i < n; i++) {
        const double *a = r->acc + i * ACC_SIZE;
        double cnt = a[ACC_N];
        for (int c = 0; c < 3; c++)
            img->rgba[4 * i + c] = cnt > 0.0 ? (float)(a[ACC_SUM + c] / cnt) : 0.0f;
        img->rgba[4 * i + 3] = 1.0f;
    }
    return img;
}

/* (sum of squares - n mean^2) / (n - 1) / n, never negative. */
static double var_of_mean(double sum, double sumsq, double n)
{
    if (n < 2.0)
        return 0.0;
    double m = sum / n;
    double v = (sumsq - n * m * m) / (n - 1.0);
    return v > 0.0 ? v / n : 0.0;
}

gi_image *gi_ref_variance_image(const gi_ref *r)
{
    assert(r);
    gi_image *img = gi_image_create(r->rs.width, r->rs.height);
    if (!img)
        return NULL;
    size_t n = (size_t)r->rs.width * r->rs.height;
    for (size_t i = 0; i < n; i++) {
        const double *a = r->acc + i * ACC_SIZE;
        for (int c = 0; c < 3; c++)
            img->rgba[4 * i + c] = (float)var_of_mean(a[ACC_SUM + c], a[ACC_SQ + c], a[ACC_N]);
        double lsum = lum_d(a[ACC_SUM], a[ACC_SUM + 1], a[ACC_SUM + 2]);
        img->rgba[4 * i + 3] = (float)var_of_mean(lsum, a[ACC_LUM_SQ], a[ACC_N]);
    }
    return img;
}

/* The mean of a per-pixel statistic over the pixels with 2 samples or
 * more (INFINITY when there are none): the stopping rules' estimates. */
static double mean_over_pixels(const gi_ref *r, double (*per_pixel)(const double *a))
{
    assert(r);
    size_t n = (size_t)r->rs.width * r->rs.height, used = 0;
    double total = 0.0;
    for (size_t i = 0; i < n; i++) {
        const double *a = r->acc + i * ACC_SIZE;
        if (a[ACC_N] < 2.0)
            continue;
        total += per_pixel(a);
        used++;
    }
    return used ? total / (double)used : INFINITY;
}

/* The luminance's standard error of the mean relative to the mean. */
static double pixel_rel_se(const double *a)
{
    double lsum = lum_d(a[ACC_SUM], a[ACC_SUM + 1], a[ACC_SUM + 2]);
    double se = sqrt(var_of_mean(lsum, a[ACC_LUM_SQ], a[ACC_N]));
    return se / (fabs(lsum / a[ACC_N]) + 0.01);
}

/* The relMSE metric's term with the squared error replaced by the
 * variance of the mean, averaged over the three channels. */
static double pixel_relmse(const double *a)
{
    double t = 0.0;
    for (int c = 0; c < 3; c++) {
        double q = a[ACC_SUM + c] / a[ACC_N] + 0.01;
        t += var_of_mean(a[ACC_SUM + c], a[ACC_SQ + c], a[ACC_N]) / (q * q);
    }
    return t / 3.0;
}

double gi_ref_mean_rel_se(const gi_ref *r)
{
    return mean_over_pixels(r, pixel_rel_se);
}

double gi_ref_mean_relmse(const gi_ref *r)
{
    return mean_over_pixels(r, pixel_relmse);
}

void gi_ref_get_stats(const gi_ref *r, gi_ref_stats *out)
{
    assert(r && out);
    memset(out, 0, sizeof *out);
    out->spp = r->spp;
    out->nonfinite = r->nonfinite;
    out->rays = r->rays;
    out->threads = r->threads;
    out->build_seconds = r->build_seconds;
    out->render_seconds = r->render_seconds;
    out->render_cpu_seconds = r->render_cpu_seconds;
}

const char *gi_ref_renderer(const gi_ref *r)
{
    assert(r);
    return r->renderer;
}
