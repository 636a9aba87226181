/* Direct light by Coherent Shadow Maps and Monte Carlo (direct=csm): the
 * "Direct Light" alternative of §4.7 of the cssm_hrc paper (direct_csm.h). */
#include "direct_csm.h"

#include "gi/envmap.h"
#include "gi/lights.h"
#include "gi/mesh.h"
#include "gi/rng.h"
#include "gi/sampling.h"
#include "gi/sequences.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

void cssm_csm_direct_free(cssm_csm_direct *d)
{
    if (!d)
        return;
    free(d->pts.texels);
    free(d->order);
    cssm_maps_free(&d->maps);
    free(d->pt_Le);
    free(d->pt_w);
    free(d->pt_ds);
    free(d->light_point);
    free(d->em);
    for (uint32_t k = 0; d->distant && k < d->object_count; k++)
        gi_csm_distant_free(&d->distant[k]);
    free(d->distant);
    free(d->local_from_world);
    free(d->scale);
    free(d->sphere_w);
    memset(d, 0, sizeof *d);
}

uint64_t cssm_csm_direct_bytes(const cssm_csm_direct *d)
{
    uint64_t b = cssm_maps_bytes(&d->maps);
    for (uint32_t k = 0; d->distant && k < d->object_count; k++)
        b += d->distant[k].data.bytes_compressed;
    return b;
}

/* The emitter whose CDF interval holds u (the core's
 * gi_emitter_find_cpu); *u is remapped to [0, 1) inside that interval. */
static uint32_t emitter_find(const cssm_csm_direct *d, float *u)
{
    uint32_t lo = gi_emitter_find_cpu(d->em, d->em_count, *u);
    float c0 = lo ? d->em[lo - 1].cdf : 0.0f, w = d->em[lo].cdf - c0;
    float r = w > 0.0f ? (*u - c0) / w : 0.5f;
    *u = r < 0.0f ? 0.0f : r > GI_ONE_MINUS_EPSILON ? GI_ONE_MINUS_EPSILON : r;
    return lo;
}

/* A point on emitter e at (u1, u2): position, unit normal, area pdf. */
static gi_vec3 emitter_point(const cssm_csm_direct *d, const gi_scene *s, uint32_t e, float u1,
                             float u2, gi_vec3 *n, float *pdf_area)
{
    gi_vec3 p[3];
    gi_scene_triangle_world(s, d->em[e].triangle, d->time, p);
    gi_vec3 ng = gi_v3_cross(gi_v3_sub(p[1], p[0]), gi_v3_sub(p[2], p[0]));
    float area = 0.5f * gi_v3_length(ng);
    float b[3];
    gi_sample_uniform_triangle(u1, u2, b);
    *n = area > 0.0f ? gi_v3_scale(ng, 0.5f / area) : gi_v3(0, 0, 0);
    *pdf_area = area > 0.0f ? d->em[e].pdf / area : 0.0f;
    return gi_v3_add(gi_v3_add(gi_v3_scale(p[0], b[0]), gi_v3_scale(p[1], b[1])),
                     gi_v3_scale(p[2], b[2]));
}

static int triangle_double_sided(const gi_scene *s, uint32_t tri)
{
    return s->materials[s->vertices[s->indices[3 * tri]].material].double_sided;
}

static gi_result out_of_memory(gi_error *err)
{
    return gi_error_set(err, GI_ERR_OUT_OF_MEMORY,
                        "cssm_hrc: out of memory for the direct light's CSMs");
}

/* The core's emitter table read back: power CDF over the emitting
 * triangles. */
static gi_result read_emitters(const gi_gpu_scene *gs, cssm_csm_direct *out, gi_error *err)
{
    out->em_count = gs->emitter_count;
    if (out->em_count) {
        out->em = malloc(out->em_count * sizeof *out->em);
        if (!out->em)
            return out_of_memory(err);
        glGetNamedBufferSubData(gs->ssbo_emitters, 0, (GLsizeiptr)(out->em_count * sizeof *out->em),
                                out->em);
    }
    return GI_OK;
}

