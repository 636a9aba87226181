/* gibench study: a declarative experiment (harness/studies/NAME.json)
 * expanded into independent runs, executed in child processes by a worker
 * pool, cached by the hash of each run's configuration, and reported with
 * tables and error-against-time charts that include the path tracer's own
 * convergence curve. The file format is documented in docs/studies.md ("gibench study").
 * This file is the command: its options, the lock on the output directory,
 * the plan that --dry-run prints, and the order of the steps, which the
 * study_*.c files carry out (study_internal.h). */
#define _POSIX_C_SOURCE 200809L
#include "study.h"
#include "study_internal.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <unistd.h>

/* --dry-run: what the study would do, without doing it. */
static void print_plan(const study *st)
{
    printf("study %s: %u runs, %u scenes, %u reference sets\n", st->name, st->run_count,
           st->scene_count, st->ref_count);
    for (uint32_t i = 0; i < st->ref_count; i++)
        printf("reference %s: %s %ux%u time %g\n", st->refs[i].name,
               st->scenes[st->refs[i].scene_index].path, st->refs[i].width, st->refs[i].height,
               (double)st->refs[i].time);
    for (uint32_t i = 0; i < st->run_count; i++) {
        const study_run *r = &st->runs[i];
        const run_spec *s = &r->spec;
        printf("run %s: %s %s %ux%u frames %u warmup %u%s%s%s%s", r->id, s->scene, s->method,
               s->width, s->height, s->frames, s->warmup, s->animate_fps > 0 ? " animate" : "",
               s->no_cache ? " no-cache" : "",
               r->ref_index < 0 ? " not-compared"
               : r->frame_ref_n ? " per-frame"
                                : "",
               s->label ? " label=" : "");
        if (s->label)
            printf("%s", s->label);
        for (uint32_t k = 0; k < s->param_count; k++)
            printf(" %s", s->params[k]);
        printf("\n");
    }
}

static void study_free(study *st)
{
    for (uint32_t i = 0; st->runs && i < st->run_count; i++) {
        json_object_put(st->runs[i].record);
        for (int k = 0; k < MAX_KEYS; k++)
            free(st->runs[i].params[k]);
        free(st->runs[i].frame_ref);
        free(st->runs[i].fr_full);
        free(st->runs[i].fr_matched);
        free(st->runs[i].fr_alt);
    }
    free(st->runs);
    free(st->refs);
    json_object_put(st->root);
    memset(st, 0, sizeof *st);
}

int study_check(const char *file, gi_plugins *reg)
{
    return study_check_as(file, NULL, reg);
}

int study_check_as(const char *file, const char *as, gi_plugins *reg)
{
    study *st = calloc(1, sizeof *st); /* over a megabyte: not on the stack */
    if (!st)
        return cli_fail(EXIT_RUN, "study: out of memory");
    st->located_as = as;
    int rc = study_load(st, file, ".", reg);
    study_free(st);
    free(st);
    return rc;
}

/* One study at a time per --out: an exclusive flock() on DIR/.gibench-study.lock,
 * taken before anything (references included) is built and held until the
 * study exits; the kernel releases it when the process dies, crashed or not.
 * The file holds the holder's pid and is left in place (unlinking it would
 * let a third study lock a new file while a second waits on the old one).
 * The descriptor is close-on-exec, so runs started by the study do not hold
 * it. Returns the descriptor, or -1 after printing why (*rc set). */
