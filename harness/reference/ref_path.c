/* The reference's path integrator: one camera sample, unidirectional path
 * tracing with next-event estimation and multiple importance sampling
 * (Veach 1997, ch. 9: one light sample and one BSDF sample per vertex,
 * power heuristic with beta = 2), Russian roulette after the third bounce.
 *
 * Conventions shared with every GPU method (docs/scenes.md "Scene conventions"):
 *  - the shading normal is the interpolated vertex normal on the side of
 *    wo (reversed on a double-sided triangle's back); where it still faces
 *    away from wo (smooth normals near a silhouette) the geometric normal
 *    stands in (gi_facing_normal, gi/scene.h; the G-buffer does the same);
 *    the geometric normal decides which side a ray leaves from: a sampled
 *    direction on the other geometric side than wo carries nothing (no
 *    light through surfaces);
 *  - the one rule for sides (gi/scene.h): gi_rt never reports the back of
 *    a single-sided triangle (camera, bounce and shadow rays pass through
 *    it), so a hit seen from behind is double-sided: its normals are turned
 *    to wo and it emits (front and back) like its front;
 *  - gi_brdf (brdf.h) is the material, its mirror lobe a delta lobe.
 *
 * Path vertex d (d = 1 at the first hit) adds its emission (a path of
 * d - 1 bounces); if d <= max_bounces it adds next-event estimates and
 * samples the BSDF to go on. So the image for B bounces holds exactly the
 * paths of at most B scattering events, and the random numbers a sample
 * draws do not depend on B until its path is cut: the images for B and
 * B + 1 share every path prefix (the tests rely on it). */
#include "ref_internal.h"

#include "gi/lights.h"
#include "gi/rng.h"
#include "gi/sampling.h"

#include <math.h>
#include <string.h>

/* Bounces 1..RR_AFTER are never cut by Russian roulette. */
#define RR_AFTER 3
#define RR_MAX_SURVIVAL 0.95f

/* A path vertex, everything oriented to the side wo is on. */
typedef struct surface {
    gi_vec3 p;  /* position, from the barycentrics */
    gi_vec3 ng; /* unit geometric normal on the side of wo */
    gi_vec3 n;  /* unit shading normal on the side of wo */
    gi_vec3 wo; /* towards the previous vertex */
    int front;  /* wo is on the front (CCW) side */
    gi_brdf brdf;
    const ref_material *mat;
    const ref_tri *tri;
} surface;

static inline float next(uint32_t *rng)
{
    return gi_rng_next_float(rng);
}

static inline int trace(const ref_scene *rs, gi_vec3 o, gi_vec3 d, float tnear, float tfar,
                        ref_hit *h, ref_counters *c)
{
    c->rays++;
    return gi_rt_intersect_tuv(rs->rt, o, d, tnear, tfar, &h->t, &h->u, &h->v, &h->prim);
}

/* 1 when something lies on the segment o + t d, 0 <= t <= tfar. */
static inline int occluded(const ref_scene *rs, gi_vec3 o, gi_vec3 d, float tfar, ref_counters *c)
{
    c->rays++;
    return gi_rt_occluded(rs->rt, o, d, 0.0f, tfar);
}

/* Ray origin just off the surface on the side of n, by an offset that
 * grows with the magnitude of p: a fixed number of float ulps away from
 * the origin, a fixed distance near it (Waechter and Binder, "A Fast and
 * Robust Method for Avoiding Self-Intersection", Ray Tracing Gems ch. 6). */
static inline float offset_coord(float p, float n)
{
    const float origin = 1.0f / 32.0f, float_scale = 1.0f / 65536.0f, int_scale = 256.0f;
    if (fabsf(p) < origin)
        return p + float_scale * n;
    int32_t of = (int32_t)(int_scale * n);
    int32_t bits;
    memcpy(&bits, &p, sizeof bits);
    bits += p < 0.0f ? -of : of;
    float r;
    memcpy(&r, &bits, sizeof r);
    return r;
}

static inline gi_vec3 offset_ray(gi_vec3 p, gi_vec3 n)
{
    return gi_v3(offset_coord(p.x, n.x), offset_coord(p.y, n.y), offset_coord(p.z, n.z));
}

static inline gi_vec3 vertex_pos(const ref_scene *rs, uint32_t v)
{
    return gi_v3_load(rs->pos + 3 * (size_t)v);
}

