/* A study's references (docs/studies.md, "gibench study"): per reference set the
 * path-traced full-GI reference, the bounce-matched ones for the methods'
 * bounce counts, the noise-floor reference of animation frames and the
 * path tracer's own convergence curve; the runs pointed at them, and the
 * sets described for the report's image viewer. */
#define _POSIX_C_SOURCE 200809L
#include "study_internal.h"

#include "gi/cache.h"
#include "gi/log.h"
#include "gi/timer.h"

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

static double rec_num(json_object *o, const char *k1, const char *k2, const char *k3)
{
    const char *keys[3] = {k1, k2, k3};
    for (int i = 0; i < 3 && keys[i]; i++) {
        json_object *v;
        if (!o || !json_object_object_get_ex(o, keys[i], &v))
            return NAN;
        o = v;
    }
    return json_object_get_double(o);
}

/* ---- progress of a reference --------------------------------------------
 * A reference renders in a child process for up to minutes; its progress
 * ("reference: 256/1024 spp, 12.0 s", asked for by GIBENCH_PROGRESS_EVERY)
 * goes to its log. A watcher thread shows the latest of those lines while
 * the child runs, at most every 10 s in a log, in place on a terminal; a
 * line with the samples and seconds follows when it is done. Nothing
 * under -q. */
typedef struct ref_watch {
    pthread_t thread;
    atomic_int done;
    int started, tty;
    char label[400], log[4200], stats[4200];
    double t0;
} ref_watch;

static void watch_line(const ref_watch *w, char *line, size_t size)
{
    line[0] = '\0';
    size_t n = 0;
    char *text = gi_file_read_all(w->log, &n);
    char *last = NULL;
    for (char *p = text; p && (p = strstr(p, "reference: ")); p++)
        last = p;
    if (last) {
        last += strlen("reference: ");
        size_t k = strcspn(last, "\n");
        if (last[k] == '\n') /* a whole line only */
            snprintf(line, size, "%.*s", (int)k, last);
    }
    free(text);
}

static void *watch_main(void *arg)
{
    ref_watch *w = arg;
    double shown = w->t0;
    char line[256], prev[256] = "";
    while (!atomic_load(&w->done)) {
        struct timespec ts = {0, 200 * 1000 * 1000};
        nanosleep(&ts, NULL);
        double now = gi_now();
        if (now - shown < (w->tty ? 1.0 : 10.0))
            continue;
        watch_line(w, line, sizeof line);
        if (!line[0] || !strcmp(line, prev))
            continue;
        snprintf(prev, sizeof prev, "%s", line);
        char el[32];
        cli_format_duration(now - w->t0, el, sizeof el);
        fprintf(stderr, "%sstudy: %s: %s; elapsed %s%s", w->tty ? "\r" : "", w->label, line, el,
                w->tty ? "\033[K" : "\n");
        shown = now;
    }
    return NULL;
}

static void watch_start(ref_watch *w, const char *label, const char *out_exr)
{
    memset(w, 0, sizeof *w);
    if (gi_log_get_level() < GI_LOG_WARN) /* -q */
        return;
    snprintf(w->label, sizeof w->label, "%s", label);
    snprintf(w->log, sizeof w->log, "%s.log", out_exr);
    snprintf(w->stats, sizeof w->stats, "%s.json", out_exr);
    w->tty = isatty(STDERR_FILENO);
    w->t0 = gi_now();
    /* the reference child's progress lines, every 2 s, into its log */
    setenv("GIBENCH_PROGRESS_EVERY", "2", 1);
    w->started = pthread_create(&w->thread, NULL, watch_main, w) == 0;
}

/* Stops the watcher; when the reference exists, a line with its samples
 * and render time (from its statistics). */
static void watch_stop(ref_watch *w, int ok)
{
    if (w->started) {
        atomic_store(&w->done, 1);
        pthread_join(w->thread, NULL);
        if (w->tty)
            fputs("\r\033[K", stderr);
    }
    if (!ok || !w->label[0])
        return;
    json_object *sj = cli_read_json(w->stats);
    double spp = rec_num(sj, "spp", NULL, NULL), t = rec_num(sj, "render_seconds", NULL, NULL);
    json_object_put(sj);
    if (isfinite(spp) && isfinite(t))
        fprintf(stderr, "study: %s: %.0f spp in %.2f s\n", w->label, spp, t);
}

