/* Job arrays, submission, waiting and task states of gibench study
 * --slurm (slurm.h). Slurm is driven through its commands (sbatch, squeue,
 * sacct, scontrol), as a user would, never through its libraries. */
#define _POSIX_C_SOURCE 200809L
#include "slurm.h"

#include "cli.h"
#include "gi/cache.h"
#include "proc.h"
#include "report.h"
#include "text.h"

#include <ctype.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

/* Value of an option that takes one: argv[*i + 1], or NULL after an error. */
static const char *value_of(int argc, char **argv, int *i)
{
    if (*i + 1 >= argc) {
        cli_fail(EXIT_USAGE, "study: %s needs a value", argv[*i]);
        return NULL;
    }
    return argv[++*i];
}

/* Whether every character of s is alphanumeric or in `extra`, and s is not empty. */
static int chars_in(const char *s, const char *extra)
{
    if (!*s)
        return 0;
    for (; *s; s++)
        if (!isalnum((unsigned char)*s) && !strchr(extra, *s))
            return 0;
    return 1;
}

int slurm_take_option(int argc, char **argv, int *i, slurm_options *o)
{
    const char *a = argv[*i], *v;
    if (!strcmp(a, "--slurm")) {
        o->enabled = 1;
        return 1;
    }
    if (!strcmp(a, "--no-wait")) {
        o->no_wait = 1;
        return 1;
    }
    const char **dest = !strcmp(a, "--partition")       ? &o->partition
                        : !strcmp(a, "--gres")          ? &o->gres
                        : !strcmp(a, "--time")          ? &o->time
                        : !strcmp(a, "--cell")          ? &o->cell
                        : !strcmp(a, "--slurm-collect") ? &o->collect
                                                        : NULL;
    if (dest) {
        if (!(v = value_of(argc, argv, i)))
            return -1;
        *dest = v;
        return 1;
    }
    if (!strcmp(a, "--array-limit")) {
        if (!(v = value_of(argc, argv, i)))
            return -1;
        if (!cli_parse_uint(v, 1, 100000, &o->array_limit)) {
            cli_fail(EXIT_USAGE, "study: --array-limit '%s' is not an integer in 1..100000", v);
            return -1;
        }
        return 1;
    }
    return 0;
}

/* The path of `name` in a directory of PATH (into out), or 0 when none
 * holds it as an executable file. */
static int find_on_path(const char *name, char *out, size_t size)
{
    const char *path = getenv("PATH");
    for (const char *p = path ? path : ""; *p;) {
        size_t n = strcspn(p, ":");
        snprintf(out, size, "%.*s/%s", (int)(n ? n : 1), n ? p : ".", name);
        if (access(out, X_OK) == 0)
            return 1;
        p += n;
        if (*p == ':')
            p++;
    }
    return 0;
}

static int on_path(const char *name)
{
    char tmp[4200];
    return find_on_path(name, tmp, sizeof tmp);
}

/* Runs a Slurm command (argv[0] a name looked up on PATH) with its output
 * in out_path; cli_run wants a path. 1 when it exited 0. */
static int run_tool(char *const argv[], const char *out_path, const char *err_path,
                    cli_proc_result *r)
{
    char exe[4200];
    char *args[16];
    int n = 0;
    for (; argv[n] && n < 15; n++)
        args[n] = argv[n];
    args[n] = NULL;
    memset(r, 0, sizeof *r);
    if (!find_on_path(argv[0], exe, sizeof exe)) {
        snprintf(r->last_line, sizeof r->last_line, "%s is not on PATH", argv[0]);
        return 0;
    }
    args[0] = exe;
    return cli_run(args, 120, out_path, err_path, r) == 0 && !r->timed_out && !r->signaled &&
           r->exit_code == 0;
}

