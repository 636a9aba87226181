/* Coherent surface shadow maps (§3.2): a depth cube map at every atlas
 * texel, rendered in a coherent traversal order and compressed by the
 * core's CSM codec (one sequence per cube face), and the visibility query
 * of §3.2.2. */
#include "cssm.h"

#include "gi/algo/csm_precompute.h"
#include "gi/algo/cubemap.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define CSSM_BATCH 16u /* texels (6 faces each) per gi_depth_render call */

/* Per face: 1 where the whole texel cone lies in the negative half-space
 * of normal n (all four corner directions below the plane): "don't care"
 * (§3.2.1). corners: 6 (M+1)^2 corner directions. */
static void dont_care_mask(const gi_vec3 *corners, uint32_t M, gi_vec3 n, int face,
                           unsigned char *mask)
{
    const gi_vec3 *c = corners + (size_t)face * (M + 1) * (M + 1);
    for (uint32_t y = 0; y < M; y++)
        for (uint32_t x = 0; x < M; x++) {
            int below = 1;
            for (uint32_t k = 0; k < 4 && below; k++) {
                uint32_t cx = x + (k & 1), cy = y + (k >> 1);
                below = gi_v3_dot(c[cy * (M + 1) + cx], n) < 0.0f;
            }
            mask[y * M + x] = (unsigned char)below;
        }
}

gi_result cssm_maps_setup(const cssm_atlas *a, const uint32_t *order, uint32_t M, cssm_maps *out,
                          gi_error *err)
{
    memset(out, 0, sizeof *out);
    const uint32_t N = a->count;
    out->M = M;
    out->N = N;
    out->znear = 1e-3f * a->diameter;
    out->zfar = 1.01f * a->diameter;
    out->face_texels = 6ull * M * M * N;
    out->seq = malloc(N * sizeof *out->seq);
    out->eye = malloc(N * sizeof *out->eye);
    if (!out->seq || !out->eye) {
        cssm_maps_free(out);
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "cssm_hrc: out of memory for %u cube maps",
                            N);
    }
    /* the eye sits just above the surface so that its own plane is not seen */
    for (uint32_t k = 0; k < N; k++) {
        out->seq[order[k]] = k;
        const cssm_texel *x = &a->texels[order[k]];
        out->eye[order[k]] = gi_v3_add(x->p, gi_v3_scale(x->n, 2.0f * out->znear));
    }
    return GI_OK;
}

gi_result cssm_maps_build(const gi_gpu_scene *gs, const cssm_atlas *a, const uint32_t *order,
                          uint32_t M, const gi_host *host, cssm_maps *out, gi_error *err)
{
    return cssm_maps_build_ex(gs, a, order, M, NULL, host, out, err);
}

/* What the core's precomputation loop (gi/algo/csm_precompute.h) asks of the
 * cube maps: map q is face q % 6 of the texel visited (q / 6)-th. */
typedef struct build_ctx {
    const cssm_atlas *a;
    const uint32_t *order;
    const cssm_build_opts *opts;
    cssm_maps *out;
    const gi_vec3 *corners; /* 6 (M+1)^2 corner directions of the face texels */
    unsigned char *mask;
    gi_depth_view cube[6]; /* the views of the texel last asked for */
    uint32_t cube_of;      /* its texel + 1 (0: none yet) */
} build_ctx;

static void build_view(void *ctx, uint32_t q, gi_depth_view *view)
{
    build_ctx *b = ctx;
    const uint32_t i = b->order[q / 6];
    if (b->cube_of != i + 1) {
        gi_depth_cube_views(b->out->eye[i], b->out->znear, b->out->zfar, b->cube);
        b->cube_of = i + 1;
    }
    *view = b->cube[q % 6];
}

/* texels whose maps are all "don't care" are not drawn */
static int build_skip(void *ctx, uint32_t q)
{
    const build_ctx *b = ctx;
    return b->opts->dont_care && b->opts->dont_care[b->order[q / 6]];
}

