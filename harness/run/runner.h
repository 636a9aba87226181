/* One method run in its own process, then its error against the
 * references, recorded as a run record (report.h). Shared by `compare`
 * and `study`. A run whose directory already holds a result for the same
 * configuration is not run again (resume). */
#ifndef GIBENCH_RUNNER_H
#define GIBENCH_RUNNER_H

#include <json-c/json.h>
#include <stdint.h>

typedef struct run_spec {
    const char *run_id; /* name in tables, e.g. "direct" or "direct#3" */
    const char *scene;
    const char *method;
    const char *camera; /* NULL: the scene's first */
    uint32_t width, height, frames, warmup, seed;
    float time;                /* scene time */
    float animate_fps;         /* > 0: animated frames */
    const char *const *params; /* "k=v" */
    uint32_t param_count;
    double timeout_s;
    const char *dir;         /* this run's directory (created) */
    const char *rel;         /* dir relative to the report directory, for links */
    const char *ref_full;    /* full-GI reference EXR, or NULL */
    const char *ref_matched; /* bounce-matched reference EXR, or NULL */
    float exposure;
    int no_cache;      /* render --no-cache: precompute afresh (timing of precomputation) */
    const char *label; /* the study entry's label, or NULL */
    /* Per-frame comparison of an animated run (animate_fps > 0): frame f
     * (scene time time + f / animate_fps) against references of that time:
     * full GI, bounce-matched, and a second full-GI render with another
     * seed (the reference's noise floor; may be NULL). frame_ref_count is
     * 0 or `frames`; with it the run writes every frame
     * (render --frames-out DIR/frames/frame_%04d.exr) and the record gets
     * "animation" (docs/studies.md, "Animated runs, frame by frame"). */
    uint32_t frame_ref_count;
    const char *const *frame_ref_full, *const *frame_ref_matched, *const *frame_ref_alt;
} run_spec;

/* How runner_execute treats a result already in the run's directory. */
enum {
    RUNNER_FRESH = 0,       /* run again whatever is there */
    RUNNER_RESUME = 1,      /* keep a result of the same configuration, failed or not */
    RUNNER_RETRY_FAILED = 2 /* keep an "ok" result, run a failed one again */
};
/* Runs (or resumes, per `resume`, a RUNNER_* mode) a run; never fails as a
 * whole: failures are records with status "failed" and the child's own
 * message (cli_reason_external tells which look external). A run whose
 * image holds NaN or infinite pixels has failed ("non-finite output: N of
 * M pixels are NaN or infinite"). Caller owns the result. */
json_object *runner_execute(const run_spec *spec, int resume);
/* Collect-only mode (on: 1), for gibench study --slurm, whose cells run
 * elsewhere: runner_execute runs nothing and writes nothing, returning the
 * cached result (with "cached": true, resume or not) or a "failed" record
 * "no result"; runner_reference says whether the reference exists (0 with
 * why when not) without rendering it. */
void runner_set_collect_only(int on);
/* A record for a run that was not attempted ("n/a" with the reason). */
json_object *runner_not_applicable(const run_spec *spec, const char *reason);

/* Runs `gibench reference` into out_exr unless a file made with the same
 * settings exists; stops at `spp` samples or, when target_se > 0, as soon
 * as the relative standard error reaches it; pixel_center: --pixel center.
 * 1 on success, else 0 with why. */
int runner_reference(const char *scene, uint64_t scene_hash, const char *camera, uint32_t width,
                     uint32_t height, uint32_t spp, double target_se, uint32_t max_bounces,
                     uint32_t seed, float time, int pixel_center, double timeout_s,
                     const char *out_exr, char *why, size_t why_size);

/* The per-frame comparison of an animated run whose frames lie at
 * frames_pattern (cli_frame_path): per-frame relMSE (full and matched),
 * leaked energy and time, frame-to-frame change of the method and of the
 * references, flicker and the reference's noise floor. `timings` is the
 * render's timings file (per-frame times). NULL with why on failure. */
json_object *runner_animation_metrics(const run_spec *spec, const char *frames_pattern,
                                      json_object *timings, char *why, size_t why_size);

/* Fills metrics of `image` against `reference` by `gibench diff --json`;
 * NULL with why on failure. heatmap (relative error) and flip_map (FLIP's
 * error map), PNGs for the report, may be NULL. */
json_object *runner_diff(const char *image, const char *reference, const char *heatmap,
                         const char *flip_map, float exposure, char *why, size_t why_size);

struct gi_metrics;
/* Adds the metrics m to the object j under the names of `gibench diff
 * --json` (the diff command and the Python API's metrics share them). */
void runner_metrics_json_add(json_object *j, const struct gi_metrics *m);

#endif