/* Slurm's time formats: minutes, MM:SS, HH:MM:SS, D-HH, D-HH:MM, D-HH:MM:SS. */
static int valid_time(const char *t)
{
    const char *dash = strchr(t, '-');
    int colons = 0;
    for (const char *p = dash ? dash + 1 : t; *p; p++) {
        if (*p == ':') {
            if (p[1] == ':' || p[1] == '\0' || p == t || p[-1] == '-')
                return 0;
            colons++;
        } else if (!isdigit((unsigned char)*p))
            return 0;
    }
    if (dash) {
        if (dash == t || dash[1] == '\0' || colons > 2)
            return 0;
        for (const char *p = t; p < dash; p++)
            if (!isdigit((unsigned char)*p))
                return 0;
        return 1;
    }
    return *t && colons <= 2;
}

int slurm_check(const slurm_options *o, const char *file, const char *out)
{
    if (o->cell || o->collect) {
        if (o->enabled)
            return cli_fail(
                EXIT_USAGE,
                "study: --cell and --slurm-collect are for Slurm's tasks, not with --slurm");
        return EXIT_OK;
    }
    if (!o->enabled) {
        if (o->partition || o->gres || o->time || o->array_limit || o->no_wait)
            return cli_fail(
                EXIT_USAGE,
                "study: --partition, --gres, --time, --array-limit and --no-wait go with --slurm");
        return EXIT_OK;
    }
    if (o->partition && !chars_in(o->partition, "_-.,"))
        return cli_fail(
            EXIT_USAGE,
            "study: --partition '%s' is not a partition name (letters, digits, _ - . ,)",
            o->partition);
    if (o->gres && !chars_in(o->gres, "_-.,:=/"))
        return cli_fail(EXIT_USAGE, "study: --gres '%s' is not a generic resource such as gpu:1",
                        o->gres);
    if (o->time && !valid_time(o->time))
        return cli_fail(EXIT_USAGE,
                        "study: --time '%s' is not a Slurm time (minutes, MM:SS, HH:MM:SS, D-HH, "
                        "D-HH:MM, D-HH:MM:SS)",
                        o->time);
    /* the paths go into #SBATCH lines and shell words: nothing to quote */
    const char *paths[2] = {file, out};
    for (int k = 0; k < 2; k++)
        if (!chars_in(paths[k], "_-.,/+=@%"))
            return cli_fail(
                EXIT_USAGE,
                "study: --slurm needs %s '%s' without blanks, quotes or shell characters",
                k ? "an output directory" : "a study file name", paths[k]);
    if (!o->dry_run)
        for (int k = 0; k < 2; k++) {
            const char *cmd = k ? "squeue" : "sbatch";
            if (!on_path(cmd))
                return cli_fail(EXIT_USAGE,
                                "study: --slurm: %s is not on PATH (is this a Slurm login node?)",
                                cmd);
        }
    return EXIT_OK;
}

/* The task list of an array, as ranges: "0-3,7,9-12", with %K. */
static char *array_spec(const slurm_stage *s, unsigned long limit)
{
    size_t cap = (size_t)s->n * 24 + 32, used = 0;
    char *b = malloc(cap);
    if (!b)
        return NULL;
    b[0] = '\0';
    for (uint32_t i = 0; i < s->n;) {
        uint32_t j = i;
        while (j + 1 < s->n && s->tasks[j + 1] == s->tasks[j] + 1)
            j++;
        used += (size_t)snprintf(b + used, cap - used, j > i ? "%s%u-%u" : "%s%u", i ? "," : "",
                                 s->tasks[i], s->tasks[j]);
        i = j + 1;
    }
    if (limit)
        snprintf(b + used, cap - used, "%%%lu", limit);
    return b;
}

/* The #SBATCH lines every script shares. */
static void common_lines(gi_text *t, const slurm_options *o, const char *name, const char *what,
                         const char *out, const char *log, const char *cwd)
{
    gi_text_put(t, "#SBATCH --job-name=gibench-%s-%s\n", name, what);
    gi_text_put(t, "#SBATCH --output=%s/slurm/logs/%s\n", out, log);
    gi_text_put(t, "#SBATCH --chdir=%s\n", cwd);
    gi_text_put(t, "#SBATCH --ntasks=1\n");
    if (o->partition)
        gi_text_put(t, "#SBATCH --partition=%s\n", o->partition);
    if (o->gres)
        gi_text_put(t, "#SBATCH --gres=%s\n", o->gres);
    if (o->time)
        gi_text_put(t, "#SBATCH --time=%s\n", o->time);
}