/* Per scene light its point: point and spot lights one each after the NA
 * area points, directional lights none; counts both kinds. */
static gi_result light_points(const gi_scene *s, uint32_t NA, cssm_csm_direct *out,
                              uint32_t *punctual, uint32_t *directional, gi_error *err)
{
    out->light_point = malloc((s->light_count ? s->light_count : 1) * sizeof *out->light_point);
    if (!out->light_point)
        return out_of_memory(err);
    for (uint32_t i = 0; i < s->light_count; i++) {
        if (s->lights[i].type == GI_LIGHT_DIRECTIONAL) {
            out->light_point[i] = UINT32_MAX;
            (*directional)++;
        } else {
            out->light_point[i] = NA + (*punctual)++;
        }
    }
    return GI_OK;
}

/* The NA points on the area lights: a Hammersley set through the power
 * CDF, stratified by power, with their radiance and weights. */
static void area_points(const gi_scene *s, uint32_t NA, cssm_csm_direct *out)
{
    for (uint32_t i = 0; i < NA; i++) {
        float h[2];
        gi_hammersley(i, NA, h);
        h[0] = ((float)i + 0.5f) / (float)NA;
        uint32_t e = emitter_find(out, &h[0]);
        gi_vec3 n;
        float pdf;
        cssm_texel *x = &out->pts.texels[i];
        x->p = emitter_point(out, s, e, h[0], h[1], &n, &pdf);
        x->n = n;
        x->chart = -1;
        x->x = x->y = CSSM_NO_XY;
        x->triangle = out->em[e].triangle;
        memcpy(&out->pt_Le[3 * i], gi_scene_triangle_emission(s, out->em[e].triangle),
               3 * sizeof(float));
        out->pt_w[i] = pdf > 0.0f ? 1.0f / ((float)NA * pdf) : 0.0f;
        out->pt_ds[i] = (unsigned char)triangle_double_sided(s, out->em[e].triangle);
        if (out->pt_ds[i]) /* a double-sided emitter lights both sides: its whole cube map
                              counts */
            x->n = gi_v3(0, 0, 0);
    }
}

/* The P light points (NA on the area lights, then the punctual lights)
 * and a depth cube map at each, compressed in a greedy order. */
static gi_result point_maps(const gi_gpu_scene *gs, uint32_t NA, uint32_t P, uint32_t M,
                            const gi_host *host, cssm_csm_direct *out, gi_error *err)
{
    const gi_scene *s = gs->scene;
    out->pts.texels = calloc(P, sizeof *out->pts.texels);
    out->pt_Le = malloc(3 * (size_t)(NA ? NA : 1) * sizeof *out->pt_Le);
    out->pt_w = malloc((NA ? NA : 1) * sizeof *out->pt_w);
    out->pt_ds = malloc(NA ? NA : 1);
    if (!out->pts.texels || !out->pt_Le || !out->pt_w || !out->pt_ds)
        return out_of_memory(err);
    out->pts.count = P;
    out->pts.diameter = out->diameter;
    area_points(s, NA, out);
    for (uint32_t i = 0; i < s->light_count; i++)
        if (out->light_point[i] != UINT32_MAX) {
            cssm_texel *x = &out->pts.texels[out->light_point[i]];
            x->p = gi_scene_light_at(s, i, gs->time).position;
            x->n = gi_v3(0, 0, 0); /* no "don't care" half */
            x->chart = -1;
            x->x = x->y = CSSM_NO_XY;
        }
    out->order = cssm_traverse(&out->pts, CSSM_GREEDY);
    if (!out->order)
        return out_of_memory(err);
    cssm_build_opts o = {.render_stage = "csm_render"};
    return cssm_maps_build_ex(gs, &out->pts, out->order, M, &o, host, &out->maps, err);
}