static int lock_out_dir(const char *out, int *rc)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/.gibench-study.lock", out);
    int fd = open(path, O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0644);
    if (fd < 0) {
        *rc = cli_fail(EXIT_RUN, "study: cannot open the lock %s: %s", path, strerror(errno));
        return -1;
    }
    while (flock(fd, LOCK_EX | LOCK_NB) != 0) {
        if (errno == EINTR)
            continue;
        if (errno == EWOULDBLOCK) {
            char pid[32] = "";
            ssize_t n = pread(fd, pid, sizeof pid - 1, 0);
            pid[n > 0 ? n : 0] = '\0';
            pid[strcspn(pid, "\n")] = '\0';
            *rc = cli_fail(EXIT_USAGE, "study: %s is in use by another study (pid %s holds %s)",
                           out, pid[0] ? pid : "unknown", path);
        } else {
            *rc = cli_fail(EXIT_RUN, "study: cannot lock %s: %s", path, strerror(errno));
        }
        close(fd);
        return -1;
    }
    char pid[32];
    int len = snprintf(pid, sizeof pid, "%ld\n", (long)getpid());
    if (ftruncate(fd, 0) != 0 || pwrite(fd, pid, (size_t)len, 0) != len) {
        *rc = cli_fail(EXIT_RUN, "study: cannot write the lock %s: %s", path, strerror(errno));
        close(fd);
        return -1;
    }
    return fd;
}

/* The command line of gibench study. */
typedef struct study_args {
    const char *file, *out;
    unsigned long jobs;
    int fresh, dry, retry_failed, mix_clocks;
    slurm_options so;
} study_args;

/* Reads and checks the options: EXIT_OK, or an exit status after printing
 * one line. */
static int parse_args(int argc, char **argv, study_args *a)
{
    int taken;
    a->jobs = 1;
    for (int i = 0; i < argc; i++) {
        if ((taken = slurm_take_option(argc, argv, &i, &a->so)) != 0) {
            if (taken < 0)
                return EXIT_USAGE;
        } else if (!strcmp(argv[i], "--out") && i + 1 < argc)
            a->out = argv[++i];
        else if (!strcmp(argv[i], "--jobs") && i + 1 < argc) {
            if (!cli_parse_uint(argv[++i], 1, 64, &a->jobs))
                return cli_fail(EXIT_USAGE, "study: --jobs '%s' is not an integer in 1..64",
                                argv[i]);
        } else if (!strcmp(argv[i], "--resume"))
            a->fresh = 0;
        else if (!strcmp(argv[i], "--fresh"))
            a->fresh = 1;
        else if (!strcmp(argv[i], "--retry-failed"))
            a->retry_failed = 1;
        else if (!strcmp(argv[i], "--dry-run"))
            a->dry = 1;
        else if (!strcmp(argv[i], "--mix-clocks"))
            a->mix_clocks = 1;
        else if (argv[i][0] == '-' && argv[i][1]) /* "-" alone: the study on standard input */
            return cli_fail(EXIT_USAGE, "study: unknown or incomplete option '%s'", argv[i]);
        else if (!a->file)
            a->file = argv[i];
        else
            return cli_fail(EXIT_USAGE, "study: one study file at a time");
    }
    if (!a->file || (!a->out && !a->dry))
        return cli_fail(
            EXIT_USAGE,
            "study: usage: gibench study STUDY.json --out DIR [--jobs N] "
            "[--resume|--fresh|--retry-failed] [--mix-clocks] [--dry-run] "
            "[--slurm [--partition P] [--gres G] [--time T] [--array-limit K] [--no-wait]]");
    if (!a->out)
        a->out = ".";
    if (!strcmp(a->file, "-") && (a->so.enabled || a->so.cell || a->so.collect))
        return cli_fail(EXIT_USAGE, "study: a study on standard input does not go with --slurm "
                                    "(the jobs read the study file again)");
    a->so.dry_run = a->dry;
    a->so.mix_clocks = a->mix_clocks;
    int src = slurm_check(&a->so, a->file, a->out);
    if (src != EXIT_OK)
        return src;
    if (a->fresh && (a->so.enabled || a->so.cell || a->so.collect))
        return cli_fail(EXIT_USAGE,
                        "study: --fresh does not go with --slurm (remove the results to redo)");
    if (a->retry_failed && a->fresh)
        return cli_fail(EXIT_USAGE, "study: --retry-failed does not go with --fresh (which "
                                    "redoes every run)");
    if (a->retry_failed && (a->so.enabled || a->so.cell || a->so.collect))
        return cli_fail(EXIT_USAGE, "study: --retry-failed does not go with --slurm (remove the "
                                    "failed runs' result.json to redo them)");
    return EXIT_OK;
}