/* The path tracer's convergence curve at one bounce limit: an image of
 * each convergence_spp count (another seed) against `reference`. The
 * full-GI images keep their old names (references made before per-bounce
 * curves are reused). */
static int pt_convergence(study *st, const char *out_dir, const study_ref *sc, const char *scene,
                          uint32_t bounces, const char *reference, tradeoff_pt_curve *curve,
                          char *why, size_t why_size)
{
    const char *px = st->ref_pixel_center ? "_center" : "";
    curve->n = 0;
    for (uint32_t c = 0; c < st->conv_n; c++) {
        char img[4096], stats[4200], b[32] = "";
        if (bounces != st->ref_bounces)
            snprintf(b, sizeof b, "b%u_", bounces);
        char stem[320];
        snprintf(stem, sizeof stem, "%s", sc->name);
        snprintf(img, sizeof img, "%s/references/%s_conv_%s%uspp%s.exr", out_dir, stem, b,
                 st->conv_spp[c], px);
        char label[400];
        snprintf(label, sizeof label, "convergence %s (%u bounces, %u spp)", stem, bounces,
                 st->conv_spp[c]);
        ref_watch w;
        watch_start(&w, label, img);
        int ok =
            runner_reference(scene, st->scenes[sc->scene_index].hash, st->camera, sc->width,
                             sc->height, st->conv_spp[c], 0.0, bounces, st->seed + 7919, sc->time,
                             st->ref_pixel_center, st->timeout_s, img, why, why_size);
        watch_stop(&w, ok);
        if (!ok)
            return 0;
        snprintf(stats, sizeof stats, "%s.json", img);
        json_object *sj = cli_read_json(stats);
        json_object *m = runner_diff(img, reference, NULL, NULL, st->exposure, why, why_size);
        /* the path tracer's time to the image, measured as the methods'
         * frames are: its render's CPU time (every thread) in studies timed
         * by CPU time, else its render's wall time (all threads); the BVH
         * build, like a method's prepare, is not in it. Images made before
         * the CPU time was recorded give their whole wall time. */
        double t = rec_num(sj,
                           st->timer && !strcmp(st->timer, "cputime") ? "render_cpu_seconds"
                                                                      : "render_seconds",
                           NULL, NULL);
        if (!isfinite(t))
            t = rec_num(sj, "wall_seconds", NULL, NULL);
        double e = rec_num(m, "relmse", NULL, NULL);
        if (isfinite(t) && isfinite(e) && t > 0 && e > 0 && curve->n < TRADEOFF_PT_POINTS) {
            curve->t[curve->n] = t;
            curve->e[curve->n] = e;
            curve->n++;
        }
        json_object_put(sj);
        json_object_put(m);
    }
    return 1;
}

/* Whether run r compares with reference set ri (its final image, or one of its frames). */
static int run_uses_ref(const study_run *r, uint32_t ri)
{
    if (r->ref_index == (int)ri)
        return 1;
    for (uint32_t f = 0; f < r->frame_ref_n; f++)
        if (r->frame_ref[f] == (int)ri)
            return 1;
    return 0;
}

/* One reference set: the full-GI reference, the bounce-matched ones for
 * every method bounce count in use and, with `curves`, the path tracer's
 * convergence images. 1 when all exist (made now or before), else 0 with why. */