/* Distant light (directional lights, the environment): per object its
 * CSM over directions, its frame and world bounding sphere. */
static gi_result distant_maps(const gi_gpu_scene *gs, const gi_host *host, cssm_csm_direct *out,
                              gi_error *err)
{
    const gi_scene *s = gs->scene;
    const uint32_t K = s->object_count;
    out->distant = calloc(K ? K : 1, sizeof *out->distant);
    out->local_from_world = malloc((K ? K : 1) * sizeof *out->local_from_world);
    out->scale = malloc((K ? K : 1) * sizeof *out->scale);
    out->sphere_w = malloc(4 * (size_t)(K ? K : 1) * sizeof *out->sphere_w);
    if (!out->distant || !out->local_from_world || !out->scale || !out->sphere_w)
        return out_of_memory(err);
    out->object_count = K;
    for (uint32_t k = 0; k < K; k++) {
        if (host && host->cancelled && host->cancelled(host))
            return gi_error_set(err, GI_ERR_CANCELLED, "cssm_hrc: cancelled");
        float T[16];
        gi_scene_object_transform(s, k, gs->time, T);
        if (!gi_mat4_invert(out->local_from_world[k], T))
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                "cssm_hrc: object %u has a singular transform", k);
        float sc = gi_v3_length(gi_mat4_dir(T, gi_v3(1, 0, 0)));
        out->scale[k] = sc > 0.0f ? sc : 1.0f;
        gi_csm_distant_desc dd = {.M = 32, .n_theta = 32};
        gi_result r = gi_csm_distant_build(gs, k, &dd, &out->distant[k], err);
        if (r != GI_OK)
            return r;
        const float *sp = out->distant[k].sphere;
        gi_vec3 c = gi_mat4_point(T, gi_v3(sp[0], sp[1], sp[2]));
        out->sphere_w[4 * k] = c.x, out->sphere_w[4 * k + 1] = c.y, out->sphere_w[4 * k + 2] = c.z;
        out->sphere_w[4 * k + 3] = sp[3] * out->scale[k];
    }
    return GI_OK;
}

gi_result cssm_csm_direct_build(const gi_gpu_scene *gs, float diameter, uint32_t N, uint32_t M,
                                const gi_host *host, cssm_csm_direct *out, gi_error *err)
{
    memset(out, 0, sizeof *out);
    const gi_scene *s = gs->scene;
    out->diameter = diameter;
    out->time = gs->time;
    /* the core's emitter table: power CDF over the emitting triangles */
    gi_result r = read_emitters(gs, out, err);
    const uint32_t NA = out->em_count ? N : 0;
    uint32_t punctual = 0, directional = 0;
    if (r == GI_OK)
        r = light_points(s, NA, out, &punctual, &directional, err);
    out->area_points = NA;
    if (r == GI_OK && NA + punctual)
        r = point_maps(gs, NA, NA + punctual, M, host, out, err);
    if (r == GI_OK && (directional || (s->has_environment && s->envmap)))
        r = distant_maps(gs, host, out, err);
    if (r != GI_OK)
        cssm_csm_direct_free(out);
    return r;
}

int cssm_csm_direct_open(const cssm_csm_direct *d, gi_vec3 x, gi_vec3 n, gi_vec3 w, float bias)
{
    /* slope-scaled bias: within one map texel the receiver's plane moves
     * away from the texel centre's depth by up to a texel x tan(angle
     * between its normal and w) (the ground plane's own map at grazing
     * directions) */
    float cn = fabsf(gi_v3_dot(n, w));
    cn = cn > 0.1f ? cn : 0.1f;
    const float slope = sqrtf(1.0f - cn * cn) / cn;
    for (uint32_t k = 0; d->distant && k < d->object_count; k++) {
        const float *sw = &d->sphere_w[4 * k];
        gi_vec3 c = gi_v3(sw[0], sw[1], sw[2]), oc = gi_v3_sub(c, x);
        float t = gi_v3_dot(oc, w), R = sw[3];
        float d2 = gi_v3_dot(oc, oc) - (t > 0.0f ? t * t : 0.0f);
        if (d2 >= R * R) /* the ray misses the object's sphere */
            continue;
        /* x projected into the object's map nearest w (its frame), CSM §3.2 */
        const float *Ti = d->local_from_world[k];
        const gi_csm_distant *cd = &d->distant[k];
        const float texel = 2.0f * cd->sphere[3] / (float)(cd->data.M ? cd->data.M : 1u);
        if (!gi_csm_distant_visible(cd, gi_mat4_point(Ti, x), gi_v3_normalize(gi_mat4_dir(Ti, w)),
                                    bias / d->scale[k] + texel * slope))
            return 0;
    }
    return 1;
}

