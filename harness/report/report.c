/* The report of `compare` and `study` (report.h): its header, the
 * accessors of run records that every writer uses, and report_write, which
 * writes runs.json and each writer's file (runs.csv, frames.csv and
 * curves.csv in report_csv.c, report.md in report_md.c, index.html in
 * report_html.c). */
#define _POSIX_C_SOURCE 200809L
#include "report.h"
#include "report_internal.h"

#include "gi/cache.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/utsname.h>
#include <time.h>
#include <unistd.h>

const char *const report_metric_keys[] = {
    "relmse", "rmse", "mae", "psnr", "ssim", "flip", "mean_lum_diff_pct", "hdr_flip", NULL};

/* The machine, for the report: kernel, architecture, cores. */
static void machine_string(char *buf, size_t size)
{
    struct utsname u;
    if (uname(&u) != 0)
        snprintf(buf, size, "unknown");
    else
        snprintf(buf, size, "%s %s %s, %ld cores", u.sysname, u.release, u.machine,
                 sysconf(_SC_NPROCESSORS_ONLN));
}

static void date_string(char *buf, size_t size)
{
    time_t t = time(NULL);
    struct tm tm;
    gmtime_r(&t, &tm);
    strftime(buf, size, "%Y-%m-%d %H:%M UTC", &tm);
}

static void command_string(const char *cmd, int argc, char **argv, char *buf, size_t size)
{
    snprintf(buf, size, "gibench %s", cmd);
    for (int i = 0; i < argc; i++) {
        size_t used = strlen(buf);
        snprintf(buf + used, size - used, " %s", argv[i]);
    }
}

json_object *report_meta_new(const char *title, const char *command, int argc, char **argv,
                             const char *renderer, const char *reference)
{
    char cmd[4096], machine[256], date[64];
    command_string(command, argc, argv, cmd, sizeof cmd);
    machine_string(machine, sizeof machine);
    date_string(date, sizeof date);
    json_object *meta = json_object_new_object();
    json_object_object_add(meta, "title", json_object_new_string(title));
    json_object_object_add(meta, "command", json_object_new_string(cmd));
    json_object_object_add(
        meta, "renderer",
        json_object_new_string(renderer && *renderer ? renderer : "(no run finished)"));
    json_object_object_add(meta, "reference", json_object_new_string(reference));
    json_object_object_add(meta, "machine", json_object_new_string(machine));
    json_object_object_add(meta, "date", json_object_new_string(date));
    return meta;
}

const char *report_str(json_object *o, const char *key)
{
    /* the method's full parameter string (defaults included) when known */
    if (!strcmp(key, "params") && o && json_object_object_get_ex(o, "params_full", NULL))
        key = "params_full";
    json_object *v;
    if (o && json_object_object_get_ex(o, key, &v) && json_object_is_type(v, json_type_string))
        return json_object_get_string(v);
    return "";
}

/* Number at a path of up to three keys; NaN when absent. */
double report_num(json_object *o, const char *k1, const char *k2, const char *k3)
{
    const char *keys[3] = {k1, k2, k3};
    for (int i = 0; i < 3 && keys[i]; i++) {
        json_object *v;
        if (!o || !json_object_object_get_ex(o, keys[i], &v))
            return NAN;
        o = v;
    }
    if (json_object_is_type(o, json_type_double) || json_object_is_type(o, json_type_int))
        return json_object_get_double(o);
    return NAN;
}

/* The union over all runs of the keys of object `field` ("stages",
 * "prepare_stages", "stats"), first-seen order. */
int report_key_names(json_object *runs, const char *field, const char **names, int max)
{
    int n = 0;
    size_t count = json_object_array_length(runs);
    for (size_t i = 0; i < count; i++) {
        json_object *stages;
        if (!json_object_object_get_ex(json_object_array_get_idx(runs, i), field, &stages) ||
            !json_object_is_type(stages, json_type_object))
            continue;
        json_object_object_foreach(stages, key, val)
        {
            (void)val;
            int seen = 0;
            for (int k = 0; k < n; k++)
                seen |= strcmp(names[k], key) == 0;
            if (!seen && n < max)
                names[n++] = key;
        }
    }
    return n;
}

int report_stage_names(json_object *runs, const char **names, int max)
{
    return report_key_names(runs, "stages", names, max);
}

/* Whether dir/rel is a file (links in the report point only at files that exist). */
int report_exists_in(const char *dir, const char *rel)
{
    if (!rel || !*rel)
        return 0;
    char path[4096];
    if (snprintf(path, sizeof path, "%s/%s", dir, rel) >= (int)sizeof path)
        return 0;
    struct stat sb;
    return stat(path, &sb) == 0 && S_ISREG(sb.st_mode);
}

/* A string field as stored (report_str() swaps "params" for "params_full"). */
const char *report_raw(json_object *o, const char *key)
{
    json_object *v;
    if (o && json_object_object_get_ex(o, key, &v) && json_object_is_type(v, json_type_string))
        return json_object_get_string(v);
    return "";
}

static int write_text(const char *dir, const char *name, text *t, char *why, size_t why_size)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    gi_error err;
    int ok = t->s && gi_file_write_atomic(path, t->s, t->len, &err) == GI_OK;
    if (!ok)
        snprintf(why, why_size, "%s", t->s ? err.text : "out of memory");
    free(t->s);
    memset(t, 0, sizeof *t);
    return ok;
}

int report_write(const char *dir, json_object *runs, json_object *meta, char *why, size_t why_size)
{
    text t = {0};
    /* every run record as it is (scripts read this: scripts/scale_fit.py) */
    put(&t, "%s\n",
        json_object_to_json_string_ext(runs, JSON_C_TO_STRING_PRETTY | JSON_C_TO_STRING_SPACED |
                                                 JSON_C_TO_STRING_NOSLASHESCAPE));
    if (!write_text(dir, "runs.json", &t, why, why_size))
        return 0;
    report_write_csv(&t, runs);
    if (!write_text(dir, "runs.csv", &t, why, why_size))
        return 0;
    report_write_frames_csv(&t, runs);
    if (!write_text(dir, "frames.csv", &t, why, why_size))
        return 0;
    report_write_curves_csv(&t, runs);
    if (!write_text(dir, "curves.csv", &t, why, why_size))
        return 0;
    report_write_md(&t, dir, runs, meta);
    if (!write_text(dir, "report.md", &t, why, why_size))
        return 0;
    report_write_html(&t, dir, runs, meta);
    return write_text(dir, "index.html", &t, why, why_size);
}
