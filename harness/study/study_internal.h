/* The study engine's shared definitions (gibench study, docs/studies.md
 * "gibench study"): the study as read and planned into runs, its scenes and
 * reference sets, and the functions that the engine's files call across
 * each other. Only harness/study/ includes it; study.h is the public entry. */
#ifndef GIBENCH_STUDY_INTERNAL_H
#define GIBENCH_STUDY_INTERNAL_H

#include "cli.h"
#include "runner.h"
#include "slurm.h"
#include "tradeoff.h"

#include <json-c/json.h>
#include <stddef.h>
#include <stdint.h>

#define MAX_RUNS 4096
#define MAX_SWEEP 64
#define MAX_KEYS 64 /* parameters of one entry: as many as render takes (--param) */
#define MAX_SCENES 16
#define MAX_REFS 512 /* an animated run compared frame by frame needs a set per frame */

/* What a run is made with: the study's top-level values, overridden per
 * method entry (docs/studies.md, "gibench study"). */
typedef struct run_settings {
    int scenes[MAX_SCENES]; /* indices into study.scenes */
    uint32_t scene_n;
    uint32_t width, height, frames, warmup;
    uint32_t repeats; /* each with seed + r; an entry's repeats are interleaved */
    float time, animate_fps;
    int cache;   /* 0: render --no-cache (precomputation timed afresh) */
    int compare; /* 0: no references, no metrics (timing-only runs) */
    const char *label;
} run_settings;

typedef struct study_run {
    run_spec spec;
    char id[512], dir[4096], rel[1024];
    char *params[MAX_KEYS];
    int scene_index;
    int ref_index;    /* -1: not compared */
    uint32_t bounces; /* the method's max_bounces + 1 */
    uint64_t setting; /* every input but the seed: runs of one setting are repeats */
    json_object *record;
    /* an animated compared run: the reference set of each frame's time, and
     * the file names handed to the runner (run_spec.frame_ref_*) */
    int *frame_ref;
    uint32_t frame_ref_n;
    const char **fr_full, **fr_matched, **fr_alt;
} study_run;

typedef struct study_scene {
    const char *name; /* as the study names it (the records' "scene") */
    char path[4096];  /* resolved from the study's base folder (study_paths.c) */
    char stem[256];
    uint64_t hash; /* its content: the file, every object's geometry, the environment map */
    uint32_t triangles, vertices; /* for scale studies (records get scene_triangles) */
} study_scene;

/* The references of one scene at one size and scene time. */
typedef struct study_ref {
    int scene_index;
    uint32_t width, height;
    float time;
    char name[320]; /* the scene's stem, plus size and time where a scene has several */
    char ref_full[4096];
    char ref_matched[8][4096];
    uint32_t matched_bounces[8];
    uint32_t matched_count;
    /* the path tracer's convergence: full GI, and for each matched bounce count */
    tradeoff_pt_curve pt_full, pt_matched[8];
    char missing[1100]; /* gibench study --slurm-collect: why the set was not made, or "" */
    int frame_only; /* used only by animated runs' frames: no convergence curve, no tradeoff table
                     */
    int want_alt;   /* a frame: also the full-GI reference with another seed (the noise floor) */
    char ref_alt[4096];
} study_ref;

typedef struct study {
    json_object *root;
    const char *name;
    uint32_t seed;
    uint32_t ref_spp, ref_bounces;
    double ref_target_se; /* 0: none */
    int ref_pixel_center; /* "pixel": "center": references sample pixel centres */
    uint32_t conv_spp[32], conv_n;
    uint32_t conv_repeats; /* "convergence_repeats": times each curve point is timed */
    /* this invocation of gibench study (issue 34, one clock per comparison):
     * recorded in every run it times and in the curves it times */
    char invocation[64];
    int mix_clocks; /* --mix-clocks: report timings of several invocations, flagged */
    float exposure;
    const char *camera;      /* as the runs get it: a "view:FILE" resolved (study_paths.c) */
    const char *camera_name; /* as the study names it (in the runs' ids) */
    char camera_buf[4200];
    char base_dir[4096];    /* relative paths resolve from here (study_paths.c) */
    const char *located_as; /* NULL, or the file the study's paths resolve as if from */
    double timeout_s;
    run_settings base;
    study_scene scenes[MAX_SCENES];
    uint32_t scene_count;
    study_ref *refs; /* MAX_REFS of them, on the heap */
    uint32_t ref_count;
    json_object *charts; /* the "charts" list, or NULL */
    const char *timer;   /* "timer": GIBENCH_TIMER for the runs, or NULL */
    study_run *runs;
    uint32_t run_count;
} study;

/* ---- reading the study file (study_json.c) ---- */

/* Prints "FILE: PATH: WHAT" and returns EXIT_USAGE. */
int study_fail_json(const char *file, const char *path, const char *what);
int study_get_uint(json_object *o, const char *prefix, const char *key, uint32_t min, uint32_t max,
                   uint32_t def, uint32_t *out, const char *file);
int study_get_number(json_object *o, const char *prefix, const char *key, double min, double max,
                     double def, double *out, const char *file);
int study_get_string(json_object *o, const char *prefix, const char *key, int null_ok,
                     const char *def, const char **out, const char *file);
json_object *study_read_strict_json(const char *file);
int study_check_keys(json_object *o, const char *const *known, const char *prefix,
                     const char *file);

/* ---- paths in the study (study_paths.c) ---- */