/* The submission's invocation id for the cells and the collect job, after
 * the #SBATCH lines (set in the script: a site's SBATCH_EXPORT=NONE would
 * drop it from the environment). The id is [0-9A-Za-z-] only. */
static void put_invocation(gi_text *t, const slurm_options *o)
{
    if (o->invocation && o->invocation[0] &&
        strspn(o->invocation, "0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz-") ==
            strlen(o->invocation))
        gi_text_put(t, "GIBENCH_STUDY_INVOCATION=%s\nexport GIBENCH_STUDY_INVOCATION\n",
                    o->invocation);
}

/* The script of one stage's array: each task runs one cell (--cell). */
static char *stage_script(const slurm_options *o, const char *file, const char *out,
                          const char *name, uint64_t plan, const slurm_stage *s, const char *cwd)
{
    char *spec = array_spec(s, o->array_limit);
    if (!spec)
        return NULL;
    gi_text t = {0};
    gi_text_put(
        &t,
        "#!/bin/sh\n# gibench study %s: the %s stage, one array task per cell\n"
        "# (written by gibench study --slurm; the task index is the cell's index in the plan)\n",
        name, !strcmp(s->kind, "ref") ? "reference" : "method-run");
    char log[64];
    snprintf(log, sizeof log, "%s-%%A_%%a.log", s->kind);
    slurm_options own = *o;
    if (!strcmp(s->kind, "ref"))
        own.gres = NULL; /* the reference renders on the CPU (Embree): --gres is for the runs */
    common_lines(&t, &own, name, !strcmp(s->kind, "ref") ? "refs" : "runs", out, log, cwd);
    gi_text_put(&t, "#SBATCH --array=%s\n", spec);
    put_invocation(&t, o);
    gi_text_put(&t,
                "'%s' study '%s' --out '%s' --cell %s:\"$SLURM_ARRAY_TASK_ID\":%016llx\n"
                "rc=$?\necho \"gibench-cell-exit $rc\"\nexit $rc\n",
                cli_self_exe(), file, out, s->kind, (unsigned long long)plan);
    free(spec);
    return t.s;
}

/* The collect job: the report from the cells' results ($1, $2: the array job ids). */
static char *collect_script(const slurm_options *o, const char *file, const char *out,
                            const char *name, const char *cwd)
{
    gi_text t = {0};
    gi_text_put(&t,
                "#!/bin/sh\n# gibench study %s: the report from the cells' results\n"
                "# (written by gibench study --slurm; $1 and $2: the reference and method-run "
                "array jobs)\n",
                name);
    slurm_options plain = *o;
    plain.gres = NULL; /* the report needs no GPU */
    common_lines(&t, &plain, name, "collect", out, "collect-%j.log", cwd);
    put_invocation(&t, o);
    gi_text_put(&t,
                "'%s' study '%s' --out '%s' --slurm-collect \"$1,$2\"%s\nrc=$?\necho "
                "\"gibench-cell-exit $rc\"\nexit $rc\n",
                cli_self_exe(), file, out, o->mix_clocks ? " --mix-clocks" : "");
    return t.s;
}

/* Runs a Slurm command; its first output line into `line`, its last error
 * line into `err`. 1 when it exited 0. */
static int slurm_cmd(char *const argv[], const char *out, char *line, size_t size, char *err,
                     size_t err_size)
{
    char o[4200], e[4200];
    snprintf(o, sizeof o, "%s/slurm/.cmd.out", out);
    snprintf(e, sizeof e, "%s/slurm/.cmd.err", out);
    cli_proc_result r;
    int ok = run_tool(argv, o, e, &r);
    if (err)
        snprintf(err, err_size, "%s", r.last_line);
    if (line) {
        size_t n = 0;
        char *text = gi_file_read_all(o, &n);
        snprintf(line, size, "%s", text ? text : "");
        line[strcspn(line, "\n")] = '\0';
        free(text);
    }
    unlink(o);
    unlink(e);
    return ok;
}

