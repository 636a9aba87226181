/* gibench conformance's internals, shared by its files (docs/conformance.md): the items of a
 * method's check list (conf_items.c), the child's sessions on the GPU (conf_session.c), image
 * measures (conf_measure.c), the checks (conf_checks.c), the child process that runs them
 * (conf_child.c) and the parent that starts children and prints the table (cmd_conformance.c). Not
 * a public header: only the .c files beside it include it. */
#ifndef GIBENCH_CONF_H
#define GIBENCH_CONF_H

#include "cli.h"

#include "gi/image.h"

#include <stddef.h>
#include <stdint.h>

#ifndef GIBENCH_SOURCE_DIR
#define GIBENCH_SOURCE_DIR "."
#endif

#define CONF_DATA GIBENCH_SOURCE_DIR "/tests/data/conformance"
#define CONF_SCENES GIBENCH_SOURCE_DIR "/scenes"
#define CONF_MAX_ITEMS 512

/* ---- items (conf_items.c) */

typedef struct conf_item {
    char group[32]; /* the table's check */
    char arg[600];  /* scene path, parameter "k=v", light kind, rho ... */
} conf_item;

typedef struct conf_opts {
    const char *method;
    uint32_t size;
    double item_timeout;
    int json;
    const char *held_out; /* --held-out SEED or folder; NULL: the shipped suite */
    const char *variants; /* --variants a,b: the held-out variants to run; NULL: all */
    int no_converge;      /* --no-converge: skip the knob sweeps */
} conf_opts;

/* The items of method m, in the fixed order that --from counts in;
 * returns how many (at most CONF_MAX_ITEMS). */
uint32_t conf_build_items(const gi_method *m, conf_item *items);
double conf_item_limit(const gi_method *m, const conf_item *it, double base);

/* ---- the child: sessions (conf_session.c) */

typedef enum { R_PASS = 0, R_FAIL = 1, R_NA = 2 } conf_status;
extern const char *const conf_status_name[3];

typedef struct conf_scene {
    gi_scene *scene;
    gi_gpu_scene *gs;
} conf_scene;

typedef struct conf_session {
    const gi_method *m;
    gi_gpu *gpu;
    cli_host host;
    int host_ready;
    void *inst;
    gi_params *params;
    GLuint tex, fbo;
    uint32_t w, h;
    char why[1024];
} conf_session;

/* The session's functions return 1 (or an image) on success, and 0 (or
 * NULL) with the reason in S->why. */
void conf_scene_free(conf_scene *s);
int conf_scene_open(conf_session *S, const char *path, float t, conf_scene *out);
void conf_instance_free(conf_session *S);
/* S->why = "WHAT failed (RESULT): the method's last error"; returns 0. */
int conf_method_error(conf_session *S, const char *what, gi_result r);
int conf_instance_new(conf_session *S, const char *const *kv, uint32_t n, const conf_scene *sc);
gi_image *conf_render_frames(conf_session *S, const conf_scene *sc, float t, uint32_t w, uint32_t h,
                             uint32_t frames, uint32_t first, float shift, uint32_t seed);
gi_image *conf_fresh_render(conf_session *S, const conf_scene *sc, uint32_t size, uint32_t frames,
                            uint32_t seed);
/* The scene moved to time t and the method told of `flags` (update()). */
int conf_update(conf_session *S, conf_scene *sc, uint32_t flags, float t);

/* ---- image measures (conf_measure.c) */

typedef struct conf_img_stats {
    double mean; /* of (R + G + B) / 3 over finite pixels */
    uint64_t nonfinite, negative;
} conf_img_stats;

conf_img_stats conf_measure(const gi_image *img);
double conf_rel_diff(const gi_image *a, const gi_image *b);
int conf_sane(const gi_image *img, char *why, size_t size);

/* ---- the checks (conf_checks.c) */

typedef struct conf_result {
    conf_status status;
    char detail[1024];
} conf_result;

/* r's status s and its detail from fmt; returns s. */
conf_status conf_set(conf_result *r, conf_status s, const char *fmt, ...);
/* Runs item `it` in session S (which holds a GPU, except for
 * unknown_params) into r. */
conf_status conf_run_item(conf_session *S, const conf_opts *o, const conf_item *it, conf_result *r);

/* The furnace check on the closed emitting sphere at `path` (albedo rho,
 * Le = 1, camera at its centre), as the furnace_* rows run it. */
conf_status conf_check_furnace_file(conf_session *S, const conf_opts *o, const char *path,
                                    double rho, conf_result *r);

/* ---- the held-out family (conf_heldout.c, conf_heldout_run.c) */

#define CONF_TRUTH GIBENCH_SOURCE_DIR "/tests/data/truth"
#define CONF_HELD_OUT_SCRIPT GIBENCH_SOURCE_DIR "/scripts/held_out.py"
#define CONF_MAX_KNOBS 16

/* gibench conformance --held-out SEED|DIR: the family's checks for ms[0..count). */
int conf_held_out(const conf_opts *o, const gi_method *const *ms, uint32_t count);
/* The child of one (method, scene): --held-out-item DIR FILE. */
int conf_held_out_item(const conf_opts *o, const char *dir, const char *file);

/* ---- the child (conf_child.c) */

/* gibench conformance --run-items: the items of o->method from `from` on. */
int conf_run_items(const conf_opts *o, uint32_t from);

#endif
