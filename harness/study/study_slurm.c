/* gibench study --slurm (slurm.h): the same cells as Slurm array tasks.
 * The cells are planned exactly as the local runner plans them; this file
 * submits those not yet done, runs one cell as an array task (--cell), and
 * collects the records (--slurm-collect). docs/studies.md, "Studies on a Slurm cluster". */
#define _POSIX_C_SOURCE 200809L
#include "study_internal.h"

#include "gi/cache.h"
#include "gi/timer.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* What the planned cells are: a task refuses to run a study that has
 * changed since it was submitted (its index would name another cell). */
static uint64_t slurm_plan_hash(const study *st)
{
    uint64_t h = gi_hash64(st->name, strlen(st->name), st->run_count * 131u + st->ref_count);
    for (uint32_t i = 0; i < st->ref_count; i++)
        h = gi_hash64(st->refs[i].name, strlen(st->refs[i].name), h);
    for (uint32_t i = 0; i < st->run_count; i++)
        h = gi_hash64(st->runs[i].id, strlen(st->runs[i].id), h);
    return h;
}

/* --cell KIND:K:PLAN: one array task. "ref": reference set K, as the local
 * runner builds it; "run": run K, after checking that its references exist,
 * exactly as the local runner runs it (runner_execute, resuming). Exit 0
 * when the cell is done (or not applicable), 1 when it failed. */
int study_slurm_cell(study *st, const char *out, gi_plugins *reg, const char *cell)
{
    char kind[8];
    unsigned long k;
    unsigned long long plan;
    if (sscanf(cell, "%7[a-z]:%lu:%llx", kind, &k, &plan) != 3 ||
        (strcmp(kind, "ref") && strcmp(kind, "run")))
        return cli_fail(EXIT_USAGE, "study: --cell '%s' is not ref:K:PLAN or run:K:PLAN", cell);
    if (plan != slurm_plan_hash(st))
        return cli_fail(EXIT_USAGE,
                        "study: the study's plan changed since it was submitted: resubmit it");
    uint32_t n = !strcmp(kind, "ref") ? st->ref_count : st->run_count;
    if (k >= n)
        return cli_fail(EXIT_USAGE, "study: --cell %s: the study has %u such cells", cell, n);
    char why[1024];
    if (!strcmp(kind, "ref")) {
        /* a reference cell times the path tracer's curve in this submission */
        if (!study_build_reference_set(st, out, (uint32_t)k, STUDY_CURVES_TIME, why, sizeof why))
            return cli_fail(EXIT_RUN, "study: %s", why);
        fprintf(stderr, "study: reference set %s done\n", st->refs[k].name);
        return EXIT_OK;
    }
    study_run *r = &st->runs[k];
    if (r->ref_index >= 0) {
        runner_set_collect_only(1); /* the references stage made them */
        int ok = study_build_reference_set(st, out, (uint32_t)r->ref_index, 0, why, sizeof why);
        runner_set_collect_only(0);
        if (!ok)
            return cli_fail(EXIT_RUN, "study: run %s: %s", r->id, why);
    }
    study_attach_refs(st, r);
    double t0 = gi_now();
    r->record = study_run_or_skip(st, r, reg, 1);
    json_object *v;
    const char *status =
        json_object_object_get_ex(r->record, "status", &v) ? json_object_get_string(v) : "?";
    int cached = json_object_object_get_ex(r->record, "cached", &v) && json_object_get_boolean(v);
    const char *reason =
        json_object_object_get_ex(r->record, "reason", &v) ? json_object_get_string(v) : "";
    fprintf(stderr, "study: run %s: %s%s%s%s (%.1f s)\n", r->id, status, cached ? " (cached)" : "",
            reason[0] ? ": " : "", reason, gi_now() - t0);
    return !strcmp(status, "ok") || !strcmp(status, "n/a") ? EXIT_OK : EXIT_RUN;
}

/* --slurm: plans the cells as the local runner does, leaves out those
 * already done (resume), and hands the rest to Slurm (slurm_run). */
