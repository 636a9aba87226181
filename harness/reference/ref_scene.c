/* The scene as the reference traces it, at one time t: the core's ray
 * casting (gi/raytrace.h: world-space vertices validated, world shading
 * normals, one Embree 3 triangle geometry, build quality high), and beside
 * it per-triangle geometric normals and areas, materials as gi_brdf, the
 * emitter-selection CDF (area x luminance of the emission), punctual lights
 * and the camera placed at t. */
#include "ref_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Coordinates beyond this overflow squared distances in float. */
#define REF_MAX_COORD 1e18f

static int finite3(gi_vec3 v)
{
    return isfinite(v.x) && isfinite(v.y) && isfinite(v.z);
}

static int coord_ok(gi_vec3 v)
{
    return finite3(v) && fabsf(v.x) <= REF_MAX_COORD && fabsf(v.y) <= REF_MAX_COORD &&
           fabsf(v.z) <= REF_MAX_COORD;
}

static void build_materials(ref_scene *rs)
{
    const gi_scene *s = rs->scene;
    for (uint32_t i = 0; i < s->material_count; i++) {
        const gi_material *m = &s->materials[i];
        ref_material *r = &rs->mats[i];
        memcpy(r->brdf.kd, m->albedo, sizeof r->brdf.kd);
        memcpy(r->brdf.ks, m->ks, sizeof r->brdf.ks);
        r->brdf.n = m->exponent;
        r->brdf.mirror = m->mirror;
        r->textured = m->albedo_texture >= 0 && (uint32_t)m->albedo_texture < s->texture_count;
        memcpy(r->emission, m->emission, sizeof r->emission);
        r->emits = m->emission[0] > 0.0f || m->emission[1] > 0.0f || m->emission[2] > 0.0f;
        r->double_sided = m->double_sided;
    }
}

static void build_triangles(ref_scene *rs)
{
    const gi_scene *s = rs->scene;
    for (uint32_t t = 0; t < s->triangle_count; t++) {
        const uint32_t *idx = s->indices + 3 * (size_t)t;
        gi_vec3 p0 = gi_v3_load(rs->pos + 3 * (size_t)idx[0]);
        gi_vec3 p1 = gi_v3_load(rs->pos + 3 * (size_t)idx[1]);
        gi_vec3 p2 = gi_v3_load(rs->pos + 3 * (size_t)idx[2]);
        gi_vec3 c = gi_v3_cross(gi_v3_sub(p1, p0), gi_v3_sub(p2, p0));
        float len = gi_v3_length(c);
        ref_tri *r = &rs->tris[t];
        memset(r, 0, sizeof *r);
        r->ng = len > 0.0f && isfinite(len) ? gi_v3_scale(c, 1.0f / len) : gi_v3(0.0f, 0.0f, 1.0f);
        r->area = isfinite(len) ? 0.5f * len : 0.0f;
        r->material = s->vertices[idx[0]].material;
    }
}

/* Emitter CDF by power (area x luminance); probabilities read back from the
 * CDF so that they are exactly the selection probabilities. */
static gi_result build_emitters(ref_scene *rs, gi_error *err)
{
    const gi_scene *s = rs->scene;
    uint32_t n = s->emitter_count;
    rs->emitter_count = 0;
    if (n == 0)
        return GI_OK;
    rs->emitters = malloc(n * sizeof *rs->emitters);
    rs->emitter_cdf = malloc((n + 1) * sizeof *rs->emitter_cdf);
    double *power = malloc(n * sizeof *power);
    if (!rs->emitters || !rs->emitter_cdf || !power) {
        free(power);
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "reference: out of memory (emitters)");
    }
    double total = 0.0;
    for (uint32_t i = 0; i < n; i++) {
        uint32_t t = s->emitters[i];
        const ref_material *m = &rs->mats[rs->tris[t].material];
        double p = (double)rs->tris[t].area * gi_luminance(m->emission);
        power[i] = p > 0.0 && isfinite(p) ? p : 0.0;
        total += power[i];
    }
    if (total > 0.0) {
        double acc = 0.0;
        rs->emitter_cdf[0] = 0.0f;
        for (uint32_t i = 0; i < n; i++) {
            acc += power[i];
            rs->emitters[i] = s->emitters[i];
            rs->emitter_cdf[i + 1] = (float)(acc / total);
        }
        rs->emitter_cdf[n] = 1.0f;
        for (uint32_t i = 0; i < n; i++)
            rs->tris[rs->emitters[i]].light_prob = rs->emitter_cdf[i + 1] - rs->emitter_cdf[i];
        rs->emitter_count = n;
    }
    free(power);
    return GI_OK;
}