int study_build_reference_set(study *st, const char *out_dir, uint32_t ri, int curves, char *why,
                              size_t why_size)
{
    study_ref *sc = &st->refs[ri];
    const char *path = st->scenes[sc->scene_index].path;
    char dir[2048], stem[320];
    snprintf(stem, sizeof stem, "%s",
             sc->name); /* a copy: -Wrestrict sees sc->name and the outputs as one object */
    snprintf(dir, sizeof dir, "%s/references", out_dir);
    cli_mkdirs(dir);
    /* the file name carries every setting that changes the image, so that
     * runs compared with an older reference are not taken as done */
    const char *px = st->ref_pixel_center ? "_center" : "";
    snprintf(sc->ref_full, sizeof sc->ref_full, "%s/%s_b%u_%uspp%s.exr", dir, stem, st->ref_bounces,
             st->ref_spp, px);
    fprintf(stderr, "study: reference %s (%ux%u, %u spp, %u bounces)\n", stem, sc->width,
            sc->height, st->ref_spp, st->ref_bounces);
    char label[400];
    snprintf(label, sizeof label, "reference %s (%u bounces)", stem, st->ref_bounces);
    ref_watch w;
    watch_start(&w, label, sc->ref_full);
    int ok =
        runner_reference(path, st->scenes[sc->scene_index].hash, st->camera, sc->width, sc->height,
                         st->ref_spp, st->ref_target_se, st->ref_bounces, st->seed, sc->time,
                         st->ref_pixel_center, st->timeout_s * 10, sc->ref_full, why, why_size);
    watch_stop(&w, ok);
    if (!ok)
        return 0;
    /* the noise floor of an animation frame: the same reference with another seed */
    if (sc->want_alt) {
        snprintf(sc->ref_alt, sizeof sc->ref_alt, "%s/%s_b%u_%uspp%s_alt.exr", dir, stem,
                 st->ref_bounces, st->ref_spp, px);
        fprintf(stderr, "study: reference %s, second seed (noise floor)\n", stem);
        if (!runner_reference(path, st->scenes[sc->scene_index].hash, st->camera, sc->width,
                              sc->height, st->ref_spp, st->ref_target_se, st->ref_bounces,
                              st->seed + 1000003u, sc->time, st->ref_pixel_center,
                              st->timeout_s * 10, sc->ref_alt, why, why_size))
            return 0;
    }
    /* bounce-matched references for every method bounce count in use */
    for (uint32_t r = 0; r < st->run_count; r++) {
        if (!run_uses_ref(&st->runs[r], ri) || st->runs[r].bounces >= st->ref_bounces)
            continue;
        uint32_t b = st->runs[r].bounces, k = 0;
        while (k < sc->matched_count && sc->matched_bounces[k] != b)
            k++;
        if (k == sc->matched_count && k < 8) {
            sc->matched_bounces[k] = b;
            snprintf(sc->ref_matched[k], sizeof sc->ref_matched[k], "%s/%s_b%u_%uspp%s.exr", dir,
                     stem, b, st->ref_spp, px);
            fprintf(stderr, "study: bounce-matched reference %s (%u bounces)\n", stem, b);
            snprintf(label, sizeof label, "bounce-matched reference %s (%u bounces)", stem, b);
            watch_start(&w, label, sc->ref_matched[k]);
            ok = runner_reference(path, st->scenes[sc->scene_index].hash, st->camera, sc->width,
                                  sc->height, st->ref_spp, st->ref_target_se, b, st->seed, sc->time,
                                  st->ref_pixel_center, st->timeout_s * 10, sc->ref_matched[k], why,
                                  why_size);
            watch_stop(&w, ok);
            if (!ok)
                return 0;
            sc->matched_count++;
        }
    }
    if (!curves || sc->frame_only)
        return 1;
    /* the path tracer's convergence, for full GI and for each bounce
     * count in use: k-spp images (another seed) against the reference
     * of the same bounce count */
    sc->pt_full.bounces = st->ref_bounces;
    if (!pt_convergence(st, out_dir, sc, path, st->ref_bounces, sc->ref_full, &sc->pt_full, why,
                        why_size))
        return 0;
    for (uint32_t k = 0; k < sc->matched_count; k++) {
        sc->pt_matched[k].bounces = sc->matched_bounces[k];
        if (!pt_convergence(st, out_dir, sc, path, sc->matched_bounces[k], sc->ref_matched[k],
                            &sc->pt_matched[k], why, why_size))
            return 0;
    }
    return 1;
}