static void build_depths(void *ctx, uint32_t q, const gi_depth_view *view, const float *map,
                         float *z1, float *z2)
{
    (void)view;
    build_ctx *b = ctx;
    const uint32_t M = b->out->M;
    const cssm_texel *x = &b->a->texels[b->order[q / 6]];
    gi_vec3 xn = x->n;
    if (b->opts->eye_from_world) /* the normal in the maps' space (rigid) */
        xn = gi_v3_normalize(gi_mat4_dir(b->opts->eye_from_world, xn));
    dont_care_mask(b->corners, M, xn, (int)(q % 6), b->mask);
    for (uint32_t t = 0; t < M * M; t++) {
        if (b->mask[t] || !map) { /* any value: an interval that never breaks a run */
            z1[t] = -FLT_MAX;
            z2[t] = FLT_MAX;
            b->out->dont_care++;
            continue;
        }
        float a1 = map[4 * t], a2 = map[4 * t + 1];
        if (b->opts->escape) { /* surface and "no surface" never share a run (env_cssm.h) */
            const float far = b->out->zfar;
            z1[t] = a1 >= far ? far : a1;
            z2[t] = a1 >= far ? FLT_MAX : fminf(fmaxf(a2, a1), far);
            continue;
        }
        if (a1 < 0.0f) /* GI_SIDES_ANY_THEN_RECEIVERS: a first surface the receivers do
                          not see, a caster only with one they see behind it */
            a1 = a2 >= FLT_MAX ? FLT_MAX : -a1;
        z1[t] = a1 >= FLT_MAX ? FLT_MAX : a1;
        z2[t] = a1 >= FLT_MAX || a2 >= FLT_MAX ? FLT_MAX : fmaxf(a2, z1[t]);
    }
}

gi_result cssm_maps_build_ex(const gi_gpu_scene *gs, const cssm_atlas *a, const uint32_t *order,
                             uint32_t M, const cssm_build_opts *opts, const gi_host *host,
                             cssm_maps *out, gi_error *err)
{
    static const cssm_build_opts none = {0};
    if (!opts)
        opts = &none;
    if (opts->escape && !opts->from_eye)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "cssm_hrc: escape intervals answer rays cast from the eye (from_eye)");
    gi_result r = cssm_maps_setup(a, order, M, out, err);
    if (r != GI_OK)
        return r;
    out->escape = opts->escape;
    if (opts->eye_from_world)
        for (uint32_t i = 0; i < a->count; i++)
            out->eye[i] = gi_mat4_point(opts->eye_from_world, out->eye[i]);
    const uint32_t N = a->count;
    gi_vec3 *corners = malloc(6 * (size_t)(M + 1) * (M + 1) * sizeof *corners);
    unsigned char *mask = malloc((size_t)M * M);
    if (!corners || !mask) {
        free(corners), free(mask);
        cssm_maps_free(out);
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "cssm_hrc: out of memory for %u cube maps",
                            N);
    }
    for (int f = 0; f < 6; f++) {
        gi_vec3 s, t, fw;
        gi_cube_basis(f, &s, &t, &fw);
        for (uint32_t y = 0; y <= M; y++)
            for (uint32_t x = 0; x <= M; x++) {
                float sx = (float)x / (float)M * 2.0f - 1.0f,
                      sy = (float)y / (float)M * 2.0f - 1.0f;
                corners[((size_t)f * (M + 1) + y) * (M + 1) + x] =
                    gi_v3_add(fw, gi_v3_add(gi_v3_scale(s, sx), gi_v3_scale(t, sy)));
            }
    }
    build_ctx b = {
        .a = a, .order = order, .opts = opts, .out = out, .corners = corners, .mask = mask};
    gi_csm_precompute_desc d = {
        .depth = {.size = M,
                  .surfaces = 2,
                  .metric = GI_DEPTH_RADIAL,
                  .only_object = opts->only_object,
                  .local = opts->local,
                  .cull = 0,
                  /* dual depth by the rule for the
                   * rays the maps answer (cssm.h) */
                  .receiver_side =
                      opts->from_eye ? GI_SIDES_EYE_THEN_BOTH : GI_SIDES_ANY_THEN_RECEIVERS,
                  .skip_objects = opts->skip_objects},
        .count = 6 * N,
        .streams = 6,
        .batch = 6 * CSSM_BATCH,
        .view = build_view,
        .depths = build_depths,
        .skip = opts->dont_care ? build_skip : NULL,
        .ctx = &b,
        .host = host,
        .p1 = 1.0f,
        .who = "cssm_hrc",
        .what = "cube maps",
        .render_stage = opts->render_stage ? opts->render_stage : "cssm_render"};
    r = gi_csm_precompute(gs, &d, out->face, err);
    free(corners), free(mask);
    if (r != GI_OK)
        cssm_maps_free(out);
    return r;
}