static gi_result place_lights(ref_scene *rs, float t, gi_error *err)
{
    const gi_scene *s = rs->scene;
    if (s->light_count == 0)
        return GI_OK;
    rs->lights = calloc(s->light_count, sizeof *rs->lights);
    if (!rs->lights)
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "reference: out of memory (lights)");
    for (uint32_t i = 0; i < s->light_count; i++) {
        const gi_light *l = &s->lights[i];
        gi_light_frame f = gi_scene_light_at(s, i, t);
        if (!coord_ok(f.position) || !finite3(f.direction))
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                "%s: light %u '%s' is not finite at t = %g", s->path, i,
                                l->name ? l->name : "(unnamed)", (double)t);
        ref_light *r = &rs->lights[i];
        r->type = l->type;
        r->position = f.position;
        r->direction = f.direction;
        memcpy(r->intensity, l->intensity, sizeof r->intensity);
        r->range = l->range;
        r->cos_inner = cosf(l->inner_cone);
        r->cos_outer = cosf(l->outer_cone);
    }
    rs->light_count = s->light_count;
    return GI_OK;
}

static gi_result place_camera(ref_scene *rs, const gi_ref_desc *d, gi_error *err)
{
    gi_camera_frame cf =
        d->camera_frame ? *d->camera_frame : gi_scene_camera_at(rs->scene, d->camera, d->time);
    ref_camera *c = &rs->cam;
    c->eye = cf.eye;
    c->forward = gi_v3_normalize(cf.forward);
    c->right = gi_v3_normalize(gi_v3_cross(c->forward, cf.up));
    c->up = gi_v3_cross(c->right, c->forward);
    c->tan_half_y = tanf(0.5f * cf.yfov);
    c->aspect = (float)d->width / (float)d->height;
    c->znear = cf.znear;
    c->zfar = cf.zfar > cf.znear ? cf.zfar : INFINITY;
    if (!coord_ok(c->eye) || !finite3(c->right) || !finite3(c->up) || !(c->tan_half_y > 0.0f) ||
        !isfinite(c->tan_half_y) || !isfinite(c->znear))
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: camera %d is not finite at t = %g",
                            rs->scene->path, d->camera, (double)d->time);
    return GI_OK;
}

gi_result ref_scene_build(ref_scene *rs, const gi_ref_desc *d, gi_error *err)
{
    const gi_scene *s = d->scene;
    memset(rs, 0, sizeof *rs);
    rs->scene = s;
    rs->width = d->width;
    rs->height = d->height;
    rs->seed = d->seed;
    rs->max_bounces = d->max_bounces;
    rs->strategy = d->strategy;
    rs->pixel_center = d->pixel_center;
    gi_result res = place_camera(rs, d, err);
    if (res != GI_OK)
        return res;

    res = gi_rt_create_ex(s, d->time, d->robust_traversal ? 0u : (unsigned)GI_RT_FAST_TRAVERSAL,
                          &rs->rt, err);
    if (res != GI_OK)
        return res;
    rs->pos = gi_rt_positions(rs->rt);
    rs->nrm = gi_rt_normals(rs->rt);
    rs->tris = malloc((size_t)(s->triangle_count ? s->triangle_count : 1) * sizeof *rs->tris);
    rs->mats = calloc(s->material_count ? s->material_count : 1, sizeof *rs->mats);
    if (!rs->tris || !rs->mats)
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "reference: out of memory (%u triangles)",
                            s->triangle_count);

    build_materials(rs);
    build_triangles(rs);
    res = build_emitters(rs, err);
    if (res == GI_OK)
        res = place_lights(rs, d->time, err);
    if (res != GI_OK)
        return res;
    if (s->envmap) {
        rs->env = s->envmap;
        rs->env_sampleable = s->envmap->marg_cdf[s->envmap->height] > 0.0f;
    }
    return GI_OK;
}

void ref_scene_release(ref_scene *rs)
{
    gi_rt_free(rs->rt);
    free(rs->tris);
    free(rs->mats);
    free(rs->emitters);
    free(rs->emitter_cdf);
    free(rs->lights);
    memset(rs, 0, sizeof *rs);
}