static void slurm_mark_missing_ref(study *st, uint32_t ri, const char *why)
{
    snprintf(st->refs[ri].missing, sizeof st->refs[ri].missing, "%s", why);
}

int study_build_references(study *st, const char *out_dir, int slurm_collecting)
{
    char why[1024];
    for (uint32_t ri = 0; ri < st->ref_count; ri++) {
        if (study_build_reference_set(st, out_dir, ri, 1, why, sizeof why))
            continue;
        if (!slurm_collecting)
            return cli_fail(EXIT_RUN, "study: %s", why);
        slurm_mark_missing_ref(st, ri, why);
    }
    return EXIT_OK;
}

void study_attach_refs(study *st, study_run *r)
{
    r->spec.ref_full = r->spec.ref_matched = NULL;
    if (r->ref_index < 0)
        return;
    study_ref *sc = &st->refs[r->ref_index];
    r->spec.ref_full = sc->ref_full;
    r->spec.ref_matched = sc->ref_full;
    for (uint32_t k = 0; k < sc->matched_count; k++)
        if (sc->matched_bounces[k] == r->bounces)
            r->spec.ref_matched = sc->ref_matched[k];
    for (uint32_t f = 0; f < r->frame_ref_n; f++) {
        const study_ref *fr = &st->refs[r->frame_ref[f]];
        r->fr_full[f] = fr->ref_full;
        r->fr_matched[f] = fr->ref_full;
        for (uint32_t k = 0; k < fr->matched_count; k++)
            if (fr->matched_bounces[k] == r->bounces)
                r->fr_matched[f] = fr->ref_matched[k];
        r->fr_alt[f] = fr->ref_alt[0] ? fr->ref_alt : NULL;
    }
    r->spec.frame_ref_count = r->frame_ref_n;
    r->spec.frame_ref_full = r->fr_full;
    r->spec.frame_ref_matched = r->fr_matched;
    r->spec.frame_ref_alt = r->fr_alt;
}

/* The path of a reference relative to the output directory (they all lie in references/). */
static json_object *ref_rel(const char *path)
{
    const char *base = strrchr(path, '/');
    char rel[4200];
    snprintf(rel, sizeof rel, "references/%s", base ? base + 1 : path);
    return json_object_new_string(rel);
}

/* For the report's image viewer: per reference set, its full-GI and
 * bounce-matched references and the runs compared with them (report.h). */
void study_reference_sets(study *st, json_object *meta)
{
    json_object *sets = json_object_new_array();
    for (uint32_t ri = 0; ri < st->ref_count; ri++) {
        study_ref *sc = &st->refs[ri];
        /* the references of an animation's inner frames hold no run's final
         * image: no viewer for them (the table and charts report them) */
        int holds_runs = 0;
        for (uint32_t i = 0; i < st->run_count; i++)
            holds_runs |= st->runs[i].ref_index == (int)ri;
        if (sc->frame_only && !holds_runs)
            continue;
        json_object *set = json_object_new_object(), *matched = json_object_new_array(),
                    *ids = json_object_new_array();
        json_object_object_add(set, "name", json_object_new_string(sc->name));
        json_object_object_add(set, "full", ref_rel(sc->ref_full));
        json_object_object_add(set, "bounces", json_object_new_int((int)st->ref_bounces));
        for (uint32_t k = 0; k < sc->matched_count; k++) {
            json_object *m = json_object_new_object();
            json_object_object_add(m, "image", ref_rel(sc->ref_matched[k]));
            json_object_object_add(m, "bounces", json_object_new_int((int)sc->matched_bounces[k]));
            json_object_array_add(matched, m);
        }
        json_object_object_add(set, "matched", matched);
        for (uint32_t i = 0; i < st->run_count; i++)
            if (st->runs[i].ref_index == (int)ri)
                json_object_array_add(ids, json_object_new_string(st->runs[i].id));
        json_object_object_add(set, "runs", ids);
        json_object_array_add(sets, set);
    }
    json_object_object_add(meta, "references", sets);
    json_object_object_add(meta, "exposure", json_object_new_double(st->exposure));
}
