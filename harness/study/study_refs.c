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

/* One timed sample of a convergence image: its render's CPU time (every
 * thread) in studies timed by CPU time, else its render's wall time (all
 * threads), as the methods' frames are measured; the BVH build, like a
 * method's prepare, is not in it. NaN when the statistics lack it. */
static double pt_sample_seconds(const study *st, const char *img)
{
    char stats[4200];
    snprintf(stats, sizeof stats, "%s.json", img);
    json_object *sj = cli_read_json(stats);
    double t = rec_num(
        sj, st->timer && !strcmp(st->timer, "cputime") ? "render_cpu_seconds" : "render_seconds",
        NULL, NULL);
    json_object_put(sj);
    return t;
}

static int cmp_seconds(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* One point of the curve timed now: the image rendered conv_repeats times
 * (its cached key removed first, so that each is a new render; the seed is
 * the same, so is the image), every render's time a sample. 1, or 0 with why. */
static int pt_time_point(study *st, const study_ref *sc, const char *scene, uint32_t bounces,
                         uint32_t spp, const char *img, double *samples, uint32_t *n, char *why,
                         size_t why_size)
{
    char cfg[4200], label[400];
    snprintf(cfg, sizeof cfg, "%s.config", img);
    *n = 0;
    for (uint32_t r = 0; r < st->conv_repeats; r++) {
        /* one line per timing: "convergence S (B bounces, K spp): K spp in T s" */
        snprintf(label, sizeof label, "convergence %s (%u bounces, %u spp)", sc->name, bounces,
                 spp);
        unlink(cfg);
        ref_watch w;
        watch_start(&w, label, img);
        int ok = runner_reference(scene, st->scenes[sc->scene_index].hash, st->camera, sc->width,
                                  sc->height, spp, 0.0, bounces, st->seed + 7919, sc->time,
                                  st->ref_pixel_center, st->timeout_s, img, why, why_size);
        watch_stop(&w, ok);
        if (!ok)
            return 0;
        double t = pt_sample_seconds(st, img);
        if (isfinite(t) && t > 0)
            samples[(*n)++] = t;
    }
    return 1;
}

/* The path tracer's convergence curve at one bounce limit: an image of
 * each convergence_spp count (another seed) against `reference`, each
 * timed conv_repeats times in this invocation (issue 34: median and
 * min-max kept), or with STUDY_CURVES_LOAD / _RECORDED the curve an
 * earlier invocation timed (its record, when its settings are these).
 * The full-GI images keep their old names. */
static int pt_convergence(study *st, const char *out_dir, const study_ref *sc, const char *scene,
                          uint32_t bounces, const char *reference, int mode,
                          tradeoff_pt_curve *curve, char *why, size_t why_size)
{
    char record[4200], key[8192];
    study_curve_record_path(st, out_dir, sc, bounces, record, sizeof record);
    study_curve_key(st, reference, bounces, key, sizeof key);
    curve->n = 0;
    curve->invocation[0] = '\0';
    if (mode != STUDY_CURVES_TIME && study_curve_load(record, key, curve))
        return 1;
    if (mode == STUDY_CURVES_RECORDED) {
        snprintf(why, why_size, "the path tracer's curve %s was not timed", record);
        return 0;
    }
    const char *px = st->ref_pixel_center ? "_center" : "";
    static double samples[TRADEOFF_PT_POINTS][64];
    for (uint32_t c = 0; c < st->conv_n; c++) {
        char img[4096], b[32] = "";
        if (bounces != st->ref_bounces)
            snprintf(b, sizeof b, "b%u_", bounces);
        char stem[320];
        snprintf(stem, sizeof stem, "%s", sc->name);
        snprintf(img, sizeof img, "%s/references/%s_conv_%s%uspp%s.exr", out_dir, stem, b,
                 st->conv_spp[c], px);
        double t[64];
        uint32_t nt = 0;
        if (!pt_time_point(st, sc, scene, bounces, st->conv_spp[c], img, t, &nt, why, why_size))
            return 0;
        json_object *m = runner_diff(img, reference, NULL, NULL, st->exposure, why, why_size);
        double e = rec_num(m, "relmse", NULL, NULL);
        json_object_put(m);
        if (nt == 0 || !isfinite(e) || !(e > 0) || curve->n >= TRADEOFF_PT_POINTS)
            continue;
        uint32_t k = curve->n++;
        memcpy(samples[k], t, nt * sizeof *t);
        qsort(t, nt, sizeof *t, cmp_seconds);
        curve->t[k] = nt % 2 ? t[nt / 2] : 0.5 * (t[nt / 2 - 1] + t[nt / 2]);
        curve->t_lo[k] = t[0];
        curve->t_hi[k] = t[nt - 1];
        curve->samples[k] = nt;
        curve->e[k] = e;
        curve->spp[k] = st->conv_spp[c];
    }
    snprintf(curve->invocation, sizeof curve->invocation, "%s", st->invocation);
    return study_curve_save(record, key, curve, samples, why, why_size);
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

/* The path tracer's convergence of set ri, for full GI and for each
 * bounce count in use: k-spp images (another seed) against the reference
 * of the same bounce count, timed or loaded as `mode` says. */
static int set_curves(study *st, const char *out_dir, uint32_t ri, int mode, char *why,
                      size_t why_size)
{
    study_ref *sc = &st->refs[ri];
    const char *path = st->scenes[sc->scene_index].path;
    sc->pt_full.bounces = st->ref_bounces;
    if (!pt_convergence(st, out_dir, sc, path, st->ref_bounces, sc->ref_full, mode, &sc->pt_full,
                        why, why_size))
        return 0;
    for (uint32_t k = 0; k < sc->matched_count; k++) {
        sc->pt_matched[k].bounces = sc->matched_bounces[k];
        if (!pt_convergence(st, out_dir, sc, path, sc->matched_bounces[k], sc->ref_matched[k], mode,
                            &sc->pt_matched[k], why, why_size))
            return 0;
    }
    return 1;
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
    if (curves == STUDY_CURVES_NONE || sc->frame_only || st->conv_n == 0)
        return 1;
    return set_curves(st, out_dir, ri, curves, why, why_size);
}

static void slurm_mark_missing_ref(study *st, uint32_t ri, const char *why)
{
    snprintf(st->refs[ri].missing, sizeof st->refs[ri].missing, "%s", why);
}

int study_build_references(study *st, const char *out_dir, int slurm_collecting)
{
    char why[1024];
    for (uint32_t ri = 0; ri < st->ref_count; ri++) {
        if (study_build_reference_set(st, out_dir, ri, STUDY_CURVES_NONE, why, sizeof why))
            continue;
        if (!slurm_collecting)
            return cli_fail(EXIT_RUN, "study: %s", why);
        slurm_mark_missing_ref(st, ri, why);
    }
    return EXIT_OK;
}

int study_build_curves(study *st, const char *out_dir, int slurm_collecting)
{
    /* the curve is timed with the runs it is compared with (issue 34): when
     * this invocation timed one of them, every curve is timed again now */
    int timed = 0;
    for (uint32_t i = 0; i < st->run_count; i++)
        timed |= st->runs[i].ref_index >= 0 && st->runs[i].spec.animate_fps <= 0 &&
                 study_timed_now(st, &st->runs[i]);
    /* runs of several invocations are refused anyway (study_check_clocks),
     * unless --mix-clocks: no curve is timed for a report that will not be
     * written */
    int refused = timed && !st->mix_clocks && study_runs_mixed(st);
    int mode = slurm_collecting || refused ? STUDY_CURVES_RECORDED
               : timed                     ? STUDY_CURVES_TIME
                                           : STUDY_CURVES_LOAD;
    char why[1024];
    for (uint32_t ri = 0; ri < st->ref_count && !cli_interrupted; ri++) {
        if (st->refs[ri].frame_only || st->refs[ri].missing[0] || st->conv_n == 0)
            continue;
        if (set_curves(st, out_dir, ri, mode, why, sizeof why))
            continue;
        if (cli_interrupted) { /* the report says the study was interrupted */
            st->refs[ri].pt_full.n = 0;
            st->refs[ri].pt_full.invocation[0] = '\0';
            break;
        }
        if (mode != STUDY_CURVES_RECORDED)
            return cli_fail(EXIT_RUN, "study: %s", why);
        if (slurm_collecting)
            fprintf(stderr, "study: %s\n", why); /* no speed-ups for this set */
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