void cssm_maps_free(cssm_maps *m)
{
    if (!m)
        return;
    for (int f = 0; f < 6; f++)
        gi_csm_data_free(&m->face[f]);
    free(m->seq);
    free(m->eye);
    memset(m, 0, sizeof *m);
}

uint64_t cssm_maps_bytes(const cssm_maps *m)
{
    uint64_t b = 0;
    for (int f = 0; f < 6; f++)
        b += m->face[f].bytes_compressed;
    return b;
}

uint64_t cssm_maps_bytes_uncompressed(const cssm_maps *m)
{
    return 2ull * m->face_texels;
}

uint64_t cssm_maps_segments(const cssm_maps *m)
{
    uint64_t b = 0;
    for (int f = 0; f < 6; f++)
        b += m->face[f].segment_count;
    return b;
}

float cssm_visible(const cssm_maps *m, uint32_t j, gi_vec3 x, float bias, int pcf)
{
    gi_vec3 d = gi_v3_sub(x, m->eye[j]);
    float depth = gi_v3_length(d);
    if (!(depth > 0.0f))
        return 1.0f;
    int face = gi_cube_face(d);
    float sx, sy;
    gi_cube_project(face, d, &sx, &sy);
    const uint32_t M = m->M, i = m->seq[j];
    const gi_csm_data *data = &m->face[face];
    float fx = (sx * 0.5f + 0.5f) * (float)M, fy = (sy * 0.5f + 0.5f) * (float)M;
    if (!pcf) {
        int tx = (int)fx, ty = (int)fy;
        tx = tx < 0 ? 0 : tx >= (int)M ? (int)M - 1 : tx;
        ty = ty < 0 ? 0 : ty >= (int)M ? (int)M - 1 : ty;
        return (float)gi_csm_visible(data, (uint32_t)ty * M + (uint32_t)tx, i, depth, bias);
    }
    /* 2 x 2 texels around the projection, bilinear weights, clamped to the face */
    float gx = fx - 0.5f, gy = fy - 0.5f;
    int x0 = (int)floorf(gx), y0 = (int)floorf(gy);
    float wx = gx - (float)x0, wy = gy - (float)y0, v = 0.0f;
    for (int k = 0; k < 4; k++) {
        int tx = x0 + (k & 1), ty = y0 + (k >> 1);
        tx = tx < 0 ? 0 : tx >= (int)M ? (int)M - 1 : tx;
        ty = ty < 0 ? 0 : ty >= (int)M ? (int)M - 1 : ty;
        float w = ((k & 1) ? wx : 1.0f - wx) * ((k >> 1) ? wy : 1.0f - wy);
        if (w > 0.0f)
            v += w * (float)gi_csm_visible(data, (uint32_t)ty * M + (uint32_t)tx, i, depth, bias);
    }
    return v;
}