/* sbatch --parsable [extra...] script [args...]: the job id, or 0 after printing why. */
static int submit(const char *out, const char *script, const char *dep, const char *a1,
                  const char *a2, char *id, size_t size)
{
    char *argv[12];
    int n = 0;
    argv[n++] = "sbatch";
    argv[n++] = "--parsable";
    if (dep) {
        argv[n++] = (char *)dep;
        argv[n++] = "--kill-on-invalid-dep=yes";
    }
    argv[n++] = (char *)script;
    if (a1) {
        argv[n++] = (char *)a1;
        argv[n++] = (char *)a2;
    }
    argv[n] = NULL;
    char err[600];
    if (!slurm_cmd(argv, out, id, size, err, sizeof err) || !id[0])
        return cli_fail(EXIT_RUN, "study: sbatch %s: %s", script, err[0] ? err : "no job id"), 0;
    id[strcspn(id, ";")] = '\0'; /* "id;cluster" on federations */
    return 1;
}

static int write_script(const char *path, const char *text)
{
    gi_error err;
    if (!text || gi_file_write_atomic(path, text, strlen(text), &err) != GI_OK)
        return cli_fail(EXIT_RUN, "study: cannot write %s", path), 0;
    return 1;
}

/* Whether the job is still queued or running (squeue lists it in such a state). */
static int job_active(const char *out, const char *job, int *known)
{
    char *argv[] = {"squeue", "-h", "-t", "all", "-j", (char *)job, "-o", "%T", NULL};
    char state[256], err[600];
    int ok = slurm_cmd(argv, out, state, sizeof state, err, sizeof err);
    if (!ok) {
        /* a job the controller forgot ("Invalid job id") is over; another error may pass */
        *known = strstr(err, "Invalid job id") != NULL;
        return !*known;
    }
    *known = 1;
    static const char *active[] = {"PENDING",   "RUNNING",   "CONFIGURING",  "COMPLETING",
                                   "SUSPENDED", "REQUEUED",  "REQUEUE_HOLD", "REQUEUE_FED",
                                   "RESIZING",  "SIGNALING", "STAGE_OUT",    NULL};
    for (int k = 0; active[k]; k++)
        if (!strcmp(state, active[k]))
            return 1;
    return 0; /* ended (or not listed: over) */
}

/* The last line before "gibench-cell-exit N" in a task's log, and N (-1: no such line). */
static int log_exit(const char *path, char *last, size_t size, int *exists)
{
    size_t n = 0;
    char *text = gi_file_read_all(path, &n);
    *exists = text != NULL;
    last[0] = '\0';
    int code = -1;
    for (char *line = text, *next; line && *line; line = next) {
        next = strchr(line, '\n');
        if (next)
            *next++ = '\0';
        else
            next = line + strlen(line);
        int c;
        if (sscanf(line, "gibench-cell-exit %d", &c) == 1)
            code = c;
        else if (*line)
            snprintf(last, size, "%s", line);
    }
    free(text);
    return code;
}

/* The job ids of one submission: "-" for a stage with no tasks. */
typedef struct stage_jobs {
    char ref[64], run[64], col[64];
} stage_jobs;

/* The three job scripts (texts[k] NULL: the stage has no tasks), printed
 * for a dry run or else written into dir as paths[k]. */