static void make_surface(const ref_scene *rs, const ref_hit *h, gi_vec3 dir, surface *s)
{
    const gi_scene *sc = rs->scene;
    const uint32_t *idx = sc->indices + 3 * (size_t)h->prim;
    float b0 = 1.0f - h->u - h->v, b1 = h->u, b2 = h->v;
    s->p = gi_v3_add(
        gi_v3_add(gi_v3_scale(vertex_pos(rs, idx[0]), b0), gi_v3_scale(vertex_pos(rs, idx[1]), b1)),
        gi_v3_scale(vertex_pos(rs, idx[2]), b2));
    s->tri = &rs->tris[h->prim];
    s->mat = &rs->mats[s->tri->material];
    s->wo = gi_v3_scale(dir, -1.0f);
    s->front = gi_v3_dot(s->tri->ng, s->wo) > 0.0f;
    s->ng = s->front ? s->tri->ng : gi_v3_scale(s->tri->ng, -1.0f);
    const float *n0 = rs->nrm + 3 * (size_t)idx[0], *n1 = rs->nrm + 3 * (size_t)idx[1],
                *n2 = rs->nrm + 3 * (size_t)idx[2];
    gi_vec3 n = gi_v3(b0 * n0[0] + b1 * n1[0] + b2 * n2[0], b0 * n0[1] + b1 * n1[1] + b2 * n2[1],
                      b0 * n0[2] + b1 * n1[2] + b2 * n2[2]);
    float len = gi_v3_length(n);
    n = len > 1e-12f && isfinite(len) ? gi_v3_scale(n, 1.0f / len) : s->ng;
    /* Reversed on a double-sided triangle's back; where it still faces
     * away from wo, the geometric normal (the G-buffer's rule too). */
    s->n = gi_facing_normal(s->front ? n : gi_v3_scale(n, -1.0f), s->ng, s->wo);
    s->brdf = s->mat->brdf;
    if (s->mat->textured) {
        const float *t0 = sc->vertices[idx[0]].uv, *t1 = sc->vertices[idx[1]].uv,
                    *t2 = sc->vertices[idx[2]].uv;
        float uv[2] = {b0 * t0[0] + b1 * t1[0] + b2 * t2[0], b0 * t0[1] + b1 * t1[1] + b2 * t2[1]};
        gi_scene_albedo(sc, s->tri->material, uv, s->brdf.kd);
    }
}

static inline void add_scaled(float L[3], const float beta[3], const float a[3], float s)
{
    for (int k = 0; k < 3; k++)
        L[k] += beta[k] * a[k] * s;
}

static inline int is_black(const float f[3])
{
    return f[0] <= 0.0f && f[1] <= 0.0f && f[2] <= 0.0f;
}

/* Weight of a light-sampled contribution whose BSDF pdf is pdf_b. */
static inline float light_weight(const ref_scene *rs, float pdf_l, float pdf_b)
{
    return rs->strategy == GI_REF_STRATEGY_MIS ? gi_power_heuristic(1.0f, pdf_l, 1.0f, pdf_b)
                                               : 1.0f;
}

/* Weight of emission reached by a BSDF sample of pdf pdf_b, when light
 * sampling would have drawn it with pdf pdf_l (0: it cannot). */
static inline float bsdf_weight(const ref_scene *rs, float pdf_b, float pdf_l)
{
    if (!(pdf_l > 0.0f))
        return 1.0f;
    switch (rs->strategy) {
    case GI_REF_STRATEGY_LIGHT:
        return 0.0f;
    case GI_REF_STRATEGY_BSDF:
        return 1.0f;
    default:
        return gi_power_heuristic(1.0f, pdf_b, 1.0f, pdf_l);
    }
}

