/* One clock per comparison (issue 34; docs/studies.md "One clock per
 * comparison"). CPU time on shared machines drifts between sessions by
 * 1.5x and more, so a speed-up is only a measurement when the method's run
 * and the path tracer's convergence curve it is divided by were timed in
 * the same invocation of gibench study. Each invocation has an id, written
 * into every run record it times and into every curve it times; the report
 * refuses tables whose times come from several invocations unless told to
 * (--mix-clocks), and then says so per table. */
#define _POSIX_C_SOURCE 200809L
#include "study_internal.h"

#include "gi/cache.h"
#include "gi/timer.h"

#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

void study_new_invocation(char *out, size_t size)
{
    uint64_t rnd = 0;
    int fd = open("/dev/urandom", O_RDONLY | O_CLOEXEC);
    if (fd < 0 || read(fd, &rnd, sizeof rnd) != (ssize_t)sizeof rnd)
        rnd = gi_hash64(&rnd, sizeof rnd, (uint64_t)(gi_now() * 1e9) ^ (uint64_t)getpid());
    if (fd >= 0)
        close(fd);
    time_t now = time(NULL);
    struct tm tm;
    char when[32] = "0";
    if (gmtime_r(&now, &tm))
        strftime(when, sizeof when, "%Y%m%dT%H%M%SZ", &tm);
    snprintf(out, size, "%s-%ld-%04x", when, (long)getpid(), (unsigned)(rnd & 0xffffu));
}

static const char *record_invocation(json_object *rec)
{
    json_object *v;
    return rec && json_object_object_get_ex(rec, "invocation", &v) ? json_object_get_string(v) : "";
}

static int record_ok(json_object *rec)
{
    json_object *v;
    return rec && json_object_object_get_ex(rec, "status", &v) &&
           !strcmp(json_object_get_string(v), "ok");
}

int study_timed_now(const study *st, const study_run *r)
{
    return record_ok(r->record) && !strcmp(record_invocation(r->record), st->invocation);
}

/* Whether run r's times are divided by a path tracer's curve: a compared,
 * finished, not animated run of a set that has curves. */
static int run_on_curve(const study *st, const study_run *r)
{
    if (r->ref_index < 0 || r->spec.animate_fps > 0 || !record_ok(r->record))
        return 0;
    const study_ref *sc = &st->refs[r->ref_index];
    return !sc->frame_only && st->conv_n > 0 && !sc->missing[0];
}

/* The invocations of a study's compared timings and, per invocation, what
 * was timed in it (for the refusal's line). */
typedef struct clock_set {
    char id[32][64];
    uint32_t runs[32], curves[32], n, more;
    char named[32][200];
} clock_set;

static void clock_add(clock_set *cs, const char *id, const char *what, int is_curve)
{
    uint32_t k = 0;
    while (k < cs->n && strcmp(cs->id[k], id))
        k++;
    if (k == cs->n) {
        if (cs->n == 32) {
            cs->more++;
            return;
        }
        snprintf(cs->id[cs->n++], sizeof cs->id[0], "%s", id);
    }
    uint32_t listed = cs->runs[k] + cs->curves[k];
    if (is_curve)
        cs->curves[k]++;
    else
        cs->runs[k]++;
    size_t used = strlen(cs->named[k]);
    if (listed < 3)
        snprintf(cs->named[k] + used, sizeof cs->named[k] - used, "%s%s", listed ? ", " : "", what);
}

int study_runs_mixed(const study *st)
{
    const char *first = NULL;
    for (uint32_t i = 0; i < st->run_count; i++)
        if (run_on_curve(st, &st->runs[i])) {
            const char *id = record_invocation(st->runs[i].record);
            if (!first)
                first = id;
            else if (strcmp(first, id))
                return 1;
        }
    return 0;
}

int study_check_clocks(const study *st, int *mixed)
{
    clock_set *cs = calloc(1, sizeof *cs);
    if (!cs)
        return cli_fail(EXIT_RUN, "study: out of memory");
    *mixed = 0;
    for (uint32_t ri = 0; ri < st->ref_count; ri++) {
        const study_ref *sc = &st->refs[ri];
        if (sc->frame_only || st->conv_n == 0 || sc->missing[0])
            continue;
        char what[400];
        /* a curve not timed (an interrupted study) has no invocation and no points */
        if (sc->pt_full.invocation[0]) {
            snprintf(what, sizeof what, "curve %s", sc->name);
            clock_add(cs, sc->pt_full.invocation, what, 1);
        }
        for (uint32_t k = 0; k < sc->matched_count; k++)
            if (sc->pt_matched[k].invocation[0]) {
                snprintf(what, sizeof what, "curve %s b%u", sc->name, sc->pt_matched[k].bounces);
                clock_add(cs, sc->pt_matched[k].invocation, what, 1);
            }
    }
    for (uint32_t i = 0; i < st->run_count; i++)
        if (run_on_curve(st, &st->runs[i])) {
            const char *id = record_invocation(st->runs[i].record);
            clock_add(cs, *id ? id : "(not recorded)", st->runs[i].id, 0);
        }
    int rc = EXIT_OK;
    if (cs->n + cs->more > 1) {
        char line[4096] = "";
        for (uint32_t k = 0; k < cs->n; k++) {
            size_t used = strlen(line);
            uint32_t all = cs->runs[k] + cs->curves[k];
            snprintf(line + used, sizeof line - used, "%s%s: %s%s", k ? "; " : "", cs->id[k],
                     cs->named[k], all > 3 ? " and more" : "");
        }
        *mixed = 1;
        if (st->mix_clocks || cli_interrupted)
            fprintf(stderr, "study: clocks mixed (%u invocations: %s); the tables say so\n",
                    cs->n + cs->more, line);
        else
            rc = cli_fail(EXIT_USAGE,
                          "study: the speed-up tables would mix clocks of %u invocations (%s); "
                          "rerun with --fresh to time every run and the path tracer's curve "
                          "in one invocation, or pass --mix-clocks",
                          cs->n + cs->more, line);
    }
    free(cs);
    return rc;
}