static int write_scripts(const slurm_options *o, const char *dir, const char *logs,
                         char *const texts[3], char paths[3][4400], const slurm_stage *refs,
                         const slurm_stage *runs)
{
    const char *names[3] = {"refs.sh", "runs.sh", "collect.sh"};
    int rc = EXIT_OK;
    if (o->dry_run) {
        for (int k = 0; k < 3; k++)
            if (texts[k])
                printf("==> %s/%s <==\n%s\n", dir, names[k], texts[k]);
        printf("# %u reference cells and %u method-run cells to submit; then: sbatch --parsable "
               "refs.sh; "
               "sbatch --parsable --dependency=afterany:REFS runs.sh; "
               "sbatch --parsable --dependency=afterany:REFS:RUNS collect.sh REFS RUNS\n",
               refs->n, runs->n);
    } else if (!cli_mkdirs(logs)) {
        rc = cli_fail(EXIT_RUN, "study: cannot create %s", logs);
    } else {
        for (int k = 0; k < 3 && rc == EXIT_OK; k++) {
            snprintf(paths[k], sizeof paths[k], "%s/%s", dir, names[k]);
            if (texts[k] && !write_script(paths[k], texts[k]))
                rc = EXIT_RUN;
        }
    }
    return rc;
}

/* Submits the references, then the runs after them, then the collect job
 * after both; the ids into *j. The runs wait for the whole reference array
 * to end (afterany, not afterok): a run task checks its own reference and
 * fails alone when that one is missing, so one failed reference costs its
 * scene's runs, not every run of the study. */
static int submit_stages(const char *out, char paths[3][4400], const slurm_stage *refs,
                         const slurm_stage *runs, stage_jobs *j)
{
    int rc = EXIT_OK;
    char dep[200];
    if (refs->n && !submit(out, paths[0], NULL, NULL, NULL, j->ref, sizeof j->ref))
        rc = EXIT_RUN;
    snprintf(dep, sizeof dep, "--dependency=afterany:%s", j->ref);
    if (rc == EXIT_OK && runs->n &&
        !submit(out, paths[1], refs->n ? dep : NULL, NULL, NULL, j->run, sizeof j->run))
        rc = EXIT_RUN;
    if (refs->n && runs->n)
        snprintf(dep, sizeof dep, "--dependency=afterany:%s:%s", j->ref, j->run);
    else
        snprintf(dep, sizeof dep, "--dependency=afterany:%s", refs->n ? j->ref : j->run);
    if (rc == EXIT_OK && !submit(out, paths[2], refs->n || runs->n ? dep : NULL, j->ref, j->run,
                                 j->col, sizeof j->col))
        rc = EXIT_RUN;
    /* a submitted job whose followers could not be: cancelled, not left behind */
    if (rc != EXIT_OK) {
        char *ids[2] = {j->ref, j->run};
        for (int k = 0; k < 2; k++)
            if (strcmp(ids[k], "-")) {
                char *argv[] = {"scancel", ids[k], NULL};
                slurm_cmd(argv, out, NULL, 0, NULL, 0);
            }
    }
    return rc;
}

/* every submission, for the record (and for scancel) */
static void record_submission(const char *out, const char *dir, const stage_jobs *j,
                              const slurm_stage *refs, const slurm_stage *runs)
{
    char jobs[4400], line[300];
    snprintf(jobs, sizeof jobs, "%s/jobs.txt", dir);
    FILE *f = fopen(jobs, "a");
    if (f) {
        fprintf(f, "%ld refs %s runs %s collect %s\n", (long)time(NULL), j->ref, j->run, j->col);
        fclose(f);
    }
    snprintf(line, sizeof line, "references %s (%u tasks), runs %s (%u tasks), collect %s", j->ref,
             refs->n, j->run, runs->n, j->col);
    printf("submitted: %s\n", line);
    fflush(stdout);
    fprintf(stderr, "study: submitted %s; logs in %s/slurm/logs\n", line, out);
}

