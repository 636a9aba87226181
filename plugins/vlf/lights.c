/* The scene's lights in the vlf method other than emissive faces and sky
 * (not in the paper, which has only those): directional lights entering
 * the radiance interfaces like the sky, point and spot lights by shadow
 * rays, their irradiance and first shot into the maps, from where
 * propagation carries it on. */
#define _POSIX_C_SOURCE 200809L
#include "field_internal.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "gi/lights.h"
#include "gi/raytrace.h"

/* Directional lights: parallel light, so it enters like the sky of Fig.
 * 6, into the interfaces of the three directions around the light's with
 * their barycentric weights, radiance alpha E / dOmega, so that each
 * carries alpha E through a unit of area across it. */
static gi_result add_suns(vlf_field *f, const gi_scene *s, float t)
{
    f->sun = calloc((size_t)f->prm.l * 2 * 3, sizeof *f->sun);
    if (!f->sun)
        return GI_ERR_OUT_OF_MEMORY;
    for (uint32_t li = 0; li < s->light_count; li++) {
        if (s->lights[li].type != GI_LIGHT_DIRECTIONAL)
            continue;
        gi_light_frame fr = gi_scene_light_at(s, li, t);
        float len = gi_v3_length(fr.direction);
        if (!(len > 0.0f))
            continue;
        uint32_t node[3];
        float al[3];
        vlf_dirs_locate(&f->dirs, gi_v3_scale(fr.direction, 1.0f / len), node, al);
        for (int k = 0; k < 3; k++)
            for (int q = 0; q < 3; q++)
                f->sun[3 * node[k] + (uint32_t)q] +=
                    al[k] * s->lights[li].intensity[q] / f->dirs.solid_angle[node[k]];
        f->sun_count++;
    }
    return GI_OK;
}

/* Point and spot lights at time t, with the scene for their shadow rays:
 * a first shot by shadow rays (vlf_punctual_first_shot). */
static gi_result add_punctual(vlf_field *f, const gi_scene *s, float t, gi_error *err)
{
    for (uint32_t li = 0; li < s->light_count; li++)
        f->punctual_count += s->lights[li].type != GI_LIGHT_DIRECTIONAL;
    if (!f->punctual_count)
        return GI_OK;
    f->punctual = calloc(f->punctual_count, sizeof *f->punctual);
    if (!f->punctual)
        return vlf_build_out_of_memory(f, err);
    uint32_t k = 0;
    for (uint32_t li = 0; li < s->light_count; li++) {
        const gi_light *L = &s->lights[li];
        if (L->type == GI_LIGHT_DIRECTIONAL)
            continue;
        gi_light_frame fr = gi_scene_light_at(s, li, t);
        vlf_punctual *P = &f->punctual[k++];
        P->spot = L->type == GI_LIGHT_SPOT;
        P->pos = fr.position;
        P->dir = fr.direction;
        memcpy(P->I, L->intensity, sizeof P->I);
        P->range = L->range;
        P->cos_inner = cosf(L->inner_cone);
        P->cos_outer = cosf(L->outer_cone);
    }
    gi_error e;
    gi_result rc = gi_rt_create(s, t, &f->rt, &e);
    if (rc != GI_OK)
        return gi_error_set(err, rc, "vlf: shadow rays for the point lights: %s", e.text);
    return GI_OK;
}

gi_result vlf_add_lights(vlf_field *f, const gi_scene *s, float t, gi_error *err)
{
    if (add_suns(f, s, t) != GI_OK)
        return vlf_build_out_of_memory(f, err);
    return add_punctual(f, s, t, err);
}

/* Irradiance at world point x of surface normal n from the point and spot
 * lights, each through a shadow ray (Embree, core raytrace.h); per light
 * into E + 3 k, and the unit direction toward it into w + k. */
static void punctual_at(const vlf_field *f, gi_vec3 x, gi_vec3 n, float *E, gi_vec3 *w)
{
    for (uint32_t k = 0; k < f->punctual_count; k++) {
        const vlf_punctual *L = &f->punctual[k];
        E[3 * k] = E[3 * k + 1] = E[3 * k + 2] = 0.0f;
        gi_vec3 d = gi_v3_sub(L->pos, x);
        float dist = gi_v3_length(d);
        if (!(dist > 0.0f))
            continue;
        w[k] = gi_v3_scale(d, 1.0f / dist);
        float c = gi_v3_dot(n, w[k]);
        if (c <= 0.0f)
            continue;
        float scale = gi_range_window(dist, L->range) / (dist * dist);
        if (L->spot)
            scale *= gi_spot_falloff(-gi_v3_dot(w[k], L->dir), L->cos_inner, L->cos_outer);
        if (!(scale > 0.0f))
            continue;
        gi_vec3 o = gi_v3_add(x, gi_v3_scale(n, 1e-4f * f->radius));
        float tfar = gi_v3_length(gi_v3_sub(L->pos, o)) * (1.0f - 1e-5f);
        if (gi_rt_occluded(f->rt, o, w[k], 0.0f, tfar))
            continue;
        for (int q = 0; q < 3; q++)
            E[3 * k + (uint32_t)q] = L->I[q] * c * scale;
    }
}

