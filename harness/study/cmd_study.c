/* gibench study: a declarative experiment (harness/studies/NAME.json)
 * expanded into independent runs, executed in child processes by a worker
 * pool, cached by the hash of each run's configuration, and reported with
 * tables and error-against-time charts that include the path tracer's own
 * convergence curve. The file format is documented in README.md ("Studies").
 * This file is the command: its options, the lock on the output directory,
 * the plan that --dry-run prints, and the order of the steps, which the
 * study_*.c files carry out (study_internal.h). */
#define _POSIX_C_SOURCE 200809L
#include "study.h"
#include "study_internal.h"

#include "report.h"

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
    study *st = calloc(1, sizeof *st); /* over a megabyte: not on the stack */
    if (!st)
        return cli_fail(EXIT_RUN, "study: out of memory");
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

int cmd_study(int argc, char **argv)
{
    const char *file = NULL, *out = NULL;
    unsigned long jobs = 1;
    int fresh = 0, dry = 0, taken;
    slurm_options so = {0};
    for (int i = 0; i < argc; i++) {
        if ((taken = slurm_take_option(argc, argv, &i, &so)) != 0) {
            if (taken < 0)
                return EXIT_USAGE;
        } else if (!strcmp(argv[i], "--out") && i + 1 < argc)
            out = argv[++i];
        else if (!strcmp(argv[i], "--jobs") && i + 1 < argc) {
            if (!cli_parse_uint(argv[++i], 1, 64, &jobs))
                return cli_fail(EXIT_USAGE, "study: --jobs '%s' is not an integer in 1..64",
                                argv[i]);
        } else if (!strcmp(argv[i], "--resume"))
            fresh = 0;
        else if (!strcmp(argv[i], "--fresh"))
            fresh = 1;
        else if (!strcmp(argv[i], "--dry-run"))
            dry = 1;
        else if (argv[i][0] == '-')
            return cli_fail(EXIT_USAGE, "study: unknown or incomplete option '%s'", argv[i]);
        else if (!file)
            file = argv[i];
        else
            return cli_fail(EXIT_USAGE, "study: one study file at a time");
    }
    if (!file || (!out && !dry))
        return cli_fail(
            EXIT_USAGE,
            "study: usage: gibench study STUDY.json --out DIR [--jobs N] [--resume|--fresh] "
            "[--dry-run] "
            "[--slurm [--partition P] [--gres G] [--time T] [--array-limit K] [--no-wait]]");
    if (!out)
        out = ".";
    so.dry_run = dry;
    int src = slurm_check(&so, file, out);
    if (src != EXIT_OK)
        return src;
    if (fresh && (so.enabled || so.cell || so.collect))
        return cli_fail(EXIT_USAGE,
                        "study: --fresh does not go with --slurm (remove the results to redo)");
    gi_plugins *reg = cli_load_plugins(0);
    study st;
    memset(&st, 0, sizeof st);
    int rc = study_load(&st, file, out, reg);
    if (rc == EXIT_OK && (so.enabled || so.cell)) {
        /* Slurm: submit the cells, or run one as an array task */
        if (st.timer)
            setenv("GIBENCH_TIMER", st.timer, 1);
        cli_install_signal_handlers();
        /* a study running locally in DIR refuses the submission; the lock
         * is given back at once, for the collect job to take */
        int lock_fd = -1;
        if (so.enabled && !dry && cli_mkdirs(out))
            lock_fd = lock_out_dir(out, &rc);
        if (lock_fd >= 0)
            close(lock_fd);
        if (rc == EXIT_OK)
            rc = so.cell ? study_slurm_cell(&st, out, reg, so.cell)
                         : study_slurm_submit(&st, file, out, reg, &so);
        study_free(&st);
        gi_plugins_free(reg);
        return rc;
    }
    if (rc == EXIT_OK && so.collect)
        runner_set_collect_only(1);
    if (rc == EXIT_OK && dry)
        print_plan(&st);
    if (rc == EXIT_OK && !dry && !cli_mkdirs(out))
        rc = cli_fail(EXIT_RUN, "study: cannot create %s", out);
    int lock_fd = -1;
    if (rc == EXIT_OK && !dry)
        lock_fd = lock_out_dir(out, &rc);
    if (rc == EXIT_OK && !dry && st.timer)
        setenv("GIBENCH_TIMER", st.timer, 1);
    if (rc == EXIT_OK && !dry) {
        cli_install_signal_handlers();
        fprintf(stderr, "study: %s: %u runs on %u scenes\n", st.name, st.run_count, st.scene_count);
        rc = study_build_references(&st, out, so.collect != NULL);
    }
    if (rc == EXIT_OK && !dry) {
        if (so.collect)
            study_slurm_collect_runs(&st, reg, out, so.collect);
        else
            study_execute_runs(&st, (uint32_t)jobs, fresh, reg);
        /* the scene's size, for scale studies (cached records too) */
        for (uint32_t i = 0; i < st.run_count; i++)
            if (st.runs[i].record) {
                const study_scene *sc = &st.scenes[st.runs[i].scene_index];
                json_object_object_add(st.runs[i].record, "scene_triangles",
                                       json_object_new_int64(sc->triangles));
                json_object_object_add(st.runs[i].record, "scene_vertices",
                                       json_object_new_int64(sc->vertices));
            }
        json_object *runs = json_object_new_array();
        char renderer[256] = "";
        int failed = 0, interrupted = 0;
        for (uint32_t i = 0; i < st.run_count; i++) {
            json_object *v;
            if (!st.runs[i].record)
                continue;
            if (!renderer[0] && json_object_object_get_ex(st.runs[i].record, "renderer", &v))
                snprintf(renderer, sizeof renderer, "%s", json_object_get_string(v));
            if (json_object_object_get_ex(st.runs[i].record, "status", &v) &&
                !strcmp(json_object_get_string(v), "failed"))
                failed++;
            if (json_object_object_get_ex(st.runs[i].record, "status", &v) &&
                !strcmp(json_object_get_string(v), "interrupted"))
                interrupted++;
            json_object_array_add(runs, json_object_get(st.runs[i].record));
        }
        char title[512], refdesc[256];
        snprintf(title, sizeof title, "gibench study: %s (%ux%u, %u frames)", st.name,
                 st.base.width, st.base.height, st.base.frames);
        snprintf(refdesc, sizeof refdesc,
                 "path traced (Embree), %u spp, %u bounces; bounce-matched the same spp%s",
                 st.ref_spp, st.ref_bounces,
                 st.ref_pixel_center ? "; camera rays through pixel centres" : "");
        json_object *meta = report_meta_new(title, "study", argc, argv, renderer, refdesc);
        if (st.ref_count) {
            char ref_png[512];
            snprintf(ref_png, sizeof ref_png, "references/%s_b%u_%uspp%s.png", st.refs[0].name,
                     st.ref_bounces, st.ref_spp, st.ref_pixel_center ? "_center" : "");
            json_object_object_add(meta, "reference_png", json_object_new_string(ref_png));
        }
        study_reference_sets(&st, meta);
        json_object *chart_list = json_object_new_array();
        study_charts_and_speedups(&st, out, meta, chart_list);
        study_animation_report(&st, out, meta, chart_list);
        study_user_charts(&st, out, runs, chart_list);
        json_object_object_add(meta, "charts", chart_list);
        char why[1024];
        if (!report_write(out, runs, meta, why, sizeof why))
            rc = cli_fail(EXIT_RUN, "study: %s", why);
        else
            fprintf(stderr,
                    "study: wrote %s/report.md, index.html, runs.csv, frames.csv, curves.csv (%d "
                    "failed runs)\n",
                    out, failed);
        if (rc == EXIT_OK && cli_interrupted)
            rc = cli_fail(EXIT_RUN,
                          "study: interrupted (%d runs to redo); rerun the same command to resume",
                          interrupted);
        json_object_put(runs);
        json_object_put(meta);
    }
    study_free(&st);
    gi_plugins_free(reg);
    if (lock_fd >= 0)
        close(lock_fd); /* releases the lock */
    return rc;
}
