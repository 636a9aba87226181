/* A study's runs executed (docs/studies.md, "gibench study"): each run in a child
 * process (runner.h), by a pool of worker processes or one after another,
 * cached by its configuration's hash, with a progress line per run. */
#define _POSIX_C_SOURCE 200809L
#include "study_internal.h"

#include "gi/timer.h"

#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

/* An executed run's record names the invocation that timed it, in its
 * result.json too, so that a later report knows which clock its times
 * come from (issue 34, docs/studies.md "One clock per comparison"). */
static void stamp_invocation(const study *st, const study_run *r, json_object *rec)
{
    json_object *v;
    if (json_object_object_get_ex(rec, "cached", &v) ||
        !json_object_object_get_ex(rec, "status", &v) || strcmp(json_object_get_string(v), "ok"))
        return;
    json_object_object_add(rec, "invocation", json_object_new_string(st->invocation));
    char path[4200], why[GI_ERROR_MAX];
    snprintf(path, sizeof path, "%s/result.json", r->spec.dir);
    if (!cli_write_json(path, rec, why, sizeof why))
        fprintf(stderr, "study: %s\n", why);
}

/* A record for a run, or "n/a" when the method's caps do not cover its scene. */
json_object *study_run_or_skip(const study *st, study_run *r, gi_plugins *reg, int resume)
{
    gi_error err;
    gi_scene *s = gi_scene_load(r->spec.scene, &err);
    char why[256];
    const gi_method *m = gi_plugins_find(reg, r->spec.method);
    json_object *rec;
    if (s && m && !cli_caps_cover(m, s, r->spec.animate_fps > 0, why, sizeof why))
        rec = runner_not_applicable(&r->spec, why);
    else
        rec = runner_execute(&r->spec, resume);
    stamp_invocation(st, r, rec);
    gi_scene_free(s);
    return rec;
}

/* Progress of one worker's share of the runs: one line per run, saying
 * whether it ran or came from a earlier result, with elapsed time and an
 * ETA from the runs executed so far. */
typedef struct run_progress {
    double start, ran_seconds;
    uint32_t ran, left;
} run_progress;

static void report_run(run_progress *p, const study *st, uint32_t i, json_object *rec,
                       double seconds, const char *who)
{
    json_object *v;
    const char *status =
        json_object_object_get_ex(rec, "status", &v) ? json_object_get_string(v) : "?";
    int cached = json_object_object_get_ex(rec, "cached", &v) && json_object_get_boolean(v);
    json_object_object_del(rec, "cached"); /* what the runner told us, not part of the record */
    const char *what = !strcmp(status, "ok") ? (cached ? "cached" : "ran") : status;
    if (!strcmp(what, "ran") || !strcmp(what, "failed")) {
        p->ran++;
        p->ran_seconds += seconds;
    }
    if (p->left)
        p->left--;
    char el[32], eta[32] = "?";
    cli_format_duration(gi_now() - p->start, el, sizeof el);
    if (p->ran)
        cli_format_duration(p->ran_seconds / p->ran * p->left, eta, sizeof eta);
    const run_spec *s = &st->runs[i].spec;
    char params[256] = "";
    for (uint32_t k = 0; k < s->param_count; k++) {
        size_t used = strlen(params);
        snprintf(params + used, sizeof params - used, "%s%s", k ? "," : " ", s->params[k]);
    }
    fprintf(stderr, "study: %s[%u/%u] %s %s (%s%s) %.1f s; elapsed %s, ETA %s\n", who, i + 1,
            st->run_count, what, st->runs[i].id, s->method, params, seconds, el,
            p->left ? eta : "0:00");
}

/* Runs every run not yet done: `jobs` worker processes, each taking runs
 * i, i+jobs, ...; results land in each run's result.json. */
void study_execute_runs(study *st, uint32_t jobs, int mode, gi_plugins *reg)
{
    for (uint32_t i = 0; i < st->run_count; i++)
        study_attach_refs(st, &st->runs[i]);
    if (jobs <= 1) {
        /* once interrupted, the runs left are not started: they are
         * reported as interrupted (or as done, when a result is cached) */
        run_progress p = {gi_now(), 0, 0, st->run_count};
        for (uint32_t i = 0; i < st->run_count; i++) {
            double t0 = gi_now();
            st->runs[i].record =
                study_run_or_skip(st, &st->runs[i], reg, cli_interrupted ? RUNNER_RESUME : mode);
            if (!cli_interrupted)
                report_run(&p, st, i, st->runs[i].record, gi_now() - t0, "");
            else
                json_object_object_del(st->runs[i].record, "cached");
        }
        return;
    }
    pid_t *pids = calloc(jobs, sizeof *pids);
    for (uint32_t j = 0; j < jobs && pids; j++) {
        pid_t pid = fork();
        if (pid == 0) {
            run_progress p = {gi_now(), 0, 0, (st->run_count - j + jobs - 1) / jobs};
            char who[32];
            snprintf(who, sizeof who, "worker %u ", j);
            for (uint32_t i = j; i < st->run_count && !cli_interrupted; i += jobs) {
                double t0 = gi_now();
                json_object *rec = study_run_or_skip(st, &st->runs[i], reg, mode);
                if (!cli_interrupted)
                    report_run(&p, st, i, rec, gi_now() - t0, who);
                json_object_put(rec);
            }
            _exit(0);
        }
        pids[j] = pid;
    }
    /* An interrupted study passes SIGTERM on to its workers (a SIGTERM sent
     * to the study alone does not reach them), which stop their runs'
     * process groups (cli_run) and start no more. */
    int forwarded = 0;
    for (uint32_t j = 0; j < jobs && pids; j++) {
        while (pids[j] > 0 && waitpid(pids[j], NULL, 0) < 0 && errno == EINTR) {
            if (cli_interrupted && !forwarded) {
                for (uint32_t k = 0; k < jobs; k++)
                    if (pids[k] > 0)
                        kill(pids[k], SIGTERM);
                forwarded = 1;
            }
        }
    }
    free(pids);
    /* collect: every worker wrote result.json; resume picks them up */
    for (uint32_t i = 0; i < st->run_count; i++) {
        st->runs[i].record = study_run_or_skip(st, &st->runs[i], reg, RUNNER_RESUME);
        json_object_object_del(st->runs[i].record, "cached");
    }
}
