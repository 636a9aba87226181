/* One object's CSM over directions and the segment-occlusion test
 * (gi/algo/csm_distant.h; Ritschel et al. 2007 §3.1, §4.1, used for moving
 * objects by Ritschel et al. 2008 §3.3). */
#include "gi/algo/csm_distant.h"

#include "gi/algo/csm_order.h"
#include "gi/mesh.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define EYE 2.0f  /* the eye sits EYE R from the centre */
#define BATCH 16u /* maps per gi_depth_render call */

static void cell_basis_n(uint32_t n_theta, uint32_t n_phi, uint32_t a, uint32_t b, gi_vec3 *t,
                         gi_vec3 *bb, gi_vec3 *d)
{
    float theta = GI_PI * ((float)b + 0.5f) / (float)n_theta;
    float phi = 2.0f * GI_PI * ((float)a + 0.5f) / (float)n_phi;
    float st = sinf(theta);
    *d = gi_v3(st * cosf(phi), cosf(theta), st * sinf(phi));
    *t = gi_v3(-sinf(phi), 0.0f, cosf(phi));
    *bb = gi_v3_cross(*d, *t);
}

static void cell_basis(const gi_csm_distant *c, uint32_t a, uint32_t b, gi_vec3 *t, gi_vec3 *bb,
                       gi_vec3 *d)
{
    cell_basis_n(c->n_theta, c->n_phi, a, b, t, bb, d);
}

/* The direction cell nearest unit w: a along phi, b along theta. */
static void nearest_cell(gi_vec3 w, uint32_t n_theta, uint32_t n_phi, uint32_t *a, uint32_t *b)
{
    float theta = atan2f(sqrtf(w.x * w.x + w.z * w.z), w.y), phi = atan2f(w.z, w.x);
    if (phi < 0.0f)
        phi += 2.0f * GI_PI;
    float u = phi * (0.5f * GI_INV_PI) * (float)n_phi - 0.5f,
          v = theta * GI_INV_PI * (float)n_theta - 0.5f;
    *a = (uint32_t)floorf(u + 0.5f) % n_phi;
    int bi = (int)floorf(v + 0.5f);
    *b = (uint32_t)(bi < 0 ? 0 : bi >= (int)n_theta ? (int)n_theta - 1 : bi);
}

static void map_view(const gi_csm_distant *c, uint32_t q, gi_depth_view *out)
{
    uint32_t a = q % c->n_phi, b = q / c->n_phi; /* scanline order, a along phi */
    gi_vec3 t, bb, d;
    cell_basis(c, a, b, &t, &bb, &d);
    const float R = c->sphere[3];
    gi_vec3 eye =
        gi_v3_add(gi_v3(c->sphere[0], c->sphere[1], c->sphere[2]), gi_v3_scale(d, EYE * R));
    memset(out, 0, sizeof *out);
    float *m = out->view; /* column-major, rows t, b, d */
    m[0] = t.x, m[4] = t.y, m[8] = t.z, m[12] = -gi_v3_dot(t, eye);
    m[1] = bb.x, m[5] = bb.y, m[9] = bb.z, m[13] = -gi_v3_dot(bb, eye);
    m[2] = d.x, m[6] = d.y, m[10] = d.z, m[14] = -gi_v3_dot(d, eye);
    m[15] = 1.0f;
    gi_mat4_ortho(out->proj, -R, R, -R, R, 0.5f * (EYE - 1.0f) * R, (EYE + 1.5f) * R);
    out->projection = GI_PROJ_ORTHOGRAPHIC;
}

void gi_csm_distant_free(gi_csm_distant *c)
{
    if (!c)
        return;
    gi_csm_data_free(&c->data);
    memset(c, 0, sizeof *c);
}

