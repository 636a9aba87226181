/* The precomputation loop of coherent shadow maps: render depth maps in
 * batches with the core's depth renderer (passes.h), read each one back and
 * stream it into the CSM codec (csm_codec.h). One loop for the csm plugin's
 * distant maps and local-light cube faces (Ritschel et al. 2007 §3.1, §3.3)
 * and for cssm_hrc's cube map at every atlas texel (Ritschel et al. 2008
 * §3.2).
 *
 * Maps are rendered in the order q = 0 .. count-1 (those `skip` names are
 * left out of the drawing, not of the codec). Map q goes to codec
 * stream q % streams as that stream's map q / streams: one stream for a
 * plain sequence of maps, six for cube maps whose faces are compressed one
 * sequence per face (view q = face q % 6 of cube q / 6).
 *
 *   gi_csm_precompute_desc d = {.depth = {.size = M, .surfaces = 2, ...},
 *                               .count = 6 * N, .streams = 6, .batch = 96,
 *                               .view = my_view, .depths = my_depths, .ctx = &me,
 *                               .host = host, .p1 = 1, .who = "cssm_hrc",
 *                               .what = "cube faces", .render_stage = "cssm_render"};
 *   gi_csm_data face[6];
 *   r = gi_csm_precompute(gs, &d, face, &err);   // then gi_csm_data_free each
 *
 * Host (optional, NULL in tests): cancellation is checked before each
 * batch (GI_ERR_CANCELLED), progress is reported after each one as
 * "<who>: <what>" with fraction p0 + p1 * (maps done) / count, and the time
 * goes to the stages render_stage (rendering and reading back) and
 * "compress" (depths and codec). Needs a current GL context.
 *
 * Ownership: on GI_OK out[0 .. streams-1] hold the compressed data (the
 * caller frees them with gi_csm_data_free); on any error they are zeroed and
 * own nothing. */
#ifndef GI_CSM_PRECOMPUTE_H
#define GI_CSM_PRECOMPUTE_H

#include "gi/algo/csm_codec.h"
#include "gi/method.h"
#include "gi/passes.h"

#ifdef __cplusplus
extern "C" {
#endif

#define GI_CSM_MAX_STREAMS 6u

typedef struct gi_csm_precompute_desc {
    gi_depth_desc depth; /* the depth renderer; depth.size is the codec's M */
    uint32_t count;      /* maps to render; a multiple of streams */
    uint32_t streams;    /* codec streams, 1 .. GI_CSM_MAX_STREAMS; 0 = 1 */
    uint32_t batch;      /* maps per gi_depth_render call; 0 = 16 */
    /* The view of map q. */
    void (*view)(void *ctx, uint32_t q, gi_depth_view *out);
    /* The codec's depths z1, z2 (M * M each) of map q from its read-back
     * layer `map` (M * M * 4 floats, gi_depth_read_layer) and its view. */
    void (*depths)(void *ctx, uint32_t q, const gi_depth_view *view, const float *map, float *z1,
                   float *z2);
    /* Optional (NULL: every map is drawn): nonzero when map q need not be
     * drawn (cssm_hrc: a texel whose cube map sees nothing it is asked
     * about, §3.3). Such a map is neither viewed nor rendered; `depths`
     * gets view and map NULL for it and still fills z1, z2. */
    int (*skip)(void *ctx, uint32_t q);
    void *ctx;
    const gi_host *host;      /* may be NULL */
    float p0, p1;             /* progress fraction p0 + p1 * done */
    const char *who;          /* plugin id in messages and progress ("csm") */
    const char *what;         /* the maps in messages and progress ("depth maps") */
    const char *render_stage; /* stage timer of render and read-back; NULL = "depth_render" */
} gi_csm_precompute_desc;

/* Renders, reads back and compresses the maps (see the manual above).
 * GI_ERR_INVALID_ARGUMENT for a desc that breaks the rules above, GI_ERR_GL
 * when the depth renderer cannot be made, GI_ERR_OUT_OF_MEMORY, the codec's
 * errors, GI_ERR_CANCELLED. */
gi_result gi_csm_precompute(const gi_gpu_scene *gs, const gi_csm_precompute_desc *d,
                            gi_csm_data *out, gi_error *err);

#ifdef __cplusplus
}
#endif
#endif