/* The receiver's BRDF (cos excluded) toward unit w: kd / pi, plus the
 * normalised Phong lobe about the mirror direction of wo for a glossy one. */
static void brdf(const cssm_receiver *rc, gi_vec3 w, float f[3])
{
    float lobe = 0.0f;
    if (rc->glossy) {
        gi_vec3 rr = gi_v3_sub(gi_v3_scale(rc->n, 2.0f * gi_v3_dot(rc->n, rc->wo)), rc->wo);
        float cl = gi_v3_dot(rr, w);
        lobe = cl > 0.0f ? (rc->exponent + 2.0f) / (2.0f * GI_PI) * powf(cl, rc->exponent) : 0.0f;
    }
    for (int k = 0; k < 3; k++)
        f[k] = rc->kd[k] / GI_PI + (rc->glossy ? rc->ks[k] * lobe : 0.0f);
}

/* The nearest of the N area points to y (the CSM's nearest filter over
 * the light's positions). */
static uint32_t nearest_point(const cssm_csm_direct *d, gi_vec3 y)
{
    uint32_t best = 0;
    float bd = FLT_MAX;
    for (uint32_t i = 0; i < d->area_points; i++) {
        gi_vec3 v = gi_v3_sub(d->pts.texels[i].p, y);
        float dd = gi_v3_dot(v, v);
        if (dd < bd)
            bd = dd, best = i;
    }
    return best;
}

/* One area-light sample: light point y (normal ny, emitted Le, weight wgt =
 * 1 / (count pdf)), shadowed by cube map j. */
static void area_sample(const cssm_csm_direct *d, const cssm_receiver *rc, gi_vec3 y, gi_vec3 ny,
                        int ds, const float Le[3], float wgt, uint32_t j, float bias, int pcf,
                        float out[3])
{
    gi_vec3 v = gi_v3_sub(y, rc->x);
    float d2 = gi_v3_dot(v, v);
    if (!(d2 > 0.0f) || !(wgt > 0.0f))
        return;
    gi_vec3 w = gi_v3_scale(v, 1.0f / sqrtf(d2));
    float cx = gi_v3_dot(rc->n, w), cy = gi_emitter_cos(ny, w, ds);
    if (!(cx > 0.0f) || !(cy > 0.0f))
        return;
    float V = cssm_visible(&d->maps, j, rc->x, bias, pcf);
    if (!(V > 0.0f))
        return;
    float f[3], g = cx * cy / d2 * wgt * V;
    brdf(rc, w, f);
    for (int k = 0; k < 3; k++)
        out[k] += f[k] * Le[k] * g;
}