/* Slurm: submit the cells, or run one as an array task */
static int run_on_slurm(study *st, const study_args *a, gi_plugins *reg)
{
    int rc = EXIT_OK;
    if (st->timer)
        setenv("GIBENCH_TIMER", st->timer, 1);
    cli_install_signal_handlers();
    /* a study running locally in DIR refuses the submission; the lock
     * is given back at once, for the collect job to take */
    int lock_fd = -1;
    if (a->so.enabled && !a->dry && cli_mkdirs(a->out))
        lock_fd = lock_out_dir(a->out, &rc);
    if (lock_fd >= 0)
        close(lock_fd);
    if (rc == EXIT_OK)
        rc = a->so.cell ? study_slurm_cell(st, a->out, reg, a->so.cell)
                        : study_slurm_submit(st, a->file, a->out, reg, &a->so);
    return rc;
}

/* The study run here, under the lock (*lock_fd, for the caller to close):
 * its references, its runs (with --slurm-collect, the records that the
 * array tasks left) and its report; with --dry-run only the plan. */
static int run_here(study *st, const study_args *a, gi_plugins *reg, int argc, char **argv,
                    int *lock_fd)
{
    int rc = EXIT_OK;
    if (a->so.collect)
        runner_set_collect_only(1);
    if (a->dry) {
        print_plan(st);
        return EXIT_OK;
    }
    if (!cli_mkdirs(a->out))
        return cli_fail(EXIT_RUN, "study: cannot create %s", a->out);
    *lock_fd = lock_out_dir(a->out, &rc);
    if (rc != EXIT_OK)
        return rc;
    if (st->timer)
        setenv("GIBENCH_TIMER", st->timer, 1);
    cli_install_signal_handlers();
    fprintf(stderr, "study: %s: %u runs on %u scenes\n", st->name, st->run_count, st->scene_count);
    rc = study_build_references(st, a->out, a->so.collect != NULL);
    if (rc != EXIT_OK)
        return rc;
    if (a->so.collect)
        study_slurm_collect_runs(st, reg, a->out, a->so.collect);
    else
        study_execute_runs(st, (uint32_t)a->jobs,
                           a->fresh          ? RUNNER_FRESH
                           : a->retry_failed ? RUNNER_RETRY_FAILED
                                             : RUNNER_RESUME,
                           reg);
    /* the path tracer's curves after the runs: timed again when this
     * invocation timed runs compared with them (one clock per comparison) */
    rc = study_build_curves(st, a->out, a->so.collect != NULL);
    if (rc != EXIT_OK)
        return rc;
    return study_write_report(st, a->out, argc, argv, a->so.collect != NULL);
}

int cmd_study(int argc, char **argv)
{
    study_args a;
    memset(&a, 0, sizeof a);
    int rc = parse_args(argc, argv, &a);
    if (rc != EXIT_OK)
        return rc;
    gi_plugins *reg = cli_load_plugins(0);
    study st;
    memset(&st, 0, sizeof st);
    int lock_fd = -1;
    rc = study_load(&st, a.file, a.out, reg);
    st.mix_clocks = a.mix_clocks;
    /* a Slurm submission is one invocation: its cells and its collect job
     * take the id it set (study_slurm_submit); anything else is a new one */
    const char *given = getenv("GIBENCH_STUDY_INVOCATION");
    if ((a.so.cell || a.so.collect) && given && *given && strlen(given) < sizeof st.invocation)
        snprintf(st.invocation, sizeof st.invocation, "%s", given);
    else
        study_new_invocation(st.invocation, sizeof st.invocation);
    if (rc == EXIT_OK && (a.so.enabled || a.so.cell))
        rc = run_on_slurm(&st, &a, reg);
    else if (rc == EXIT_OK)
        rc = run_here(&st, &a, reg, argc, argv, &lock_fd);
    study_free(&st);
    gi_plugins_free(reg);
    if (lock_fd >= 0)
        close(lock_fd); /* releases the lock */
    return rc;
}