/* One emitter triangle by power, a uniform point on it. */
static void sample_area_light(const ref_scene *rs, const surface *s, const float beta[3],
                              uint32_t *rng, float L[3], ref_counters *c)
{
    float u0 = next(rng), u1 = next(rng), u2 = next(rng);
    uint32_t t = rs->emitters[gi_cdf_find_interval(rs->emitter_cdf, rs->emitter_count, u0)];
    const ref_tri *lt = &rs->tris[t];
    if (!(lt->light_prob > 0.0f) || !(lt->area > 0.0f))
        return;
    const uint32_t *idx = rs->scene->indices + 3 * (size_t)t;
    float b[3];
    gi_sample_uniform_triangle(u1, u2, b);
    gi_vec3 y = gi_v3_add(gi_v3_add(gi_v3_scale(vertex_pos(rs, idx[0]), b[0]),
                                    gi_v3_scale(vertex_pos(rs, idx[1]), b[1])),
                          gi_v3_scale(vertex_pos(rs, idx[2]), b[2]));
    gi_vec3 d = gi_v3_sub(y, s->p);
    float dist2 = gi_v3_dot(d, d);
    if (!(dist2 > 0.0f))
        return;
    gi_vec3 w = gi_v3_scale(d, 1.0f / sqrtf(dist2));
    if (gi_v3_dot(w, s->ng) <= 0.0f)
        return;
    const ref_material *lm = &rs->mats[lt->material];
    float cos_y = gi_emitter_cos(lt->ng, w, lm->double_sided);
    if (!(cos_y > 0.0f))
        return;
    float f[3];
    gi_brdf_eval(&s->brdf, s->n, s->wo, w, f);
    if (is_black(f))
        return;
    float cos_x = gi_v3_dot(s->n, w);
    float pdf_l = lt->light_prob * dist2 / (lt->area * cos_y);
    float mis = light_weight(rs, pdf_l, gi_brdf_pdf(&s->brdf, s->n, s->wo, w));
    /* Both ends off their surfaces, each towards the other. */
    gi_vec3 o = offset_ray(s->p, s->ng);
    gi_vec3 ye = offset_ray(y, gi_v3_dot(lt->ng, w) < 0.0f ? lt->ng : gi_v3_scale(lt->ng, -1.0f));
    gi_vec3 seg = gi_v3_sub(ye, o);
    float len = gi_v3_length(seg);
    if (!(len > 0.0f) || occluded(rs, o, gi_v3_scale(seg, 1.0f / len), len, c))
        return;
    float s_ = cos_x * mis / pdf_l;
    for (int k = 0; k < 3; k++)
        L[k] += beta[k] * f[k] * lm->emission[k] * s_;
}

/* One direction from the environment map's luminance x sin(theta) CDF. */
static void sample_environment(const ref_scene *rs, const surface *s, const float beta[3],
                               uint32_t *rng, float L[3], ref_counters *c)
{
    float u1 = next(rng), u2 = next(rng);
    gi_vec3 w;
    float pdf_l = gi_envmap_sample(rs->env, u1, u2, &w);
    if (!(pdf_l > 0.0f) || gi_v3_dot(w, s->ng) <= 0.0f)
        return;
    float f[3];
    gi_brdf_eval(&s->brdf, s->n, s->wo, w, f);
    if (is_black(f))
        return;
    float Le[3];
    gi_envmap_eval(rs->env, w, Le);
    if (is_black(Le))
        return;
    float mis = light_weight(rs, pdf_l, gi_brdf_pdf(&s->brdf, s->n, s->wo, w));
    if (occluded(rs, offset_ray(s->p, s->ng), w, INFINITY, c))
        return;
    float s_ = gi_v3_dot(s->n, w) * mis / pdf_l;
    for (int k = 0; k < 3; k++)
        L[k] += beta[k] * f[k] * Le[k] * s_;
}

/* Point, spot and directional lights: every one, with a shadow ray. */
static void punctual_lights(const ref_scene *rs, const surface *s, const float beta[3], float L[3],
                            ref_counters *c)
{
    for (uint32_t i = 0; i < rs->light_count; i++) {
        const ref_light *l = &rs->lights[i];
        gi_vec3 w;
        float scale, dist = INFINITY;
        if (l->type == GI_LIGHT_DIRECTIONAL) {
            w = gi_v3_scale(l->direction, -1.0f);
            scale = 1.0f;
        } else {
            gi_vec3 d = gi_v3_sub(l->position, s->p);
            dist = gi_v3_length(d);
            if (!(dist > 0.0f))
                continue;
            w = gi_v3_scale(d, 1.0f / dist);
            scale = gi_range_window(dist, l->range) / (dist * dist);
            if (l->type == GI_LIGHT_SPOT)
                scale *= gi_spot_falloff(-gi_v3_dot(w, l->direction), l->cos_inner, l->cos_outer);
        }
        if (!(scale > 0.0f) || gi_v3_dot(w, s->ng) <= 0.0f)
            continue;
        float f[3];
        gi_brdf_eval(&s->brdf, s->n, s->wo, w, f);
        if (is_black(f))
            continue;
        gi_vec3 o = offset_ray(s->p, s->ng);
        float tfar = isinf(dist) ? INFINITY : gi_v3_length(gi_v3_sub(l->position, o));
        if (occluded(rs, o, w, tfar, c))
            continue;
        float s_ = gi_v3_dot(s->n, w) * scale;
        for (int k = 0; k < 3; k++)
            L[k] += beta[k] * f[k] * l->intensity[k] * s_;
    }
}

