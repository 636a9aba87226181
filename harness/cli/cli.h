/* Shared pieces of the gibench command: argument helpers, the plugin
 * registry, the host services handed to plugins, and JSON output. */
#ifndef GIBENCH_CLI_H
#define GIBENCH_CLI_H

#include "gi/limits.h"
#include "gi/method.h"
#include "gi/plugin.h"
#include "gi/timer.h"

#include <json-c/json.h>
#include <signal.h>
#include <stdio.h>

/* Exit codes (docs/ARCHITECTURE.md): 0 ok, 1 failure while running, 2 bad usage or input. */
enum { EXIT_OK = 0, EXIT_RUN = 1, EXIT_USAGE = 2 };

/* Prints "gibench: <message>" on stderr and returns `code`. */
int cli_fail(int code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* Parses "WxH" into a size that keeps gi/limits.h's GI_IMAGE_SIZE_RULE; 0
 * on malformed text or a size beyond it. */
int cli_parse_size(const char *s, uint32_t *w, uint32_t *h);
/* The file name of frame `index` from a printf-style PATTERN with exactly
 * one %d, %Nd or %0Nd (N < 10) and %% for a percent sign (render
 * --frames-out, and the study's runs that read those frames back). 1 on
 * success, 0 for a bad pattern or a name that does not fit. */
int cli_frame_path(const char *pattern, uint32_t index, char *out, size_t size);
/* Parses an unsigned integer in [min, max]; 0 on failure. */
int cli_parse_uint(const char *s, unsigned long min, unsigned long max, unsigned long *out);
/* Parses a finite number that a float holds; 0 on failure. */
int cli_parse_float(const char *s, float *out);
/* Parses an exposure in stops, -64..64 (beyond, every pixel is black or white). */
int cli_parse_exposure(const char *s, float *out);
/* Appends an --out file name to outs[0..*count) for command `cmd`
 * ("render", "reference"): at most `max`, and only .exr, .pfm or .png
 * names. Returns 0, or EXIT_USAGE after printing the reason. */
int cli_add_out(const char *cmd, const char **outs, int *count, int max, const char *path);

/* mkdir -p; 1 on success. */
int cli_mkdirs(const char *path);
/* Makes a fresh private folder "$TMPDIR/<stem>-XXXXXX" (/tmp when TMPDIR is
 * unset or empty, as mktemp(1) does) and writes its path to out. 1 on
 * success; 0 with errno set and out holding the template that failed, for
 * the caller's error message. */
int cli_temp_dir(const char *stem, char *out, size_t size);
/* Makes and opens a fresh private file "$TMPDIR/<stem>-XXXXXX" the same
 * way; returns its descriptor, or -1 with errno set and out holding the
 * template that failed. */
int cli_temp_file(const char *stem, char *out, size_t size);
/* Reads a JSON file (NULL if absent or malformed). */
json_object *cli_read_json(const char *path);
/* Reads a JSON file a user wrote (a study, a saved view) strictly
 * (json_strict.c): a regular file of at most GI_MAX_JSON_BYTES, strict
 * JSON (no trailing comma, comment or text after the value), no object
 * giving a key twice, keys compared unescaped ("fr\u0061mes" is
 * "frames"). NULL with the one-line reason in `why` ("FILE: /json/path:
 * key given twice (line N)", "FILE: line N: not valid JSON: ..."). */
json_object *cli_read_json_strict(const char *path, char *why, size_t why_size);

/* The folder of the build's own plugins: $GIBENCH_PLUGIN_DIR when set
 * (empty: none), else the folder compiled in (GIBENCH_PLUGIN_DIR); NULL
 * for none. */
const char *cli_plugin_dir(void);
/* The plugin registry of cli_plugin_dir() plus $GIBENCH_PLUGIN_PATH; loader
 * refusals are printed as warnings. Whatever plugins print while they load
 * goes to stderr. */
gi_plugins *cli_load_plugins(int quiet);
/* The caps as a list of words ("direct area-lights ..."). */
void cli_caps_string(uint32_t caps, char *buf, size_t size);
const char *cli_param_type_name(gi_param_type t);

/* A progress line on a terminal: "\rLABEL [#####.....]  45%  k/N  0:12 elapsed, ETA 0:15  NOTE".
 * Off (nothing printed) when stderr is not a terminal or under -q, so that
 * logs stay clean. The ETA is the elapsed time scaled by the share left. */
typedef struct cli_progress {
    int on, open;
    double start;
    char label[64];
} cli_progress;
void cli_progress_start(cli_progress *p, const char *label);
/* fraction in [0, 1]; done/total are shown when total > 0; note may be NULL. */
void cli_progress_show(cli_progress *p, double fraction, uint64_t done, uint64_t total,
                       const char *note);
/* Ends an open line (a newline); nothing when none is open. */
void cli_progress_end(cli_progress *p);
/* "m:ss" or "h:mm:ss" of a duration in seconds. */
void cli_format_duration(double seconds, char *out, size_t size);

/* Host services for one method instance. */
typedef struct cli_host {
    gi_host host;
    const char *method_id;
    gi_timer *timer; /* where stage timers go now (prepare or render timer) */
    json_object *stats;
    int show_progress;
    cli_progress bar; /* the precomputation's progress line */
} cli_host;

void cli_host_init(cli_host *h, const char *method_id, const char *cache_dir,
                   const gi_gpu_scene *gs, const char *renderer, int software);
void cli_host_free(cli_host *h);
/* Completes and ends a precomputation progress line left open (a plugin
 * whose last report was below 100 %). */
void cli_host_progress_end(cli_host *h);

/* Set by SIGINT/SIGTERM; the host reports it through cancelled(). */
extern volatile sig_atomic_t cli_interrupted;
void cli_install_signal_handlers(void);

/* Writes `obj` to `path` atomically, releases it, and returns EXIT_OK or
 * EXIT_RUN after printing why (the end of render and reference). */
int cli_save_json(const char *path, json_object *obj);
/* Writes a JSON object to a file atomically (pretty-printed). */
int cli_write_json(const char *path, json_object *obj, char *why, size_t why_size);
/* Stage statistics of a timer as a JSON object {stage: {median_ms, ...}}. */
json_object *cli_timer_json(const gi_timer *t);

/* The scene by its content, not its name: the file's bytes, every object's
 * geometry (gi_scene_object_hash), every texture's decoded texels and the
 * environment map's bytes. What run ids and references are keyed on. */
uint64_t cli_scene_content_hash(const gi_scene *s, const char *path);

/* Do the method's caps cover the scene's lighting and materials (and
 * motion when animated)? 0 with the reason naming everything not covered
 * ("avg does not handle directional lights or environment light"). */
int cli_caps_cover(const gi_method *m, const gi_scene *s, int animated, char *why, size_t size);

/* One installed method as gibench methods --json lists it (id, title,
 * caps, parameters with ranges and quality knobs); also the Python API's. */
json_object *cli_method_json(const gi_plugin *it);

/* The help of one command (gibench help CMD, CMD --help): 0 when known. */
int cli_command_help(const char *cmd, FILE *to);

/* The commands, dispatched by main.c. methods, info, render, reference,
 * diff and compare are front ends in this folder; study, conformance and
 * view live in the libraries of harness/study/, harness/conformance/ and
 * harness/view/. */
int cmd_methods(int argc, char **argv);
int cmd_info(int argc, char **argv);
int cmd_render(int argc, char **argv);
int cmd_diff(int argc, char **argv);
int cmd_compare(int argc, char **argv);
int cmd_study(int argc, char **argv);
int cmd_reference(int argc, char **argv);
int cmd_conformance(int argc, char **argv);
int cmd_view(int argc, char **argv);

#endif
