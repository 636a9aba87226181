/* What the report's writers share (report.c, report_csv.c, report_md.c,
 * report_html.c, report_viewer.c): the text they build each file in, the
 * accessors of run records, and each writer. */
#ifndef GIBENCH_REPORT_INTERNAL_H
#define GIBENCH_REPORT_INTERNAL_H

#include "text.h"

#include <json-c/json.h>
#include <stddef.h>

/* The text every output file is built in (text.h). */
typedef gi_text text;
#define put gi_text_put

/* A string field of a record; "" when absent. "params" reads the method's
 * full parameter string (defaults included) when the record has it. */
const char *report_str(json_object *o, const char *key);
/* A string field as stored (report_str swaps "params" for "params_full"). */
const char *report_raw(json_object *o, const char *key);
/* Number at a path of up to three keys; NaN when absent. */
double report_num(json_object *o, const char *k1, const char *k2, const char *k3);
/* The union over all runs of the keys of object `field` ("stages",
 * "prepare_stages", "stats"), first-seen order. */
int report_key_names(json_object *runs, const char *field, const char **names, int max);
/* The keys of "stages" over all runs. */
int report_stage_names(json_object *runs, const char **names, int max);
/* Whether dir/rel is a file (links in the report point only at files that exist). */
int report_exists_in(const char *dir, const char *rel);

/* runs.csv: every run, one row (report_csv.c). */
void report_write_csv(text *t, json_object *runs);
/* frames.csv: every timed frame of every run (per-frame time of animations). */
void report_write_frames_csv(text *t, json_object *runs);
/* curves.csv: every run's convergence curve (render --curve-ref). */
void report_write_curves_csv(text *t, json_object *runs);
/* report.md, for results/ (report_md.c). */
void report_write_md(text *t, const char *dir, json_object *runs, json_object *meta);
/* index.html with its script and style inline (report_html.c). */
void report_write_html(text *t, const char *dir, json_object *runs, json_object *meta);
/* The image viewer's data, per reference set (report_viewer.c); writes
 * each image's HDR script beside its .exr. */
json_object *report_viewer_sets(const char *dir, json_object *runs, json_object *meta);

#endif
