/* Precomputation of one object's Coherent Shadow Map (§3.1, §4.1): the
 * N_theta x N_phi orthographic dual-depth maps around its bounding sphere,
 * rendered by the core's precomputation loop (gi/algo/csm_precompute.h: depth
 * renderer object-local, only this object, eye-z; read back and streamed
 * into the codec) in the chosen enumeration order. */
#include "csm_cpu.h"

#include "gi/algo/csm_precompute.h"

#include <stdlib.h>
#include <string.h>

/* The depth option of the maps (csm_texel_depths), for gi_csm_precompute. */
typedef struct encode_depths {
    const csm_encode_desc *desc;
    float *far; /* M x M, CSM_DEPTH_SPHERE only */
} encode_depths;

static void encode_view(void *ctx, uint32_t q, gi_depth_view *out)
{
    const encode_depths *e = ctx;
    e->desc->view(e->desc->ctx, q, out);
}

static void encode_texel_depths(void *ctx, uint32_t q, const gi_depth_view *v, const float *map,
                                float *z1, float *z2)
{
    (void)q;
    const encode_depths *e = ctx;
    const csm_encode_desc *desc = e->desc;
    /* depth option and open surfaces: csm_texel_depths (csm_cpu.h) */
    if (e->far)
        csm_sphere_far(v, desc->metric, desc->sphere, desc->M, e->far);
    csm_texel_depths(map, (size_t)desc->M * desc->M, desc->z3, desc->shell, e->far, z1, z2);
}

/* The maps draw both sides of every triangle (gi_depth_desc.receiver_side
 * GI_SIDES_BOTH), whatever the rule for sides (gi/scene.h) says of single-sided ones:
 * the dual depth of a closed object must lie between its entry and its exit
 * (§3.1), and only both sides give both. A single-sided open surface then
 * blocks from both sides, where the rule lets a ray from a receiver that
 * sees its back through; no receiver of the shipped scenes lies there. The
 * sides a shadow ray meets alone (GI_SIDES_RECEIVERS) keep only the exit of a
 * closed object: csm_local's cube-map test then fails (41 of 47
 * disagreements near a silhouette, 90 % required). */
gi_result csm_encode_maps(const gi_gpu_scene *gs, const csm_encode_desc *desc, const gi_host *host,
                          float p0, float p1, gi_csm_data *out, gi_error *err)
{
    memset(out, 0, sizeof *out);
    const uint32_t M = desc->M;
    encode_depths e = {desc, NULL};
    if (desc->z3 == CSM_DEPTH_SPHERE) {
        e.far = desc->sphere ? malloc((size_t)M * M * sizeof *e.far) : NULL;
        if (!e.far)
            return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "csm: out of memory for %u x %u %s", M,
                                M, desc->what);
    }
    gi_csm_precompute_desc d = {.depth = {.size = M,
                                          .surfaces = desc->z3 ? 3u : 2u,
                                          .metric = desc->metric,
                                          .only_object = desc->object + 1u,
                                          .local = 1,
                                          .cull = 0,
                                          /* both sides: see below */
                                          .receiver_side = GI_SIDES_BOTH},
                                .count = desc->count,
                                .streams = 1,
                                .batch = desc->batch,
                                .view = encode_view,
                                .depths = encode_texel_depths,
                                .ctx = &e,
                                .host = host,
                                .p0 = p0,
                                .p1 = p1,
                                .who = "csm",
                                .what = desc->what};
    gi_result r = gi_csm_precompute(gs, &d, out, err);
    free(e.far);
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

gi_result csm_build_object(const gi_gpu_scene *gs, uint32_t object, const float sphere[4],
                           const csm_build_desc *desc, const gi_host *host, float p0, float p1,
                           gi_csm_data *out, gi_error *err)
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