int study_slurm_submit(study *st, const char *file, const char *out, gi_plugins *reg,
                       const slurm_options *so)
{
    uint32_t *ref_tasks = calloc(st->ref_count + 1, sizeof *ref_tasks);
    uint32_t *run_tasks = calloc(st->run_count + 1, sizeof *run_tasks);
    if (!ref_tasks || !run_tasks) {
        free(ref_tasks);
        free(run_tasks);
        return cli_fail(EXIT_RUN, "study: out of memory");
    }
    uint32_t nref = 0, nrun = 0, cached = 0, na = 0, nmade = 0;
    char why[1024];
    runner_set_collect_only(1);
    /* one submission is one invocation (docs/studies.md "One clock per
     * comparison"): its cells inherit the id through sbatch's environment */
    uint8_t *retime = calloc(st->ref_count + 1, 1);
    for (uint32_t i = 0; i < st->ref_count; i++)
        if (!study_build_reference_set(st, out, i, 0, why, sizeof why))
            ref_tasks[nref++] = i;
        else
            retime[i] = 1; /* made: a cell only if a run compared with it runs now */
    nmade = nref;
    for (uint32_t i = 0; i < st->run_count; i++) {
        study_run *r = &st->runs[i];
        study_attach_refs(st, r);
        json_object *rec = study_run_or_skip(st, r, reg, 1), *v;
        const char *status =
            json_object_object_get_ex(rec, "status", &v) ? json_object_get_string(v) : "";
        if (json_object_object_get_ex(rec, "cached", &v))
            cached++;
        else if (!strcmp(status, "n/a"))
            na++;
        else {
            run_tasks[nrun++] = i;
            /* the curve its speed-up divides by is timed in this submission too */
            if (r->ref_index >= 0 && retime && retime[r->ref_index] == 1 && st->conv_n > 0 &&
                !st->refs[r->ref_index].frame_only) {
                retime[r->ref_index] = 2;
                ref_tasks[nref++] = (uint32_t)r->ref_index;
            }
        }
        json_object_put(rec);
    }
    free(retime);
    for (uint32_t i = 1; i < nref; i++) /* in order: the array spec joins runs of indices */
        for (uint32_t j = i; j > 0 && ref_tasks[j] < ref_tasks[j - 1]; j--) {
            uint32_t tmp = ref_tasks[j];
            ref_tasks[j] = ref_tasks[j - 1];
            ref_tasks[j - 1] = tmp;
        }
    runner_set_collect_only(0);
    fprintf(stderr,
            "study: %s: %u reference sets (%u to make), %u runs (%u done before, %u not "
            "applicable, %u to run)\n",
            st->name, st->ref_count, nmade, st->run_count, cached, na, nrun);
    if (nref > nmade)
        fprintf(stderr,
                "study: %u reference sets' convergence curves are timed again with the runs "
                "(one clock per comparison)\n",
                nref - nmade);
    /* one submission is one invocation (docs/studies.md "One clock per
     * comparison"): its cells and collect job take its id */
    study_new_invocation(st->invocation, sizeof st->invocation);
    slurm_options own = *so;
    own.invocation = st->invocation;
    slurm_stage refs = {"ref", ref_tasks, nref}, runs = {"run", run_tasks, nrun};
    int rc = slurm_run(&own, file, out, st->name, slurm_plan_hash(st), &refs, &runs);
    free(ref_tasks);
    free(run_tasks);
    return rc;
}

/* --slurm-collect REFJOB,RUNJOB: the records of every run from the cells'
 * results, running nothing; a cell without a result is a failed run whose
 * reason is how its Slurm task ended. */
void study_slurm_collect_runs(study *st, gi_plugins *reg, const char *out, const char *jobs)
{
    char ref_job[64] = "-", run_job[64] = "-";
    sscanf(jobs, "%63[^,],%63s", ref_job, run_job);
    slurm_tasks *rt = slurm_tasks_query(out, "ref", ref_job),
                *mt = slurm_tasks_query(out, "run", run_job);
    runner_set_collect_only(1);
    for (uint32_t i = 0; i < st->run_count; i++) {
        study_run *r = &st->runs[i];
        study_attach_refs(st, r);
        json_object *rec = study_run_or_skip(st, r, reg, 1), *v;
        if (json_object_object_get_ex(rec, "cached", &v)) {
            json_object_object_del(rec, "cached");
        } else if (json_object_object_get_ex(rec, "status", &v) &&
                   !strcmp(json_object_get_string(v), "failed")) {
            char why[2200], task[1000];
            if (r->ref_index >= 0 && st->refs[r->ref_index].missing[0]) {
                slurm_tasks_describe(rt, (uint32_t)r->ref_index, task, sizeof task);
                snprintf(why, sizeof why, "no reference (%s): %s", st->refs[r->ref_index].missing,
                         task);
            } else {
                slurm_tasks_describe(mt, i, task, sizeof task);
                snprintf(why, sizeof why, "no result: %s", task);
            }
            json_object_object_add(rec, "reason", json_object_new_string(why));
            json_object_object_del(rec, "config");
            fprintf(stderr, "study: run %s: %s\n", r->id, why);
        }
        r->record = rec;
    }
    runner_set_collect_only(0);
    slurm_tasks_free(rt);
    slurm_tasks_free(mt);
}