/* The study's base folder from its file's name ("-": standard input, the
 * current folder) and its "base" key: EXIT_OK, or EXIT_USAGE after printing
 * one line. */
int study_set_base(study *st, json_object *root, const char *file);
/* `name` resolved from the study's base folder (absolute names kept). */
void study_resolve(const study *st, const char *name, char *out, size_t size);
/* EXIT_OK when `resolved` can be read, else EXIT_USAGE after one line that
 * names the study file, the JSON path, the resolved path and the base. */
int study_check_readable(const study *st, const char *file, const char *jpath, const char *name,
                         const char *resolved);

/* ---- the study read and planned (study_load.c, study_plan.c) ---- */

/* Reads, validates and plans the study in `file` into st (runs, scenes,
 * reference sets); run directories lie under out_dir. EXIT_OK, or an exit
 * status after printing one line. */
int study_load(study *st, const char *file, const char *out_dir, gi_plugins *reg);
int study_expand_method(study *st, const char *file, const char *out_dir, const gi_method *m,
                        json_object *params, const char *mpath, const run_settings *rs);
void study_name_refs(study *st);

/* ---- references (study_refs.c) ---- */

/* curves: STUDY_CURVES_NONE (the images only), STUDY_CURVES_LOAD (the path
 * tracer's curves as an earlier invocation timed them, timed now when none
 * fits), STUDY_CURVES_TIME (timed now, in this invocation). */
enum {
    STUDY_CURVES_NONE = 0,
    STUDY_CURVES_LOAD = 1,
    STUDY_CURVES_TIME = 2,
    STUDY_CURVES_RECORDED = 3 /* as recorded only, never timed (--slurm-collect) */
};
int study_build_reference_set(study *st, const char *out_dir, uint32_t ri, int curves, char *why,
                              size_t why_size);
/* Every reference set's images. With slurm_collecting (gibench study
 * --slurm-collect) a missing set is reported with its runs, not fatal. */
int study_build_references(study *st, const char *out_dir, int slurm_collecting);
/* The path tracer's curves of every set that has them, after the runs:
 * timed now when this invocation timed a run compared with them (or no
 * earlier curve fits), else as recorded. EXIT_OK or EXIT_RUN after one line. */
int study_build_curves(study *st, const char *out_dir, int slurm_collecting);
/* Whether the runs compared with a curve come from several invocations. */
int study_runs_mixed(const study *st);
/* Whether this invocation timed run r (its record names the invocation). */
int study_timed_now(const study *st, const study_run *r);
/* The refusal of mixed clocks: EXIT_OK when every run compared with a
 * path tracer's curve, and the curves, were timed in one invocation (or
 * --mix-clocks, *mixed set); else EXIT_USAGE after one line naming them. */
int study_check_clocks(const study *st, int *mixed);
/* A new invocation id: UTC time, pid and random bits. */
void study_new_invocation(char *out, size_t size);
/* The path tracer's curve of set sc at a bounce limit as an invocation
 * timed it (study_clock.c): its file, the key of its settings, and the
 * file read (1 when it holds a curve of that key) and written. */
void study_curve_record_path(const study *st, const char *out_dir, const study_ref *sc,
                             uint32_t bounces, char *path, size_t size);
void study_curve_key(const study *st, const char *reference, uint32_t bounces, char *key,
                     size_t size);
int study_curve_load(const char *path, const char *key, tradeoff_pt_curve *curve);
int study_curve_save(const char *path, const char *key, const tradeoff_pt_curve *curve,
                     double samples[][64], char *why, size_t why_size);
/* Points run r's spec at the reference files of its set(s). */
void study_attach_refs(study *st, study_run *r);
void study_reference_sets(study *st, json_object *meta);

/* ---- execution (study_exec.c) ---- */

/* A run's record (cached, executed, or "n/a"); an executed one gets the
 * study's invocation, in its result.json too. */
json_object *study_run_or_skip(const study *st, study_run *r, gi_plugins *reg, int resume);
/* mode: RUNNER_FRESH (--fresh), RUNNER_RESUME, RUNNER_RETRY_FAILED (--retry-failed). */
void study_execute_runs(study *st, uint32_t jobs, int mode, gi_plugins *reg);

/* ---- the report's charts and tables (study_charts.c, study_anim.c) ---- */

/* mixed: the study's clocks are mixed (--mix-clocks): each table says so.
 * Also writes pt_curves.csv, every timed sample of the path tracer's curves. */
void study_charts_and_speedups(study *st, const char *out_dir, json_object *meta,
                               json_object *chart_list, int mixed);
void study_user_charts(study *st, const char *out_dir, json_object *runs, json_object *chart_list);
void study_animation_report(study *st, const char *out_dir, json_object *meta,
                            json_object *chart_list);

/* ---- the report (study_report.c) ---- */

/* Writes out/report.md, index.html and the CSV files from the runs'
 * records. EXIT_OK, or EXIT_RUN after printing why (also when the study
 * was interrupted, and when a run failed, unless `slurm_collect`: the
 * collect job names the failed runs but ends completed, its report being
 * its work). */
int study_write_report(study *st, const char *out, int argc, char **argv, int slurm_collect);

/* ---- gibench study --slurm (study_slurm.c) ---- */

int study_slurm_cell(study *st, const char *out, gi_plugins *reg, const char *cell);
int study_slurm_submit(study *st, const char *file, const char *out, gi_plugins *reg,
                       const slurm_options *so);
void study_slurm_collect_runs(study *st, gi_plugins *reg, const char *out, const char *jobs);

#endif
