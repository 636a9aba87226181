/* A study's report (report.h): the records of its runs, with the scene
 * sizes that scale studies chart, the report's description of the study
 * and its references, the charts and tables of study_charts.c and
 * study_anim.c, and report.md, index.html and the CSV files written from
 * them. docs/studies.md, "gibench study". */
#define _POSIX_C_SOURCE 200809L
#include "study_internal.h"

#include "proc.h"
#include "report.h"

#include <stdio.h>
#include <string.h>
#include <unistd.h>

/* the scene's name and size, for scale studies (cached records too) */
static void add_scene_sizes(study *st)
{
    for (uint32_t i = 0; i < st->run_count; i++)
        if (st->runs[i].record) {
            const study_scene *sc = &st->scenes[st->runs[i].scene_index];
            /* the scene as the study names it, wherever the study ran from */
            json_object_object_add(st->runs[i].record, "scene", json_object_new_string(sc->name));
            json_object_object_add(st->runs[i].record, "scene_triangles",
                                   json_object_new_int64(sc->triangles));
            json_object_object_add(st->runs[i].record, "scene_vertices",
                                   json_object_new_int64(sc->vertices));
        }
}

/* The runs' records as a list, the first renderer they name, and how many
 * failed or were interrupted. */
static json_object *collect_records(const study *st, char *renderer, size_t renderer_size,
                                    int *failed, int *interrupted)
{
    json_object *runs = json_object_new_array();
    for (uint32_t i = 0; i < st->run_count; i++) {
        json_object *v;
        if (!st->runs[i].record)
            continue;
        if (!renderer[0] && json_object_object_get_ex(st->runs[i].record, "renderer", &v))
            snprintf(renderer, renderer_size, "%s", json_object_get_string(v));
        if (json_object_object_get_ex(st->runs[i].record, "status", &v) &&
            !strcmp(json_object_get_string(v), "failed"))
            (*failed)++;
        if (json_object_object_get_ex(st->runs[i].record, "status", &v) &&
            !strcmp(json_object_get_string(v), "interrupted"))
            (*interrupted)++;
        json_object_array_add(runs, json_object_get(st->runs[i].record));
    }
    return runs;
}

/* The report's description of the study: its title, its references and
 * the image that stands for them. */
static json_object *meta_of_study(const study *st, int argc, char **argv, const char *renderer)
{
    char title[512], refdesc[256];
    snprintf(title, sizeof title, "gibench study: %s (%ux%u, %u frames)", st->name, st->base.width,
             st->base.height, st->base.frames);
    snprintf(refdesc, sizeof refdesc,
             "path traced (Embree), %u spp, %u bounces; bounce-matched the same spp%s", st->ref_spp,
             st->ref_bounces, st->ref_pixel_center ? "; camera rays through pixel centres" : "");
    json_object *meta = report_meta_new(title, "study", argc, argv, renderer, refdesc);
    if (st->ref_count) {
        char ref_png[512];
        snprintf(ref_png, sizeof ref_png, "references/%s_b%u_%uspp%s.png", st->refs[0].name,
                 st->ref_bounces, st->ref_spp, st->ref_pixel_center ? "_center" : "");
        json_object_object_add(meta, "reference_png", json_object_new_string(ref_png));
    }
    return meta;
}

/* The failed runs, a line each (the first 20), saying which look external
 * (killed by a signal from outside, a full disk, an I/O error: worth a
 * retry), then the verdict: a study with failed runs exits 1. */
static int report_failures(const study *st, int failed)
{
    int external = 0, listed = 0;
    for (uint32_t i = 0; i < st->run_count; i++) {
        json_object *v, *rec = st->runs[i].record;
        if (!rec || !json_object_object_get_ex(rec, "status", &v) ||
            strcmp(json_object_get_string(v), "failed"))
            continue;
        const char *why =
            json_object_object_get_ex(rec, "reason", &v) ? json_object_get_string(v) : "";
        int ext = cli_reason_external(why);
        external += ext;
        if (listed++ < 20)
            fprintf(stderr, "study: failed%s: %s: %s\n", ext ? " (looks external)" : "",
                    st->runs[i].id, why);
    }
    if (external)
        return cli_fail(EXIT_RUN,
                        "study: %d of %u runs failed, %d of them look external (killed, disk "
                        "full, I/O error); --retry-failed redoes the failed runs",
                        failed, st->run_count, external);
    return cli_fail(EXIT_RUN, "study: %d of %u runs failed; --retry-failed redoes them", failed,
                    st->run_count);
}

/* A refused report leaves no report of an earlier invocation behind to
 * be read as this one's. */
static void remove_report(const char *out)
{
    static const char *const files[] = {"report.md",  "index.html", "runs.csv",     "runs.json",
                                        "frames.csv", "curves.csv", "pt_curves.csv"};
    char path[4200];
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        snprintf(path, sizeof path, "%s/%s", out, files[i]);
        unlink(path);
    }
}

int study_write_report(study *st, const char *out, int argc, char **argv, int slurm_collect)
{
    int rc = EXIT_OK, mixed = 0;
    /* one clock per comparison (issue 34): timings of several invocations
     * are refused unless --mix-clocks */
    if ((rc = study_check_clocks(st, &mixed)) != EXIT_OK) {
        remove_report(out);
        return rc;
    }
    add_scene_sizes(st);
    char renderer[256] = "";
    int failed = 0, interrupted = 0;
    json_object *runs = collect_records(st, renderer, sizeof renderer, &failed, &interrupted);
    json_object *meta = meta_of_study(st, argc, argv, renderer);
    study_reference_sets(st, meta);
    json_object *chart_list = json_object_new_array();
    study_charts_and_speedups(st, out, meta, chart_list, mixed);
    study_animation_report(st, out, meta, chart_list);
    study_user_charts(st, out, runs, chart_list);
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
    else if (rc == EXIT_OK && failed && report_failures(st, failed) != EXIT_OK && !slurm_collect)
        rc = EXIT_RUN;
    json_object_put(runs);
    json_object_put(meta);
    return rc;
}