void cssm_csm_direct_eval(const cssm_csm_direct *d, const gi_scene *s, const cssm_receiver *rc,
                          uint32_t S, uint32_t env_samples, uint32_t seed, float bias, int pcf,
                          float out[3])
{
    uint32_t rng = gi_rng_init(seed, 0, 0xc5d1u);
    /* area lights */
    if (d->area_points && S == 0) {
        for (uint32_t i = 0; i < d->area_points; i++)
            area_sample(d, rc, d->pts.texels[i].p, d->pts.texels[i].n, d->pt_ds[i],
                        &d->pt_Le[3 * i], d->pt_w[i], i, bias, pcf, out);
    } else if (d->area_points) {
        float sub[3] = {0, 0, 0};
        for (uint32_t k = 0; k < S; k++) {
            float u1 = ((float)k + gi_rng_next_float(&rng)) / (float)S,
                  u2 = gi_rng_next_float(&rng);
            u1 = u1 < GI_ONE_MINUS_EPSILON ? u1 : GI_ONE_MINUS_EPSILON;
            uint32_t e = emitter_find(d, &u1);
            gi_vec3 ny;
            float pdf;
            gi_vec3 y = emitter_point(d, s, e, u1, u2, &ny, &pdf);
            int ds = triangle_double_sided(s, d->em[e].triangle);
            if (ds) /* a double-sided emitter: its normal faces the receiver */
                ny = gi_v3_dot(ny, gi_v3_sub(rc->x, y)) < 0.0f ? gi_v3_scale(ny, -1.0f) : ny;
            area_sample(d, rc, y, ny, 1, gi_scene_triangle_emission(s, d->em[e].triangle),
                        pdf > 0.0f ? 1.0f / ((float)S * pdf) : 0.0f, nearest_point(d, y), bias, pcf,
                        sub);
        }
        for (int k = 0; k < 3; k++)
            out[k] += sub[k];
    }
    /* point, spot and directional lights */
    for (uint32_t i = 0; i < s->light_count; i++) {
        const gi_light *l = &s->lights[i];
        gi_light_frame fr = gi_scene_light_at(s, i, d->time);
        gi_vec3 w;
        float k = 0.0f;
        if (l->type == GI_LIGHT_DIRECTIONAL) {
            w = gi_v3_scale(gi_v3_normalize(fr.direction), -1.0f);
            float cs = gi_v3_dot(rc->n, w);
            if (!(cs > 0.0f) || !cssm_csm_direct_open(d, rc->x, rc->n, w, bias))
                continue;
            k = cs;
        } else {
            gi_vec3 v = gi_v3_sub(fr.position, rc->x);
            float dist = gi_v3_length(v);
            if (!(dist > 0.0f))
                continue;
            w = gi_v3_scale(v, 1.0f / dist);
            float cs = gi_v3_dot(rc->n, w);
            if (!(cs > 0.0f))
                continue;
            k = cs / (dist * dist) * gi_range_window(dist, l->range);
            if (l->type == GI_LIGHT_SPOT)
                k *=
                    gi_spot_falloff(gi_v3_dot(gi_v3_normalize(fr.direction), gi_v3_scale(w, -1.0f)),
                                    cosf(l->inner_cone), cosf(l->outer_cone));
            if (!(k > 0.0f))
                continue;
            k *= cssm_visible(&d->maps, d->light_point[i], rc->x, bias, pcf);
            if (!(k > 0.0f))
                continue;
        }
        float f[3];
        brdf(rc, w, f);
        for (int j = 0; j < 3; j++)
            out[j] += f[j] * l->intensity[j] * k;
    }
    /* the environment: half the directions from the map's sampler, half
     * cosine-weighted, balance heuristic; visibility by the distant CSMs */
    const gi_envmap *env = s->has_environment ? s->envmap : NULL;
    if (env && env_samples) {
        for (uint32_t k = 0; k < env_samples; k++) {
            float u1 = gi_rng_next_float(&rng), u2 = gi_rng_next_float(&rng);
            gi_vec3 w;
            float weight = gi_envmap_mis_direction(env, rc->n, k, env_samples, u1, u2, &w);
            if (!(weight > 0.0f) || !cssm_csm_direct_open(d, rc->x, rc->n, w, bias))
                continue;
            float L[3], f[3];
            gi_envmap_eval(env, w, L);
            brdf(rc, w, f);
            for (int j = 0; j < 3; j++)
                out[j] += f[j] * L[j] * weight;
        }
    }
}