/* wait for the collect job, which waits for the others */
static int wait_for_collect(const char *out, const stage_jobs *j)
{
    int known = 1, unknown_polls = 0;
    for (;;) {
        int active = job_active(out, j->col, &known);
        if (!active && known)
            break;
        if (!known && ++unknown_polls > 30)
            return cli_fail(EXIT_RUN, "study: squeue cannot tell job %s's state: %s", j->col,
                            "giving up waiting");
        if (cli_interrupted)
            return cli_fail(
                EXIT_RUN, "study: interrupted while waiting; the jobs go on (scancel %s %s %s)",
                strcmp(j->ref, "-") ? j->ref : "", strcmp(j->run, "-") ? j->run : "", j->col);
        struct timespec ts = {2, 0};
        nanosleep(&ts, NULL);
    }
    char log[4500], last[600];
    int exists;
    snprintf(log, sizeof log, "%s/slurm/logs/collect-%s.log", out, j->col);
    int code = log_exit(log, last, sizeof last, &exists);
    if (code != 0)
        return cli_fail(EXIT_RUN, "study: the collect job %s %s (%s)%s%s", j->col,
                        code > 0 ? "failed" : "ended without finishing", log, last[0] ? ": " : "",
                        last);
    fprintf(stderr, "study: collect job %s done: %s\n", j->col, last);
    return EXIT_OK;
}

int slurm_run(const slurm_options *o, const char *file, const char *out, const char *name,
              uint64_t plan, const slurm_stage *refs, const slurm_stage *runs)
{
    char cwd[4096], dir[4200], logs[4300];
    if (!getcwd(cwd, sizeof cwd))
        return cli_fail(EXIT_RUN, "study: cannot read the working directory");
    if (!chars_in(cwd, "_-.,/+=@%"))
        return cli_fail(
            EXIT_USAGE,
            "study: --slurm needs a working directory without blanks or shell characters");
    snprintf(dir, sizeof dir, "%s/slurm", out);
    snprintf(logs, sizeof logs, "%s/logs", dir);
    char *texts[3] = {refs->n ? stage_script(o, file, out, name, plan, refs, cwd) : NULL,
                      runs->n ? stage_script(o, file, out, name, plan, runs, cwd) : NULL,
                      collect_script(o, file, out, name, cwd)};
    char paths[3][4400];
    int rc = write_scripts(o, dir, logs, texts, paths, refs, runs);
    stage_jobs j = {"-", "-", ""};
    if (rc == EXIT_OK && !o->dry_run)
        rc = submit_stages(out, paths, refs, runs, &j);
    for (int k = 0; k < 3; k++)
        free(texts[k]);
    if (rc != EXIT_OK || o->dry_run)
        return rc;
    record_submission(out, dir, &j, refs, runs);
    if (o->no_wait) {
        fprintf(stderr, "study: not waiting (--no-wait): the collect job %s writes %s/report.md\n",
                j.col, out);
        return EXIT_OK;
    }
    return wait_for_collect(out, &j);
}

/* ---- the collect job's view of the tasks ---- */

typedef struct task_state {
    uint32_t task;
    char state[32], exit[16];
} task_state;

struct slurm_tasks {
    char out[4096], kind[8], job[64];
    task_state *s;
    uint32_t n, cap;
    const char *source; /* "sacct", "scontrol" or NULL */
};

static void add_state(slurm_tasks *t, uint32_t task, const char *state, const char *exit)
{
    if (t->n == t->cap) {
        uint32_t cap = t->cap ? 2 * t->cap : 64;
        task_state *s = realloc(t->s, cap * sizeof *s);
        if (!s)
            return;
        t->s = s;
        t->cap = cap;
    }
    task_state *e = &t->s[t->n++];
    e->task = task;
    snprintf(e->state, sizeof e->state, "%.*s", (int)strcspn(state, " "), state);
    snprintf(e->exit, sizeof e->exit, "%s", exit);
}

/* Reads a command's whole output into a string (NULL when it fails). */
static char *slurm_output(char *const argv[], const char *out)
{
    char o[4200];
    snprintf(o, sizeof o, "%s/slurm/.query.%ld", out, (long)getpid());
    cli_proc_result r;
    int ok = run_tool(argv, o, NULL, &r);
    size_t n = 0;
    char *text = ok ? gi_file_read_all(o, &n) : NULL;
    unlink(o);
    return text;
}

