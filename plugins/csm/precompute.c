/* Precomputation of one object's Coherent Shadow Map (§3.1, §4.1): the
 * N_theta x N_phi orthographic dual-depth maps around its bounding sphere,
 * rendered in batches by the core's depth renderer (object-local, only this
 * object, eye-z), read back and streamed into the core's codec in the
 * chosen enumeration order. */
#include "csm_cpu.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void timer(const gi_host *host, const char *name, int begin)
{
    if (!host)
        return;
    if (begin)
        host->stage_begin(host, name);
    else
        host->stage_end(host, name);
}

gi_result csm_encode_maps(const gi_gpu_scene *gs, const csm_encode_desc *desc, const gi_host *host, float p0, float p1,
                          gi_csm_data *out, gi_error *err)
{
    memset(out, 0, sizeof *out);
    const uint32_t M = desc->M, N = desc->count;
    const uint32_t batch = desc->batch ? desc->batch : 16;
    gi_depth_desc dd = {.size = M,
                        .surfaces = desc->z3 ? 3u : 2u,
                        .metric = desc->metric,
                        .only_object = desc->object + 1u,
                        .local = 1,
                        .cull = 0};
    gi_depth_renderer *dr = gi_depth_renderer_create(&dd, err);
    if (!dr)
        return GI_ERR_GL;
    GLuint tex = gi_depth_texture_create(dr, batch);
    gi_depth_view *views = calloc(batch, sizeof *views);
    float *z1 = malloc((size_t)M * M * sizeof *z1), *z2 = malloc((size_t)M * M * sizeof *z2);
    float *far = desc->z3 == CSM_DEPTH_SPHERE ? malloc((size_t)M * M * sizeof *far) : NULL;
    gi_csm_codec *enc = NULL;
    gi_result r = GI_ERR_OUT_OF_MEMORY;
    if (!views || !z1 || !z2 || (desc->z3 == CSM_DEPTH_SPHERE && (!far || !desc->sphere))) {
        snprintf(err->text, sizeof err->text, "csm: out of memory for %u x %u %s", M, M, desc->what);
        goto done;
    }
    r = gi_csm_codec_begin(M, N, &enc, err);
    if (r != GI_OK)
        goto done;
    for (uint32_t first = 0; first < N; first += batch) {
        if (host && host->cancelled(host)) {
            r = GI_ERR_CANCELLED;
            snprintf(err->text, sizeof err->text, "csm: precomputation cancelled");
            goto done;
        }
        uint32_t count = N - first < batch ? N - first : batch;
        for (uint32_t k = 0; k < count; k++)
            desc->view(desc->ctx, first + k, &views[k]);
        timer(host, "depth_render", 1);
        r = gi_depth_render(dr, gs, views, count, tex, 0, err);
        timer(host, "depth_render", 0);
        if (r != GI_OK)
            goto done;
        for (uint32_t k = 0; k < count; k++) {
            timer(host, "depth_render", 1);
            float *map = gi_depth_read_layer(tex, M, k);
            timer(host, "depth_render", 0);
            if (!map) {
                r = GI_ERR_OUT_OF_MEMORY;
                snprintf(err->text, sizeof err->text, "csm: reading %s %u failed", desc->what, first + k);
                goto done;
            }
            timer(host, "compress", 1);
            /* depth option and open surfaces: csm_texel_depths (csm_cpu.h) */
            if (far)
                csm_sphere_far(&views[k], desc->metric, desc->sphere, M, far);
            csm_texel_depths(map, (size_t)M * M, desc->z3, desc->shell, far, z1, z2);
            free(map);
            r = gi_csm_codec_add_map(enc, first + k, z1, z2, err);
            timer(host, "compress", 0);
            if (r != GI_OK)
                goto done;
        }
        if (host) {
            char label[96];
            snprintf(label, sizeof label, "csm: %s", desc->what);
            host->progress(host, label, p0 + p1 * (float)(first + count) / (float)N);
        }
    }
    timer(host, "compress", 1);
    r = gi_csm_codec_finish(enc, out, err);
    timer(host, "compress", 0);
    enc = NULL;
done:
    gi_csm_codec_free(enc);
    free(views);
    free(z1);
    free(z2);
    free(far);
    glDeleteTextures(1, &tex);
    gi_depth_renderer_free(dr);
    return r;
}

/* Map q of an object's distant-light CSM: the q-th cell of the enumeration
 * order on the lat-long grid (§4.1, §4.4). */
typedef struct distant_views {
    const csm_build_desc *desc;
    const float *sphere;
} distant_views;

static void distant_view(void *ctx, uint32_t q, gi_depth_view *out)
{
    const distant_views *dv = ctx;
    uint32_t a, b;
    float theta, phi;
    gi_csm_order_cell(dv->desc->order, dv->desc->n_phi, dv->desc->n_theta, q, &a, &b);
    csm_cell_angles(dv->desc->n_theta, dv->desc->n_phi, a, b, &theta, &phi);
    csm_map_view(dv->sphere, theta, phi, out);
}

gi_result csm_build_object(const gi_gpu_scene *gs, uint32_t object, const float sphere[4], const csm_build_desc *desc,
                           const gi_host *host, float p0, float p1, gi_csm_data *out, gi_error *err)
{
    distant_views dv = {desc, sphere};
    csm_encode_desc e = {.object = object,
                         .M = desc->M,
                         .count = desc->n_theta * desc->n_phi,
                         .metric = GI_DEPTH_EYE_Z,
                         .z3 = desc->z3,
                         .sphere = sphere,
                         .shell = desc->shell,
                         .batch = desc->batch,
                         .view = distant_view,
                         .ctx = &dv,
                         .what = "depth maps"};
    return csm_encode_maps(gs, &e, host, p0, p1, out, err);
}