/* ---- the path tracer's curve, as one invocation timed it ----------------
 * references/STEM_conv_[bB_]curve[_center].json: the invocation, a key
 * (the reference's own key, the sample counts, repeats, timer and seed:
 * a curve of other settings is timed again) and per point the relMSE and
 * every timed sample. */

void study_curve_record_path(const study *st, const char *out_dir, const study_ref *sc,
                             uint32_t bounces, char *path, size_t size)
{
    char b[32] = "";
    if (bounces != st->ref_bounces)
        snprintf(b, sizeof b, "b%u_", bounces);
    snprintf(path, size, "%s/references/%s_conv_%scurve%s.json", out_dir, sc->name, b,
             st->ref_pixel_center ? "_center" : "");
}

void study_curve_key(const study *st, const char *reference, uint32_t bounces, char *key,
                     size_t size)
{
    char cfg[4200];
    snprintf(cfg, sizeof cfg, "%s.config", reference);
    size_t n = 0;
    char *rk = gi_file_read_all(cfg, &n);
    int used = snprintf(key, size, "bounces %u repeats %u timer %s seed %u spp", bounces,
                        st->conv_repeats, st->timer ? st->timer : "wall", st->seed + 7919);
    for (uint32_t c = 0; c < st->conv_n && used > 0 && (size_t)used < size; c++)
        used += snprintf(key + used, size - (size_t)used, " %u", st->conv_spp[c]);
    if (used > 0 && (size_t)used < size)
        snprintf(key + used, size - (size_t)used, "\n%s", rk ? rk : "(no reference key)");
    free(rk);
}

int study_curve_load(const char *path, const char *key, tradeoff_pt_curve *curve)
{
    json_object *o = cli_read_json(path), *v, *pts;
    int ok =
        o && json_object_object_get_ex(o, "key", &v) && !strcmp(json_object_get_string(v), key) &&
        json_object_object_get_ex(o, "invocation", &v) &&
        json_object_object_get_ex(o, "points", &pts) && json_object_is_type(pts, json_type_array);
    if (ok) {
        snprintf(curve->invocation, sizeof curve->invocation, "%s",
                 json_object_get_string(json_object_object_get(o, "invocation")));
        curve->n = 0;
        for (size_t i = 0; i < json_object_array_length(pts) && curve->n < TRADEOFF_PT_POINTS;
             i++) {
            json_object *p = json_object_array_get_idx(pts, i);
            uint32_t k = curve->n++;
            curve->e[k] = json_object_get_double(json_object_object_get(p, "relmse"));
            curve->spp[k] = (uint32_t)json_object_get_int64(json_object_object_get(p, "spp"));
            curve->t[k] = json_object_get_double(json_object_object_get(p, "seconds_median"));
            curve->t_lo[k] = json_object_get_double(json_object_object_get(p, "seconds_min"));
            curve->t_hi[k] = json_object_get_double(json_object_object_get(p, "seconds_max"));
            json_object *s = json_object_object_get(p, "seconds");
            curve->samples[k] = s ? (uint32_t)json_object_array_length(s) : 0;
        }
    }
    json_object_put(o);
    return ok;
}

int study_curve_save(const char *path, const char *key, const tradeoff_pt_curve *curve,
                     double samples[][64], char *why, size_t why_size)
{
    json_object *o = json_object_new_object(), *pts = json_object_new_array();
    json_object_object_add(o, "invocation", json_object_new_string(curve->invocation));
    json_object_object_add(o, "key", json_object_new_string(key));
    json_object_object_add(o, "bounces", json_object_new_int((int32_t)curve->bounces));
    for (uint32_t k = 0; k < curve->n; k++) {
        json_object *p = json_object_new_object(), *s = json_object_new_array();
        for (uint32_t r = 0; r < curve->samples[k]; r++)
            json_object_array_add(s, json_object_new_double(samples[k][r]));
        json_object_object_add(p, "spp", json_object_new_int((int32_t)curve->spp[k]));
        json_object_object_add(p, "relmse", json_object_new_double(curve->e[k]));
        json_object_object_add(p, "seconds", s);
        json_object_object_add(p, "seconds_median", json_object_new_double(curve->t[k]));
        json_object_object_add(p, "seconds_min", json_object_new_double(curve->t_lo[k]));
        json_object_object_add(p, "seconds_max", json_object_new_double(curve->t_hi[k]));
        json_object_array_add(pts, p);
    }
    json_object_object_add(o, "points", pts);
    int ok = cli_write_json(path, o, why, why_size);
    json_object_put(o);
    return ok;
}
