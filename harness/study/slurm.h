/* gibench study --slurm: a study's cells as Slurm job arrays. The study
 * runner (study_slurm.c) plans the cells exactly as it does locally; this
 * file writes the job scripts (one array per stage: references, then the
 * method runs with an afterok dependency, then one collect job that writes
 * the report), submits them with sbatch, waits by polling squeue, and
 * tells the collect job how each missing cell's task ended (sacct, else
 * scontrol, else the task's log). docs/studies.md, "Studies on a Slurm cluster". */
#ifndef GIBENCH_SLURM_H
#define GIBENCH_SLURM_H

#include <stddef.h>
#include <stdint.h>

typedef struct slurm_options {
    int enabled;           /* --slurm */
    const char *partition; /* --partition P */
    const char *gres;      /* --gres G, e.g. gpu:1 */
    const char *time;      /* --time T: each task's limit, in Slurm's format */
    unsigned long
        array_limit;     /* --array-limit K: at most K tasks of a stage at once (0: no limit) */
    int no_wait;         /* --no-wait: return once submitted */
    int dry_run;         /* --dry-run with --slurm: print the scripts */
    const char *cell;    /* hidden --cell ref:K:PLAN or run:K:PLAN: one array task */
    const char *collect; /* hidden --slurm-collect REFJOB,RUNJOB: the collect job */
    int mix_clocks;      /* gibench study --mix-clocks: passed on to the collect job */
    /* the submission's invocation id, given to every cell and the collect job
     * (GIBENCH_STUDY_INVOCATION: one submission is one clock, docs/studies.md) */
    const char *invocation;
} slurm_options;

/* Takes argv[*i] (and its value) when it is one of the options above,
 * advancing *i: 1 taken, 0 not one of them, -1 after printing a one-line
 * error (a missing or malformed value). */
int slurm_take_option(int argc, char **argv, int *i, slurm_options *o);

/* Checks the options together (values, sbatch on PATH unless a dry run,
 * the output directory usable in a script). EXIT_OK or EXIT_USAGE after a
 * one-line error. */
int slurm_check(const slurm_options *o, const char *file, const char *out);

/* One stage's array: the task indices (cells) that still need running. */
typedef struct slurm_stage {
    const char *kind; /* "ref" or "run": the cell kind (--cell KIND:K) */
    const uint32_t *tasks;
    uint32_t n;
} slurm_stage;

/* Writes DIR/slurm/{refs,runs,collect}.sh, and unless a dry run (which
 * prints them) submits them and, unless --no-wait, waits for the collect
 * job. `plan` identifies the planned cells (a task refuses a study changed
 * since). Returns the exit status for gibench. */
int slurm_run(const slurm_options *o, const char *file, const char *out, const char *name,
              uint64_t plan, const slurm_stage *refs, const slurm_stage *runs);

/* The collect job's view of one stage's tasks: why task K of job `job`
 * (its array job id, "-" for none) left no result: Slurm's state and exit
 * code where sacct or scontrol still know it, and what the task's log
 * (DIR/slurm/logs/KIND-JOB_K.log) says. */
typedef struct slurm_tasks slurm_tasks;
slurm_tasks *slurm_tasks_query(const char *out, const char *kind, const char *job);
void slurm_tasks_describe(const slurm_tasks *t, uint32_t task, char *buf, size_t size);
void slurm_tasks_free(slurm_tasks *t);

#endif
