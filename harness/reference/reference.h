/* The reference: a CPU path tracer on Embree 3 over the core's scene, the
 * ground truth every GPU method is measured against (docs/ARCHITECTURE.md "The reference";
 * docs/commands.md "gibench reference").
 *
 * Use:
 *     gi_ref_desc d;
 *     gi_ref_desc_init(&d);                 // defaults: unlimited bounces, MIS, all cores
 *     d.scene = scene; d.width = 256; d.height = 256; d.seed = 1;
 *     gi_ref *r;
 *     gi_error err;
 *     if (gi_ref_create(&d, &r, &err) != GI_OK) { fprintf(stderr, "%s\n", err.text); ... }
 *     while (gi_ref_spp(r) < 1024 && gi_ref_mean_rel_se(r) > 0.01)
 *         gi_ref_render(r, 16, &err);       // one pass: 16 more samples per pixel
 *     gi_image *mean = gi_ref_mean_image(r), *var = gi_ref_variance_image(r);
 *     ...
 *     gi_image_free(mean); gi_image_free(var); gi_ref_free(r);
 *
 * Ownership: the scene is borrowed and must outlive the renderer (its index
 * buffer and vertex attributes are read while rendering). gi_ref_create
 * gives you a renderer to free with gi_ref_free; the image getters return new
 * images you free with gi_image_free. One renderer is not to be used from two
 * threads at once; gi_ref_render runs its own worker threads.
 *
 * Estimator: unidirectional path tracing. At every path vertex, next-event
 * estimation samples one emissive triangle (chosen with probability
 * proportional to area x luminance of its emission, point uniform on it) and
 * one environment direction (luminance x sin(theta) CDF of envmap.h), each
 * combined with BSDF sampling by the power heuristic; punctual lights
 * (point, spot, directional) are evaluated every one. Russian roulette after
 * the third bounce with survival min(0.95, max component of the
 * throughput), dividing by it (unbiased). Camera rays are jittered uniformly
 * inside the pixel (box filter).
 *
 * Determinism: sample s of pixel p draws all its random numbers from
 * gi_rng_init(p, s, seed) (rng.h), and each pixel adds its samples in order
 * of s. The mean and variance after N samples per pixel are therefore the
 * same bits whatever the thread count and however the N samples were split
 * into gi_ref_render passes.
 *
 * Errors: gi_ref_create returns GI_ERR_INVALID_ARGUMENT for bad input (a
 * size of 0, a non-finite vertex or camera at the requested time) and other
 * codes for run-time failures (out of memory, Embree errors); the message
 * goes to err.
 */
#ifndef GI_REFERENCE_H
#define GI_REFERENCE_H

#include "gi/common.h"
#include "gi/image.h"
#include "gi/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

/* How direct light is estimated at each vertex. MIS is the reference;
 * the other two exist so tests can hold independent estimators against it
 * (`gibench reference --strategy`, hidden). Punctual lights are always
 * sampled directly (BSDF sampling cannot hit them), and emitters seen after
 * a mirror bounce are always counted (light sampling cannot reach them). */
typedef enum gi_ref_strategy {
    GI_REF_STRATEGY_MIS = 0,   /* light and BSDF sampling, power heuristic */
    GI_REF_STRATEGY_LIGHT = 1, /* light sampling only for area lights and the map */
    GI_REF_STRATEGY_BSDF = 2,  /* BSDF sampling only for area lights and the map */
} gi_ref_strategy;

/* max_bounces: no limit; paths end by Russian roulette (or by escaping). */
#define GI_REF_UNLIMITED (-1)

typedef struct gi_ref_desc {
    const gi_scene *scene; /* required; borrowed */
    int camera;            /* camera index for gi_scene_camera_at; -1 (or none in the
                              file) = the default view of the bounds */
    /* When not NULL, this camera instead of `camera` (copied by gi_ref_create):
     * a free camera, e.g. gibench view's orbit camera or a saved view. */
    const gi_camera_frame *camera_frame;
    float time;             /* scene time t: object, light and camera placement */
    uint32_t width, height; /* required, gi_image_size_ok (gi/limits.h) */
    uint32_t seed;
    /* Scattering events a path may have: 0 = emitters and the environment
     * seen directly, 1 = plus direct light at the first hit, k = up to k
     * bounces; GI_REF_UNLIMITED = all. NOT zero-means-default: a zeroed
     * desc renders emitters only; start from gi_ref_desc_init. */
    int max_bounces;
    uint32_t threads; /* worker threads; 0 = $SLURM_CPUS_PER_TASK, else the online CPUs */
    gi_ref_strategy strategy;
    /* 0: each camera sample uniform in its pixel (box filter, the pixel's
     * exact average); 1: every sample through the pixel's centre, as the
     * GPU methods' G-buffers sample it (so that a comparison measures
     * shading, not anti-aliasing). */
    int pixel_center;
    /* 0: Embree's default traversal (GI_RT_FAST_TRAVERSAL, what Embree's
     * own path tracer uses); 1: RTC_SCENE_FLAG_ROBUST, slower, never lets
     * a ray through the shared edge of two triangles. The two agree to
     * float rounding except for such rare rays (statistically the same
     * image; `gibench reference --traversal`). */
    int robust_traversal;
} gi_ref_desc;