gi_result gi_csm_distant_build(const gi_gpu_scene *gs, uint32_t object,
                               const gi_csm_distant_desc *desc, gi_csm_distant *out, gi_error *err)
{
    memset(out, 0, sizeof *out);
    const gi_scene *s = gs->scene;
    if (object >= s->object_count) {
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "csm_distant: object %u out of range (%u objects)", object,
                            s->object_count);
    }
    const uint32_t M = desc && desc->M ? desc->M : 32u;
    out->n_theta = desc && desc->n_theta ? desc->n_theta : 32u;
    out->n_phi = desc && desc->n_phi ? desc->n_phi : 2u * out->n_theta;
    gi_mesh_object_sphere(s, object, out->sphere);
    if (!(out->sphere[3] > 0.0f))
        out->sphere[3] = 1e-6f;
    const float shell = (desc && desc->shell > 0.0f ? desc->shell : 0.01f) * out->sphere[3];
    const uint32_t N = out->n_theta * out->n_phi;
    gi_depth_desc dd = {.size = M,
                        .surfaces = 2,
                        .metric = GI_DEPTH_EYE_Z,
                        .only_object = object + 1u,
                        .local = 1,
                        /* Both sides of every triangle: the first two surfaces of a closed
                         * object are its entry and exit, and the stored depth lies between
                         * them (the dual depth of csm_cpu.h), away from receivers beside it. Only
                         * the sides a shadow ray from the receiver meets (GI_SIDES_RECEIVERS)
                         * would leave the exit alone, where the object touches the ground:
                         * bunny_env's direct light by cssm_direct_tests env, relMSE 0.037
                         * (one side) against 0.024 (both; unshadowed 0.052), the error on
                         * ground points within a texel of the bunny's base. What both sides
                         * get wrong: a receiver that sees a single-sided triangle's back
                         * along w is shadowed by it (gi/scene.h lets that ray through);
                         * no receiver of the shipped scenes lies there. */
                        .receiver_side = GI_SIDES_BOTH};
    gi_depth_renderer *dr = gi_depth_renderer_create(&dd, err);
    if (!dr)
        return GI_ERR_GL;
    GLuint tex = gi_depth_texture_create(dr, BATCH);
    gi_depth_view views[BATCH];
    float *z1 = malloc((size_t)M * M * sizeof *z1), *z2 = malloc((size_t)M * M * sizeof *z2);
    float *map = malloc((size_t)M * M * 4 * sizeof *map);
    gi_csm_codec *enc = NULL;
    gi_result r = GI_ERR_OUT_OF_MEMORY;
    if (!z1 || !z2 || !map) {
        r = gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "csm_distant: out of memory for %u x %u maps",
                         M, M);
        goto done;
    }
    if ((r = gi_csm_codec_begin(M, N, &enc, err)) != GI_OK)
        goto done;
    for (uint32_t first = 0; first < N && r == GI_OK; first += BATCH) {
        uint32_t count = N - first < BATCH ? N - first : BATCH;
        for (uint32_t k = 0; k < count; k++)
            map_view(out, first + k, &views[k]);
        if ((r = gi_depth_render(dr, gs, views, count, tex, 0, err)) != GI_OK)
            break;
        for (uint32_t k = 0; k < count && r == GI_OK; k++) {
            gi_depth_read_layer_into(tex, M, k, map);
            for (size_t t = 0; t < (size_t)M * M; t++) {
                float a = map[4 * t], b = map[4 * t + 1];
                if (a >= FLT_MAX) { /* empty texel */
                    z1[t] = z2[t] = FLT_MAX;
                    continue;
                }
                /* a lone first surface (open mesh, grazing silhouette): a shell
                 * behind it, so that what lies behind stays blocked */
                z1[t] = a;
                z2[t] = b >= FLT_MAX ? a + shell : fmaxf(a, b);
            }
            r = gi_csm_codec_add_map(enc, first + k, z1, z2, err);
        }
    }
    if (r == GI_OK)
        r = gi_csm_codec_finish(enc, &out->data, err);
    else
        gi_csm_codec_free(enc);
    enc = NULL;
done:
    gi_csm_codec_free(enc);
    free(z1);
    free(z2);
    free(map);
    glDeleteTextures(1, &tex);
    gi_depth_renderer_free(dr);
    if (r != GI_OK)
        gi_csm_distant_free(out);
    return r;
}