void ref_camera_ray(const ref_scene *rs, uint32_t x, uint32_t y, uint32_t *rng, ref_ray *ray)
{
    const ref_camera *cam = &rs->cam;
    /* Box filter: a uniform point in the pixel; row 0 is the top. With
     * pixel_center the point is the centre (the numbers are still drawn, so
     * that the rest of the path uses the same stream). */
    float jx = next(rng), jy = next(rng);
    if (rs->pixel_center)
        jx = jy = 0.5f;
    float sx = (((float)x + jx) / (float)rs->width * 2.0f - 1.0f) * cam->tan_half_y * cam->aspect;
    float sy = (1.0f - ((float)y + jy) / (float)rs->height * 2.0f) * cam->tan_half_y;
    ray->d = gi_v3_normalize(
        gi_v3_add(cam->forward, gi_v3_add(gi_v3_scale(cam->right, sx), gi_v3_scale(cam->up, sy))));
    /* The rasteriser's near and far planes, so both see the same surfaces. */
    float cos_f = gi_v3_dot(ray->d, cam->forward);
    ray->o = cam->eye;
    ray->tnear = cam->znear / cos_f;
    ray->tfar = cam->zfar / cos_f;
}

void ref_path_trace(const ref_scene *rs, const ref_ray *ray, const ref_hit *first, int first_hit,
                    uint32_t *rng, float L[3], ref_counters *c)
{
    L[0] = L[1] = L[2] = 0.0f;
    float beta[3] = {1.0f, 1.0f, 1.0f};
    gi_vec3 o = ray->o, d = ray->d;
    float tnear = ray->tnear, tfar = ray->tfar;
    int prev_delta = 1; /* the camera ray: emission seen directly counts in full */
    float prev_pdf = 0.0f;
    const int nee = rs->strategy != GI_REF_STRATEGY_BSDF;

    for (int depth = 0;; depth++) { /* depth = bounces so far */
        ref_hit h;
        int found;
        if (depth == 0 && first) { /* the caller traced the camera ray */
            c->rays++;
            h = *first;
            found = first_hit;
        } else {
            found = trace(rs, o, d, tnear, tfar, &h, c);
        }
        if (!found) {
            if (rs->env) {
                float Le[3];
                gi_envmap_eval(rs->env, d, Le);
                float w = 1.0f;
                if (!prev_delta && rs->env_sampleable)
                    w = bsdf_weight(rs, prev_pdf, gi_envmap_pdf(rs->env, d));
                add_scaled(L, beta, Le, w);
            }
            break;
        }
        surface s;
        make_surface(rs, &h, d, &s);
        if (s.mat->emits && (s.front || s.mat->double_sided)) {
            float w = 1.0f;
            if (!prev_delta) {
                float cos_y = fabsf(gi_v3_dot(s.tri->ng, s.wo));
                float pdf_l =
                    cos_y > 0.0f ? s.tri->light_prob * h.t * h.t / (s.tri->area * cos_y) : 0.0f;
                w = bsdf_weight(rs, prev_pdf, pdf_l);
            }
            add_scaled(L, beta, s.mat->emission, w);
        }
        if (rs->max_bounces >= 0 && depth >= rs->max_bounces)
            break;

        /* Next-event estimation: paths of depth + 1 bounces. */
        if (nee && rs->emitter_count > 0)
            sample_area_light(rs, &s, beta, rng, L, c);
        if (nee && rs->env_sampleable)
            sample_environment(rs, &s, beta, rng, L, c);
        if (rs->light_count > 0)
            punctual_lights(rs, &s, beta, L, c);

        /* The vertex a continuation would find could add only emission
         * (depth + 1 = max_bounces); a scene without emitters and without
         * an environment has none to add, so the ray is not traced (the
         * image is the same bits, the path ends here either way). */
        if (depth + 1 == rs->max_bounces && rs->emitter_count == 0 && !rs->env)
            break;

        /* BSDF sampling continues the path. */
        float u1 = next(rng), u2 = next(rng), u3 = next(rng);
        gi_vec3 wi;
        float pdf, weight[3];
        int delta;
        gi_brdf_sample(&s.brdf, s.n, s.wo, u1, u2, u3, &wi, &pdf, weight, &delta);
        if (!(pdf > 0.0f) || gi_v3_dot(wi, s.ng) <= 0.0f)
            break;
        for (int k = 0; k < 3; k++)
            beta[k] *= weight[k];
        if (depth + 1 > RR_AFTER) {
            float q = fminf(RR_MAX_SURVIVAL, fmaxf(beta[0], fmaxf(beta[1], beta[2])));
            if (!(next(rng) < q))
                break;
            for (int k = 0; k < 3; k++)
                beta[k] /= q;
        }
        if (is_black(beta))
            break;
        o = offset_ray(s.p, s.ng);
        d = wi;
        tnear = 0.0f;
        tfar = INFINITY;
        prev_delta = delta;
        prev_pdf = pdf;
    }
}
