/* The precomputation loop of coherent shadow maps (csm_precompute.h):
 * render in batches, read back, compress (Ritschel et al. 2007 §3.1). */
#include "gi/algo/csm_precompute.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

gi_result gi_csm_precompute(const gi_gpu_scene *gs, const gi_csm_precompute_desc *d,
                            gi_csm_data *out, gi_error *err)
{
    const uint32_t S = d->streams ? d->streams : 1u;
    const uint32_t M = d->depth.size, N = d->count;
    const uint32_t batch = d->batch ? d->batch : 16u;
    const char *who = d->who ? d->who : "csm", *what = d->what ? d->what : "maps";
    const char *render_stage = d->render_stage ? d->render_stage : "depth_render";
    const gi_host *host = d->host;
    if (S > GI_CSM_MAX_STREAMS) {
        snprintf(err->text, sizeof err->text, "%s: %u codec streams (at most %u)", who, S,
                 GI_CSM_MAX_STREAMS);
        return GI_ERR_INVALID_ARGUMENT;
    }
    memset(out, 0, S * sizeof *out);
    if (N == 0 || N % S != 0 || !d->view || !d->depths) {
        snprintf(err->text, sizeof err->text, "%s: %u %s do not make %u codec streams", who, N,
                 what, S);
        return GI_ERR_INVALID_ARGUMENT;
    }
    gi_depth_renderer *dr = gi_depth_renderer_create(&d->depth, err);
    if (!dr)
        return GI_ERR_GL;
    GLuint tex = gi_depth_texture_create(dr, batch);
    gi_depth_view *views = calloc(batch, sizeof *views);
    uint32_t *slot =
        calloc(batch, sizeof *slot); /* map k of a batch: its layer, UINT32_MAX not drawn */
    float *z1 = malloc((size_t)M * M * sizeof *z1), *z2 = malloc((size_t)M * M * sizeof *z2);
    gi_csm_codec *enc[GI_CSM_MAX_STREAMS] = {0};
    gi_result r = GI_ERR_OUT_OF_MEMORY;
    if (!views || !slot || !z1 || !z2) {
        snprintf(err->text, sizeof err->text, "%s: out of memory for %u x %u %s", who, M, M, what);
        goto done;
    }
    for (uint32_t s = 0; s < S; s++)
        if ((r = gi_csm_codec_begin(M, N / S, &enc[s], err)) != GI_OK)
            goto done;
    for (uint32_t first = 0; first < N; first += batch) {
        if (host && host->cancelled(host)) {
            r = GI_ERR_CANCELLED;
            snprintf(err->text, sizeof err->text, "%s: precomputation cancelled", who);
            goto done;
        }
        uint32_t count = N - first < batch ? N - first : batch;
        uint32_t drawn = 0; /* maps of this batch to draw: layers 0 .. drawn-1 */
        for (uint32_t k = 0; k < count; k++) {
            slot[k] = d->skip && d->skip(d->ctx, first + k) ? UINT32_MAX : drawn;
            if (slot[k] != UINT32_MAX)
                d->view(d->ctx, first + k, &views[drawn++]);
        }
        gi_host_stage(host, render_stage, 1);
        r = drawn ? gi_depth_render(dr, gs, views, drawn, tex, 0, err) : GI_OK;
        gi_host_stage(host, render_stage, 0);
        if (r != GI_OK)
            goto done;
        for (uint32_t k = 0; k < count; k++) {
            const uint32_t q = first + k;
            float *map = NULL;
            if (slot[k] != UINT32_MAX) {
                gi_host_stage(host, render_stage, 1);
                map = gi_depth_read_layer(tex, M, slot[k]);
                gi_host_stage(host, render_stage, 0);
                if (!map) {
                    r = GI_ERR_OUT_OF_MEMORY;
                    snprintf(err->text, sizeof err->text, "%s: reading %s %u failed", who, what, q);
                    goto done;
                }
            }
            gi_host_stage(host, "compress", 1);
            d->depths(d->ctx, q, map ? &views[slot[k]] : NULL, map, z1, z2);
            free(map);
            r = gi_csm_codec_add_map(enc[q % S], q / S, z1, z2, err);
            gi_host_stage(host, "compress", 0);
            if (r != GI_OK)
                goto done;
        }
        if (host) {
            char label[96];
            snprintf(label, sizeof label, "%s: %s", who, what);
            host->progress(host, label, d->p0 + d->p1 * (float)(first + count) / (float)N);
        }
    }
    gi_host_stage(host, "compress", 1);
    for (uint32_t s = 0; s < S && r == GI_OK; s++) {
        r = gi_csm_codec_finish(enc[s], &out[s], err);
        enc[s] = NULL;
    }
    gi_host_stage(host, "compress", 0);
done:
    for (uint32_t s = 0; s < S; s++) {
        gi_csm_codec_free(enc[s]);
        if (r != GI_OK)
            gi_csm_data_free(&out[s]);
    }
    free(views);
    free(slot);
    free(z1);
    free(z2);
    glDeleteTextures(1, &tex);
    gi_depth_renderer_free(dr);
    return r;
}