/* The point and spot lights' first shot (not in the paper, which has
 * emissive faces and sky): their direct irradiance on every diffuse
 * element (at the element's centroid on its face) and their reflection by
 * every non-diffuse face into its tiles (each covered cell's point on the
 * face, reflected as §3.4 reflects the interface's light), added to the
 * next maps of the first iteration: shot on from there like received
 * light. */
gi_result vlf_punctual_first_shot(vlf_field *f)
{
    uint32_t P = f->punctual_count, l = f->prm.l;
    float *E = malloc((size_t)P * 3 * sizeof *E), *g = malloc((size_t)2 * l * sizeof *g);
    gi_vec3 *w = malloc((size_t)P * sizeof *w);
    if (!E || !g || !w) {
        free(E), free(g), free(w);
        return GI_ERR_OUT_OF_MEMORY;
    }
    for (uint32_t e = 0; e < f->elem_count; e++) {
        if (!(f->elem_area[e] > 0.0f))
            continue;
        const vlf_face *fc = &f->faces[f->elem_face[e]];
        gi_vec3 q =
            gi_v3_add(fc->origin,
                      gi_v3_add(gi_v3_scale(fc->t, f->elem_c[2 * (size_t)e] / f->prm.density),
                                gi_v3_scale(fc->b, f->elem_c[2 * (size_t)e + 1] / f->prm.density)));
        punctual_at(f, gi_v3_add(f->centre, gi_v3_scale(q, f->radius)), fc->n, E, w);
        for (uint32_t k = 0; k < P; k++)
            for (int c = 0; c < 3; c++)
                f->E_next[3 * (size_t)e + (size_t)c] += E[3 * k + (uint32_t)c];
    }
    for (uint32_t fi = 0; fi < f->face_count; fi++) {
        const vlf_face *fc = &f->faces[fi];
        if (fc->nd < 0)
            continue;
        for (uint32_t i = 0; i < l; i++) {
            const vlf_rect *rj = &f->rects[(size_t)fc->nd * l + i];
            const vlf_psf *ps = &f->psf[i];
            float dn = gi_v3_dot(ps->n, fc->n);
            if (rj->w == 0 || fabsf(dn) < 1e-6f)
                continue;
            uint32_t sd = dn > 0.0f ? i : i + l; /* the signed direction leaving the front */
            for (uint32_t yy = 0; yy < rj->h; yy++)
                for (uint32_t xx = 0; xx < rj->w; xx++) {
                    size_t slot = rj->offset + (size_t)yy * rj->w + xx;
                    if (!f->nd_cover[slot])
                        continue;
                    float U =
                        ((float)(rj->x0 + (int32_t)xx) + 0.5f) / (float)f->prm.N * 2.0f - 1.0f;
                    float V =
                        ((float)(rj->y0 + (int32_t)yy) + 0.5f) / (float)f->prm.N * 2.0f - 1.0f;
                    gi_vec3 o = gi_v3_add(gi_v3_scale(ps->u, U), gi_v3_scale(ps->v, V));
                    float tt = gi_v3_dot(fc->n, gi_v3_sub(fc->origin, o)) / dn;
                    gi_vec3 q = gi_v3_add(o, gi_v3_scale(ps->n, tt));
                    punctual_at(f, gi_v3_add(f->centre, gi_v3_scale(q, f->radius)), fc->n, E, w);
                    for (uint32_t k = 0; k < P; k++) {
                        if (E[3 * k] <= 0.0f && E[3 * k + 1] <= 0.0f && E[3 * k + 2] <= 0.0f)
                            continue;
                        /* light travelling along -w, reflected about the face */
                        gi_vec3 t = gi_v3_scale(w[k], -1.0f);
                        gi_vec3 r = gi_v3_sub(t, gi_v3_scale(fc->n, 2.0f * gi_v3_dot(t, fc->n)));
                        double norm = vlf_reflect_weights(f, fc, r, g);
                        if (norm <= 0.0 || g[sd] <= 0.0f)
                            continue;
                        for (int c = 0; c < 3; c++)
                            f->out_next[3 * slot + (size_t)c] +=
                                fc->ks[c] * E[3 * k + (uint32_t)c] * (float)(g[sd] / norm);
                    }
                }
        }
    }
    free(E), free(g), free(w);
    return GI_OK;
}
