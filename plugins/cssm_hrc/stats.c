/* The stats cssm_hrc reports (README "What it does"): the atlas
 * (§3.2.3), the CSSM's compression (§3.2, Table 2), the moving objects'
 * maps and hull checks (§3.3), the visibility data kept, the cut sizes of
 * the gathers (§4.3). */
#define _POSIX_C_SOURCE 200809L /* clock_gettime */
#include "cssm_hrc.h"

#include <stdio.h>
#include <time.h>

void cssm_stats_atlas(const cssm_hrc *c)
{
    const gi_host *host = c->kit.host;
    const cssm_atlas *a = &c->atlas;
    host->stat(host, "atlas_texels", (double)a->count);
    host->stat(host, "atlas_chart_texels", (double)a->chart_texels);
    host->stat(host, "atlas_charts", (double)a->chart_count);
    host->stat(host, "atlas_coverage", a->covered_area / a->surface_area);
}

void cssm_stats_maps(const cssm_hrc *c)
{
    const gi_host *host = c->kit.host;
    uint64_t bc = cssm_maps_bytes(&c->maps), bu = cssm_maps_bytes_uncompressed(&c->maps);
    host->stat(host, "cssm_bytes", (double)bc);
    host->stat(host, "cssm_bytes_uncompressed", (double)bu);
    host->stat(host, "compression_ratio", bc ? (double)bu / (double)bc : 0.0);
    host->stat(host, "segments_per_texel",
               (double)cssm_maps_segments(&c->maps) / (6.0 * c->M * c->M));
    host->stat(host, "dont_care_share", (double)c->maps.dont_care / (double)c->maps.face_texels);
    cssm_traversal_measure m;
    cssm_traversal_measures(&c->atlas, c->order, &m);
    host->stat(host, "traversal_step_mean", m.step_mean);
    host->stat(host, "traversal_jumps", (double)m.jumps);
    host->stat(host, "traversal_jump_length_share", m.jump_length_share);
    host->stat(host, "traversal_plane_changes", (double)m.plane_changes);
}

/* Compressed sizes of the §3.3 maps of moving objects: their own CSSMs,
 * their CSMs, and (several movers) the static objects' CSMs. */
static void motion_bytes(const cssm_motion *m, double *self_bytes, double *csm_bytes,
                         double *static_bytes)
{
    *self_bytes = *csm_bytes = *static_bytes = 0.0;
    for (uint32_t k = 0; m->movers && k < m->mover_count; k++) {
        *self_bytes += (double)cssm_maps_bytes(&m->movers[k].self);
        *csm_bytes += (double)m->movers[k].csm.data.bytes_compressed;
    }
    for (uint32_t k = 0; m->static_csm && k < m->object_count; k++)
        *static_bytes += (double)m->static_csm[k].data.bytes_compressed;
}

void cssm_stats_moving(const cssm_hrc *c)
{
    const gi_host *host = c->kit.host;
    double self_bytes, csm_bytes, static_bytes;
    motion_bytes(&c->motion, &self_bytes, &csm_bytes, &static_bytes);
    host->stat(host, "moving_objects", (double)c->motion.mover_count);
    host->stat(host, "moving_cssm_bytes", self_bytes);
    host->stat(host, "moving_csm_bytes", csm_bytes);
    if (c->motion.mover_count > 1)
        host->stat(host, "static_csm_bytes", static_bytes);
}

void cssm_stats_data_bytes(const cssm_hrc *c)
{
    const gi_host *host = c->kit.host;
    double bc = (double)cssm_maps_bytes(&c->maps);
    double self_bytes, csm_bytes, static_bytes;
    motion_bytes(&c->motion, &self_bytes, &csm_bytes, &static_bytes);
    /* data_bytes counts the compressed visibility maps, the bulk of what is
     * kept: the CSSM, the movers' maps and, with direct=csm, the lights'
     * CSMs; the atlas and the hierarchy are not counted. */
    host->stat(host, "data_bytes",
               bc + self_bytes + csm_bytes + static_bytes +
                   (c->csm ? (double)cssm_csm_direct_bytes(c->csm) : 0.0));
}

void cssm_stats_hulls(const cssm_hrc *c, const gi_scene *s)
{
    const gi_host *host = c->kit.host;
    host->stat(host, "hull_overlap", (double)c->motion.overlaps);
    host->stat(host, "hull_intrusion", (double)c->motion.intrusions);
    for (uint32_t k = 0; k < c->motion.pair_count; k++) { /* per pair of objects with a mover */
        const cssm_hull_pair *pr = &c->motion.pairs[k];
        char pair[72], name[96];
        snprintf(pair, sizeof pair, "%.30s.%.30s",
                 s->objects[pr->a].name ? s->objects[pr->a].name : "?",
                 s->objects[pr->b].name ? s->objects[pr->b].name : "?");
        snprintf(name, sizeof name, "hull_overlap.%s", pair);
        host->stat(host, name, (double)pr->overlap);
        snprintf(name, sizeof name, "hull_intrusion.%s", pair);
        host->stat(host, name, (double)pr->intrusion);
    }
}

void cssm_stats_cuts(const cssm_hrc *c, const cssm_gather_stats *st)
{
    const gi_host *host = c->kit.host;
    if (st->receivers) {
        host->stat(host, "cut_size_pixels", (double)st->nodes / (double)st->receivers);
        host->stat(host, "clamped_share", (double)st->clamped / (double)st->nodes);
    }
}

static double cpu_seconds(clockid_t id)
{
    struct timespec t;
    return clock_gettime(id, &t) == 0 ? (double)t.tv_sec + 1e-9 * (double)t.tv_nsec : 0.0;
}

void cssm_stats_cpu_begin(cssm_hrc *c)
{
    c->cpu_t0[0] = cpu_seconds(CLOCK_PROCESS_CPUTIME_ID);
    c->cpu_t0[1] = cpu_seconds(CLOCK_THREAD_CPUTIME_ID);
}

void cssm_stats_cpu_end(cssm_hrc *c)
{
    const double p = cpu_seconds(CLOCK_PROCESS_CPUTIME_ID) - c->cpu_t0[0];
    const double m = cpu_seconds(CLOCK_THREAD_CPUTIME_ID) - c->cpu_t0[1];
    if (c->cpu_frames++ == 0) /* the first frame compiles the shaders */
        return;
    c->cpu_process_s += p;
    c->cpu_main_s += m;
    const gi_host *host = c->kit.host;
    host->stat(host, "frame_cpu_ms", 1e3 * c->cpu_process_s / (double)(c->cpu_frames - 1));
    if (c->cpu_process_s > 0.0)
        host->stat(host, "frame_main_share", c->cpu_main_s / c->cpu_process_s);
}

void cssm_cpu_now(double t[2])
{
    t[0] = cpu_seconds(CLOCK_PROCESS_CPUTIME_ID);
    t[1] = cpu_seconds(CLOCK_THREAD_CPUTIME_ID);
}