/* Defaults: scene NULL, camera 0, time 0, size 0 (must be set), seed 1,
 * unlimited bounces, all CPUs, MIS, fast traversal. */
void gi_ref_desc_init(gi_ref_desc *d);

typedef struct gi_ref gi_ref;

/* Validates the scene at desc->time (every transformed vertex finite),
 * builds the Embree BVH (build quality high) and the light tables.
 * On success *out owns a renderer with no samples yet. */
gi_result gi_ref_create(const gi_ref_desc *desc, gi_ref **out, gi_error *err);
void gi_ref_free(gi_ref *r);

/* Adds `spp` samples to every pixel (samples gi_ref_spp() .. + spp - 1),
 * using the desc's worker threads; returns when they are done. spp = 0 is
 * a no-op. Fails only when worker threads cannot be started. */
gi_result gi_ref_render(gi_ref *r, uint32_t spp, gi_error *err);

/* Samples per pixel so far (passes added up). */
uint64_t gi_ref_spp(const gi_ref *r);

/* Mean radiance, linear RGB; A = 1. NULL when memory runs out. A pixel all
 * of whose samples were non-finite is 0. */
gi_image *gi_ref_mean_image(const gi_ref *r);
/* Variance of the mean (the squared standard error) per channel,
 * s^2 / n with s^2 the unbiased sample variance of the n finite samples;
 * A = the same for the luminance (Rec. 709) of the samples. 0 where n < 2. */
gi_image *gi_ref_variance_image(const gi_ref *r);

/* The stopping statistic of --target-se: the mean over pixels of
 *     SE(lum) / (mean(lum) + 0.01),
 * SE(lum) the standard error of the pixel's mean luminance (square root of
 * variance.A above). Pixels with fewer than 2 finite samples are left out;
 * +infinity before any pixel has 2. */
double gi_ref_mean_rel_se(const gi_ref *r);
/* The stopping statistic of --target-relmse: the reference's own expected
 * relMSE, the mean over pixels and channels of
 *     var(mean_c) / (mean_c + 0.01)^2,
 * gibench's relMSE metric (metrics.h) with the error replaced by the
 * variance of the mean. Pixels with fewer than 2 finite samples are left
 * out; +infinity before any pixel has 2. */
double gi_ref_mean_relmse(const gi_ref *r);

typedef struct gi_ref_stats {
    uint64_t spp;              /* samples per pixel */
    uint64_t nonfinite;        /* NaN/Inf samples, discarded (each counted once) */
    uint64_t rays;             /* closest-hit and shadow rays traced */
    uint32_t threads;          /* worker threads */
    double build_seconds;      /* scene validation + BVH build in gi_ref_create */
    double render_seconds;     /* wall time inside gi_ref_render, summed */
    double render_cpu_seconds; /* the process's CPU time (every thread) inside gi_ref_render,
                                  summed: what studies timed by CPU time compare with
                                  (docs/studies.md "Speed against accuracy") */
} gi_ref_stats;
void gi_ref_get_stats(const gi_ref *r, gi_ref_stats *out);

/* "embree 3.13.5 cpu": the renderer name recorded with every result. */
const char *gi_ref_renderer(const gi_ref *r);
/* When gi_ref_progressive stops: at `spp` samples per pixel, after
 * `seconds` of rendering, once gi_ref_mean_rel_se falls to `target_se`, or
 * once gi_ref_mean_relmse falls to `target_relmse`
 * (checked at sample counts that depend on the image alone, so that the
 * stopping point and the image are reproducible); 0 leaves a limit out,
 * the first one reached stops. */
typedef struct gi_ref_until {
    uint64_t spp;
    double seconds;
    double target_se;
    double target_relmse;
} gi_ref_until;
/* Called after every pass with the samples so far, the last standard
 * error checked (with target_se; else the current one) and the samples
 * it was taken at, and the seconds so far; nonzero cancels. */
typedef int (*gi_ref_pass_fn)(void *user, uint64_t spp, double rel_se, uint64_t se_spp,
                              double elapsed);
/* Passes of about half a second until `u` says stop (*stop: "spp",
 * "time", "target-se" or "target-relmse"). GI_ERR_CANCELLED when fn asked. The loop of
 * gibench reference; the image after N samples is the same bits however
 * they were split (see Determinism above). */
gi_result gi_ref_progressive(gi_ref *r, const gi_ref_until *u, gi_ref_pass_fn fn, void *user,
                             const char **stop, gi_error *err);

/* Name of a strategy ("mis", "light", "bsdf"), and the reverse (-1 when
 * the name is unknown). */
const char *gi_ref_strategy_name(gi_ref_strategy s);
int gi_ref_strategy_parse(const char *name);

#ifdef __cplusplus
}
#endif
#endif