slurm_tasks *slurm_tasks_query(const char *out, const char *kind, const char *job)
{
    slurm_tasks *t = calloc(1, sizeof *t);
    if (!t)
        return NULL;
    snprintf(t->out, sizeof t->out, "%s", out);
    snprintf(t->kind, sizeof t->kind, "%s", kind);
    snprintf(t->job, sizeof t->job, "%s", job);
    if (!strcmp(job, "-") || !*job)
        return t;
    /* sacct where accounting is on: "JOB_K|STATE|EXIT:SIGNAL" */
    char *sacct[] = {"sacct", "-n", "-P", "-X", "-j", (char *)job, "--format=JobID,State,ExitCode",
                     NULL};
    char *text = on_path("sacct") ? slurm_output(sacct, out) : NULL;
    char *save = NULL;
    for (char *line = text ? strtok_r(text, "\n", &save) : NULL; line;
         line = strtok_r(NULL, "\n", &save)) {
        char id[96], state[64], code[32];
        unsigned task;
        if (sscanf(line, "%95[^|]|%63[^|]|%31s", id, state, code) == 3 && strchr(id, '_') &&
            sscanf(strchr(id, '_') + 1, "%u", &task) == 1 && !strchr(strchr(id, '_'), '['))
            add_state(t, task, state, code);
    }
    free(text);
    if (t->n) {
        t->source = "sacct";
        return t;
    }
    /* else the controller's memory of finished jobs (MinJobAge): one line per task */
    char *sctl[] = {"scontrol", "-o", "show", "job", (char *)job, NULL};
    text = slurm_output(sctl, out);
    for (char *line = text ? strtok_r(text, "\n", &save) : NULL; line;
         line = strtok_r(NULL, "\n", &save)) {
        const char *a = strstr(line, "ArrayTaskId="), *s = strstr(line, "JobState="),
                   *e = strstr(line, "ExitCode=");
        unsigned task;
        char state[32] = "", code[16] = "";
        if (!a || !s || sscanf(a + 12, "%u", &task) != 1 ||
            isdigit((unsigned char)a[12 + strspn(a + 12, "0123456789")]))
            continue;
        if (a[12 + strspn(a + 12, "0123456789")] != ' ')
            continue; /* "1-5%2": tasks not yet split off, still pending */
        sscanf(s + 9, "%31s", state);
        if (e)
            sscanf(e + 9, "%15s", code);
        add_state(t, task, state, code);
    }
    free(text);
    if (t->n)
        t->source = "scontrol";
    return t;
}

void slurm_tasks_describe(const slurm_tasks *t, uint32_t task, char *buf, size_t size)
{
    if (!t || !strcmp(t->job, "-")) {
        snprintf(buf, size, "no Slurm task ran this cell");
        return;
    }
    const task_state *s = NULL;
    for (uint32_t i = 0; i < t->n; i++)
        if (t->s[i].task == task)
            s = &t->s[i];
    char log[4400], last[400];
    snprintf(log, sizeof log, "%s/slurm/logs/%s-%s_%u.log", t->out, t->kind, t->job, task);
    int exists, code = log_exit(log, last, sizeof last, &exists);
    char what[700];
    if (!exists)
        snprintf(what, sizeof what, "never started (no log)");
    else if (code >= 0)
        snprintf(what, sizeof what, "the cell exited %d: %s", code, last);
    else
        snprintf(what, sizeof what, "killed while running (%s)",
                 last[0] ? last : "log without an exit line");
    if (s)
        snprintf(buf, size, "Slurm task %s_%u: %s, exit code %s; %s", t->job, task, s->state,
                 s->exit, what);
    else if (t->n && !exists)
        /* the controller holds the array's other tasks: this one was
         * taken out of the array before it ever ran */
        snprintf(buf, size,
                 "Slurm task %s_%u: CANCELLED while pending (%s keeps no record of it); no log",
                 t->job, task, t->source);
    else
        snprintf(buf, size,
                 "Slurm task %s_%u: state unknown (no accounting, and the controller forgot the "
                 "job); %s",
                 t->job, task, what);
}

void slurm_tasks_free(slurm_tasks *t)
{
    if (t)
        free(t->s);
    free(t);
}
