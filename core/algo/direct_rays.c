/* Direct irradiance by shadow rays (gi/algo/direct_rays.h). */
#include "gi/algo/direct_rays.h"

#include "gi/envmap.h"
#include "gi/lights.h"
#include "gi/rng.h"
#include "gi/sampling.h"
#include "gi/sequences.h"

#include <math.h>
#include <stdlib.h>

typedef struct emitter {
    gi_vec3 p[3];
    gi_vec3 n; /* unit geometric normal (counter-clockwise front) */
    float area;
    float le[3];
    int double_sided;
} emitter;

struct gi_direct_rays {
    const gi_rt *rt;
    const gi_scene *scene;
    float time;
    /* 1e-4 of the scene's size: hits nearer than this are ignored, so that
     * a point is not shadowed by its own surface nor, on an edge or in a
     * corner (an element at a mesh vertex), by the face beside it */
    float eps;
    uint32_t count;
    emitter *em;
    float *cdf; /* count + 1: power CDF (area x luminance x sides) */
};

static float luminance(const float c[3])
{
    return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2];
}

/* The emitting triangles placed at rt's time and their power. */
static gi_result collect_emitters(gi_direct_rays *d, gi_error *err)
{
    const gi_scene *s = d->scene;
    const float *pos = gi_rt_positions(d->rt);
    uint32_t n = 0;
    for (uint32_t t = 0; t < s->triangle_count; t++)
        n += luminance(gi_scene_triangle_emission(s, t)) > 0.0f;
    d->em = malloc((size_t)(n ? n : 1) * sizeof *d->em);
    d->cdf = malloc(((size_t)n + 1) * sizeof *d->cdf);
    if (!d->em || !d->cdf)
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "direct rays: out of memory for %u emitters",
                            n);
    double total = 0.0;
    d->cdf[0] = 0.0f;
    for (uint32_t t = 0; t < s->triangle_count; t++) {
        const float *le = gi_scene_triangle_emission(s, t);
        if (!(luminance(le) > 0.0f))
            continue;
        emitter *e = &d->em[d->count];
        for (int k = 0; k < 3; k++)
            e->p[k] = gi_v3_load(&pos[3 * (size_t)s->indices[3 * t + (uint32_t)k]]);
        gi_vec3 c = gi_v3_cross(gi_v3_sub(e->p[1], e->p[0]), gi_v3_sub(e->p[2], e->p[0]));
        float len = gi_v3_length(c);
        e->area = 0.5f * len;
        e->n = len > 0.0f ? gi_v3_scale(c, 1.0f / len) : gi_v3(0, 0, 1);
        for (int k = 0; k < 3; k++)
            e->le[k] = le[k];
        e->double_sided = s->materials[s->vertices[s->indices[3 * t]].material].double_sided;
        total += (double)e->area * luminance(le) * (e->double_sided ? 2.0 : 1.0);
        d->cdf[++d->count] = (float)total;
    }
    for (uint32_t i = 1; i <= d->count; i++)
        d->cdf[i] = total > 0.0 ? (float)(d->cdf[i] / total) : (float)i / (float)d->count;
    if (d->count)
        d->cdf[d->count] = 1.0f;
    return GI_OK;
}

gi_result gi_direct_rays_create(const gi_rt *rt, gi_direct_rays **out, gi_error *err)
{
    if (!rt || !out)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "direct rays: NULL argument");
    *out = NULL;
    gi_direct_rays *d = calloc(1, sizeof *d);
    if (!d)
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "direct rays: out of memory");
    d->rt = rt;
    d->scene = gi_rt_scene(rt);
    d->time = gi_rt_time(rt);
    const float *b = d->scene->bounds;
    float size = gi_v3_length(gi_v3(b[3] - b[0], b[4] - b[1], b[5] - b[2]));
    d->eps = 1e-4f * (size > 0.0f ? size : 1.0f);
    gi_result r = collect_emitters(d, err);
    if (r != GI_OK) {
        gi_direct_rays_free(d);
        return r;
    }
    *out = d;
    return GI_OK;
}

void gi_direct_rays_free(gi_direct_rays *d)
{
    if (!d)
        return;
    free(d->em);
    free(d->cdf);
    free(d);
}

uint32_t gi_direct_rays_emitters(const gi_direct_rays *d)
{
    return d ? d->count : 0;
}

/* Point k of a stratified 2D set (the Sobol (0,2)-sequence, shifted by
 * the random offset r): stratified for any count, a power of two best. */
static void stratified(uint32_t k, const float r[2], float u[2])
{
    gi_sobol02(k, u);
    u[0] = gi_cp_rotate(u[0], r[0]);
    u[1] = gi_cp_rotate(u[1], r[1]);
}

/* Area lights: K points, the k-th triangle from the k-th of K strata of
 * the power CDF (one random shift for all), its point on the triangle from
 * the k-th stratified 2D point. (Not the first coordinate rescaled within
 * the triangle's interval: with K strata on a lattice that rescaled value
 * is the same for every k.) */