int gi_csm_distant_blocks(const gi_csm_distant *c, gi_vec3 p, gi_vec3 q, float bias)
{
    gi_vec3 w = gi_v3_sub(q, p);
    float len = gi_v3_length(w);
    if (!(len > 0.0f) || !c->data.M)
        return 0;
    w = gi_v3_scale(w, 1.0f / len);
    uint32_t a, b;
    nearest_cell(w, c->n_theta, c->n_phi, &a, &b);
    gi_vec3 t, bb, d;
    cell_basis(c, a, b, &t, &bb, &d);
    const gi_vec3 centre = gi_v3(c->sphere[0], c->sphere[1], c->sphere[2]);
    const float R = c->sphere[3];
    /* the segment's point nearest the centre: there the map's line and the
     * segment's line part least inside the sphere */
    float s = gi_v3_dot(gi_v3_sub(centre, p), w);
    s = s < 0.0f ? 0.0f : s > len ? len : s;
    gi_vec3 m = gi_v3_sub(gi_v3_add(p, gi_v3_scale(w, s)), centre);
    float sx = gi_v3_dot(m, t) / R, sy = gi_v3_dot(m, bb) / R;
    if (!(fabsf(sx) < 1.0f && fabsf(sy) < 1.0f))
        return 0;
    const uint32_t M = c->data.M;
    uint32_t tx = (uint32_t)((sx * 0.5f + 0.5f) * (float)M),
             ty = (uint32_t)((sy * 0.5f + 0.5f) * (float)M);
    tx = tx >= M ? M - 1 : tx;
    ty = ty >= M ? M - 1 : ty;
    uint32_t i = gi_csm_order_index(GI_CSM_ORDER_SCANLINE, c->n_phi, c->n_theta, a, b);
    float z = gi_csm_lookup(&c->data, ty * M + tx, i);
    if (!(z < FLT_MAX))
        return 0;
    float dp = EYE * R - gi_v3_dot(gi_v3_sub(p, centre), d),
          dq = EYE * R - gi_v3_dot(gi_v3_sub(q, centre), d);
    float lo = fminf(dp, dq), hi = fmaxf(dp, dq);
    return lo + bias < z && z < hi - bias;
}

int gi_csm_dir_visible(const gi_csm_data *data, const float sphere[4], uint32_t n_theta,
                       uint32_t n_phi, gi_csm_order order, gi_vec3 x, gi_vec3 w, float bias)
{
    if (!data->M || !n_theta || !n_phi)
        return 1;
    uint32_t a, b;
    nearest_cell(w, n_theta, n_phi, &a, &b);
    gi_vec3 t, bb, d;
    cell_basis_n(n_theta, n_phi, a, b, &t, &bb, &d);
    gi_vec3 p = gi_v3_sub(x, gi_v3(sphere[0], sphere[1], sphere[2]));
    const float R = sphere[3];
    float sx = gi_v3_dot(p, t) / R, sy = gi_v3_dot(p, bb) / R, depth = EYE * R - gi_v3_dot(p, d);
    if (!(fabsf(sx) < 1.0f && fabsf(sy) < 1.0f))
        return 1;
    const uint32_t M = data->M;
    uint32_t tx = (uint32_t)((sx * 0.5f + 0.5f) * (float)M),
             ty = (uint32_t)((sy * 0.5f + 0.5f) * (float)M);
    tx = tx >= M ? M - 1 : tx;
    ty = ty >= M ? M - 1 : ty;
    uint32_t i = gi_csm_order_index(order, n_phi, n_theta, a, b);
    return gi_csm_visible(data, ty * M + tx, i, depth, bias);
}

int gi_csm_distant_visible(const gi_csm_distant *c, gi_vec3 x, gi_vec3 w, float bias)
{
    return gi_csm_dir_visible(&c->data, c->sphere, c->n_theta, c->n_phi, GI_CSM_ORDER_SCANLINE, x,
                              w, bias);
}
