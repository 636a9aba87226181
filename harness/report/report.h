/* Result files of `compare` and `study`: one JSON record per run, and from
 * them runs.csv, report.md (for results/) and index.html. Everything is
 * written atomically, so an interrupted run leaves either the old or the
 * new file, never half of one.
 *
 * A run record (json object) has: run (id), scene, method, params, status
 * ("ok", "n/a", "failed"), reason, renderer, timer, frames, prepare_ms,
 * frame_ms {median, min, max}, stages {name: {median, min, max}} (ms), stats {...},
 * metrics {"full": {...}, "matched": {...}} (metric name -> value), and
 * the file names image, png, heatmap, flip_map (relative to the output
 * directory). index.html also gets, from meta, "references" (per reference
 * set: name, full, bounces, matched [{image, bounces}], runs [ids]) and
 * "exposure"; report_write writes each image's .exr beside it as a .js file
 * (its linear RGB for the page's exposure control). */
#ifndef GIBENCH_REPORT_H
#define GIBENCH_REPORT_H

#include <json-c/json.h>
#include <stddef.h>

/* The metrics listed in tables, in this order (keys of `gibench diff --json`). */
extern const char *const report_metric_keys[];

/* Writes dir/runs.csv, dir/report.md and dir/index.html from `runs` (an
 * array of run records) and `meta` (title, scene(s), reference, renderer,
 * machine, command). Returns 1 on success, else 0 with why. */
int report_write(const char *dir, json_object *runs, json_object *meta, char *why, size_t why_size);

/* The report header: title, the command as typed ("gibench <command>
 * <argv...>"), GL renderer, reference description, machine and date. */
json_object *report_meta_new(const char *title, const char *command, int argc, char **argv,
                             const char *renderer, const char *reference);

#endif
