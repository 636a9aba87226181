/* The precomputation loop of coherent shadow maps (csm_precompute.h):
 * render in batches, read back, compress (Ritschel et al. 2007 §3.1). */
#include "gi/algo/csm_precompute.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* One precomputation's renderer, layered texture, scratch and codecs. */
typedef struct precompute_run {
    const gi_gpu_scene *gs;
    const gi_csm_precompute_desc *d;
    uint32_t S, M;
    const char *who, *what, *render_stage;
    gi_depth_renderer *dr;
    GLuint tex;
    gi_depth_view *views;
    uint32_t *slot;       /* map k of a batch: its layer, UINT32_MAX not drawn */
    float *z1, *z2, *map; /* map: one layer read back (M*M*4) */
    gi_csm_codec *enc[GI_CSM_MAX_STREAMS];
} precompute_run;

/* Maps first .. first + count - 1: those not skipped drawn in one
 * gi_depth_render call, then each read back and added to its stream's
 * codec. */
static gi_result encode_batch(precompute_run *pr, uint32_t first, uint32_t count, gi_error *err)
{
    const gi_csm_precompute_desc *d = pr->d;
    const gi_host *host = d->host;
    uint32_t drawn = 0; /* maps of this batch to draw: layers 0 .. drawn-1 */
    for (uint32_t k = 0; k < count; k++) {
        pr->slot[k] = d->skip && d->skip(d->ctx, first + k) ? UINT32_MAX : drawn;
        if (pr->slot[k] != UINT32_MAX)
            d->view(d->ctx, first + k, &pr->views[drawn++]);
    }
    gi_host_stage(host, pr->render_stage, 1);
    gi_result r =
        drawn ? gi_depth_render(pr->dr, pr->gs, pr->views, drawn, pr->tex, 0, err) : GI_OK;
    gi_host_stage(host, pr->render_stage, 0);
    if (r != GI_OK)
        return r;
    for (uint32_t k = 0; k < count; k++) {
        const uint32_t q = first + k;
        float *map = NULL;
        if (pr->slot[k] != UINT32_MAX) {
            gi_host_stage(host, pr->render_stage, 1);
            gi_depth_read_layer_into(pr->tex, pr->M, pr->slot[k], pr->map);
            gi_host_stage(host, pr->render_stage, 0);
            map = pr->map;
        }
        gi_host_stage(host, "compress", 1);
        d->depths(d->ctx, q, map ? &pr->views[pr->slot[k]] : NULL, map, pr->z1, pr->z2);
        r = gi_csm_codec_add_map(pr->enc[q % pr->S], q / pr->S, pr->z1, pr->z2, err);
        gi_host_stage(host, "compress", 0);
        if (r != GI_OK)
            return r;
    }
    return GI_OK;
}

gi_result gi_csm_precompute(const gi_gpu_scene *gs, const gi_csm_precompute_desc *d,
                            gi_csm_data *out, gi_error *err)
{
    const uint32_t S = d->streams ? d->streams : 1u;
    const uint32_t M = d->depth.size, N = d->count;
    /* Maps per gi_depth_render call: d->batch, fewer on a large scene (about
     * 2^20 triangles a call) so that the cancel asked between calls is seen
     * within a fraction of a second (issue 32); the maps are the same. */
    const uint32_t tris = gs->scene->triangle_count, fit = (1u << 20) / (tris ? tris : 1u);
    uint32_t batch = d->batch ? d->batch : 16u;
    batch = fit < batch ? (fit ? fit : 1u) : batch;
    const char *who = d->who ? d->who : "csm", *what = d->what ? d->what : "maps";
    const char *render_stage = d->render_stage ? d->render_stage : "depth_render";
    const gi_host *host = d->host;
    if (S > GI_CSM_MAX_STREAMS) {
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: %u codec streams (at most %u)", who,
                            S, GI_CSM_MAX_STREAMS);
    }
    memset(out, 0, S * sizeof *out);
    if (N == 0 || N % S != 0 || !d->view || !d->depths) {
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: %u %s do not make %u codec streams",
                            who, N, what, S);
    }
    precompute_run pr = {
        .gs = gs, .d = d, .S = S, .M = M, .who = who, .what = what, .render_stage = render_stage};
    pr.dr = gi_depth_renderer_create(&d->depth, err);
    if (!pr.dr)
        return GI_ERR_GL;
    pr.tex = gi_depth_texture_create(pr.dr, batch);
    pr.views = calloc(batch, sizeof *pr.views);
    pr.slot = calloc(batch, sizeof *pr.slot);
    pr.z1 = malloc((size_t)M * M * sizeof *pr.z1);
    pr.z2 = malloc((size_t)M * M * sizeof *pr.z2);
    pr.map = malloc((size_t)M * M * 4 * sizeof *pr.map);
    gi_result r = GI_ERR_OUT_OF_MEMORY;
    if (!pr.views || !pr.slot || !pr.z1 || !pr.z2 || !pr.map) {
        r = gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "%s: out of memory for %u x %u %s", who, M, M,
                         what);
        goto done;
    }
    for (uint32_t s = 0; s < S; s++)
        if ((r = gi_csm_codec_begin(M, N / S, &pr.enc[s], err)) != GI_OK)
            goto done;
    for (uint32_t first = 0; first < N; first += batch) {
        if (host && host->cancelled(host)) {
            r = gi_error_set(err, GI_ERR_CANCELLED, "%s: precomputation cancelled", who);
            goto done;
        }
        uint32_t count = N - first < batch ? N - first : batch;
        if ((r = encode_batch(&pr, first, count, err)) != GI_OK)
            goto done;
        if (host) {
            char label[96];
            snprintf(label, sizeof label, "%s: %s", who, what);
            host->progress(host, label, d->p0 + d->p1 * (float)(first + count) / (float)N);
        }
    }
    gi_host_stage(host, "compress", 1);
    for (uint32_t s = 0; s < S && r == GI_OK; s++) {
        r = gi_csm_codec_finish(pr.enc[s], &out[s], err);
        pr.enc[s] = NULL;
    }
    gi_host_stage(host, "compress", 0);
done:
    for (uint32_t s = 0; s < S; s++) {
        gi_csm_codec_free(pr.enc[s]);
        if (r != GI_OK)
            gi_csm_data_free(&out[s]);
    }
    free(pr.views);
    free(pr.slot);
    free(pr.z1);
    free(pr.z2);
    free(pr.map);
    glDeleteTextures(1, &pr.tex);
    gi_depth_renderer_free(pr.dr);
    return r;
}