static void area_lights(const gi_direct_rays *d, gi_vec3 o, gi_vec3 n, uint32_t K, uint32_t *rng,
                        double E[3])
{
    if (!d->count || !K)
        return;
    float r0 = gi_rng_next_float(rng), r[2] = {gi_rng_next_float(rng), gi_rng_next_float(rng)},
          u[2];
    for (uint32_t k = 0; k < K; k++) {
        float u0 = ((float)k + r0) / (float)K;
        uint32_t i = gi_cdf_find_interval(d->cdf, d->count, u0 < 1.0f ? u0 : GI_ONE_MINUS_EPSILON);
        const emitter *e = &d->em[i];
        float pick = d->cdf[i + 1] - d->cdf[i];
        if (!(pick > 0.0f) || !(e->area > 0.0f))
            continue;
        float bc[3];
        stratified(k, r, u);
        gi_sample_uniform_triangle(u[0], u[1], bc);
        gi_vec3 y = gi_v3_add(gi_v3_add(gi_v3_scale(e->p[0], bc[0]), gi_v3_scale(e->p[1], bc[1])),
                              gi_v3_scale(e->p[2], bc[2]));
        gi_vec3 dv = gi_v3_sub(y, o);
        float r2 = gi_v3_dot(dv, dv);
        if (!(r2 > 0.0f))
            continue;
        gi_vec3 w = gi_v3_scale(dv, 1.0f / sqrtf(r2));
        float cx = gi_v3_dot(n, w), cy = gi_emitter_cos(e->n, w, e->double_sided);
        if (cx <= 0.0f || cy <= 0.0f)
            continue;
        if (gi_rt_occluded(d->rt, o, dv, d->eps / sqrtf(r2), 1.0f - 1e-4f))
            continue;
        double g = (double)cx * cy / r2 * e->area / pick / K; /* area pdf 1 / (pick x area) */
        for (int c = 0; c < 3; c++)
            E[c] += g * e->le[c];
    }
}

/* The environment along K directions (the map's sampler and cosine,
 * balanced; gi_envmap_mis_direction), each strategy's directions from its
 * own stratified set. */
static void environment(const gi_direct_rays *d, gi_vec3 o, gi_vec3 n, uint32_t K, uint32_t *rng,
                        double E[3])
{
    const gi_envmap *env = d->scene->envmap;
    if (!env || !K)
        return;
    const uint32_t half = K > 1 ? K / 2 : 1; /* the map's share, as gi_envmap_mis_direction's */
    float r[2][2] = {{gi_rng_next_float(rng), gi_rng_next_float(rng)},
                     {gi_rng_next_float(rng), gi_rng_next_float(rng)}};
    for (uint32_t k = 0; k < K; k++) {
        float u[2];
        stratified(k < half ? k : k - half, r[k >= half], u);
        gi_vec3 w;
        float weight = gi_envmap_mis_direction(env, n, k, K, u[0], u[1], &w);
        if (!(weight > 0.0f) || gi_rt_occluded(d->rt, o, w, d->eps, INFINITY))
            continue;
        float L[3];
        gi_envmap_eval(env, w, L);
        for (int c = 0; c < 3; c++)
            E[c] += (double)weight * L[c];
    }
}

/* KHR punctual lights, one shadow ray each. */
static void punctual(const gi_direct_rays *d, gi_vec3 o, gi_vec3 n, double E[3])
{
    const gi_scene *s = d->scene;
    for (uint32_t i = 0; i < s->light_count; i++) {
        const gi_light *lt = &s->lights[i];
        gi_light_frame f = gi_scene_light_at(s, i, d->time);
        gi_vec3 w;
        float scale, r;
        if (!gi_punctual_toward(lt, f, o, &w, &r, &scale))
            continue;
        float tfar = isinf(r) ? INFINITY : r * (1.0f - 1e-5f);
        float c = gi_v3_dot(n, w);
        if (c <= 0.0f || !(scale > 0.0f) || gi_rt_occluded(d->rt, o, w, d->eps, tfar))
            continue;
        for (int j = 0; j < 3; j++)
            E[j] += (double)(c * scale * lt->intensity[j]);
    }
}

void gi_direct_rays_irradiance(const gi_direct_rays *d, gi_vec3 x, gi_vec3 n, uint32_t area_samples,
                               uint32_t env_samples, uint32_t seed, float E[3])
{
    double acc[3] = {0.0, 0.0, 0.0};
    gi_vec3 o = x; /* hits nearer than eps are ignored instead of moving the origin, which would
                      change the distance to a near light */
    uint32_t rng = gi_rng_init(seed, 0, 0xd1ec7u);
    area_lights(d, o, n, area_samples, &rng, acc);
    environment(d, o, n, env_samples, &rng, acc);
    punctual(d, o, n, acc);
    for (int c = 0; c < 3; c++)
        E[c] = (float)acc[c];
}
