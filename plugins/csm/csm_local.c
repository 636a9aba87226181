/* Local lights of the csm plugin: light shapes, depth cube maps at points
 * on them (§4.2, §3.3) and the nearest query (csm_local.h). */
#include "csm_local.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

/* Planar bounding rectangle of the emissive triangles of object k. */
static void fit_rectangle(const gi_scene *s, uint32_t k, float t, csm_light *l)
{
    gi_vec3 nsum = gi_v3(0, 0, 0), c = gi_v3(0, 0, 0);
    uint32_t nv = 0;
    for (uint32_t e = 0; e < s->emitter_count; e++) {
        uint32_t tri = s->emitters[e];
        if (s->vertices[s->indices[3 * tri]].object != k)
            continue;
        gi_vec3 p[3];
        gi_scene_triangle_world(s, tri, t, p);
        nsum = gi_v3_add(nsum, gi_v3_cross(gi_v3_sub(p[1], p[0]), gi_v3_sub(p[2], p[0])));
        for (int j = 0; j < 3; j++)
            c = gi_v3_add(c, p[j]);
        nv += 3;
    }
    c = gi_v3_scale(c, 1.0f / (float)(nv ? nv : 1));
    gi_vec3 n = gi_v3_length(nsum) > 0.0f ? gi_v3_normalize(nsum) : gi_v3(0, 1, 0);
    gi_vec3 t0, b0;
    gi_onb(n, &t0, &b0);
    /* The minimum-area bounding rectangle has a side along an edge of the
     * convex hull; the triangle edges include those, so try each edge's
     * direction in the plane (the first 256 triangles') and keep the
     * smallest rectangle. */
    float best = FLT_MAX, lo1 = 0, hi1 = 0, lo2 = 0, hi2 = 0;
    gi_vec3 a1 = t0, a2 = b0;
    uint32_t tried = 0;
    for (uint32_t e = 0; e < s->emitter_count && tried < 256; e++) {
        uint32_t tri = s->emitters[e];
        if (s->vertices[s->indices[3 * tri]].object != k)
            continue;
        tried++;
        gi_vec3 p[3];
        gi_scene_triangle_world(s, tri, t, p);
        for (int side = 0; side < 3; side++) {
            gi_vec3 d = gi_v3_sub(p[(side + 1) % 3], p[side]);
            d = gi_v3_sub(d, gi_v3_scale(n, gi_v3_dot(d, n)));
            if (!(gi_v3_length(d) > 0.0f))
                continue;
            gi_vec3 c1 = gi_v3_normalize(d), c2 = gi_v3_normalize(gi_v3_cross(n, c1));
            float l1 = FLT_MAX, h1 = -FLT_MAX, l2 = FLT_MAX, h2 = -FLT_MAX;
            for (uint32_t f = 0; f < s->emitter_count; f++) {
                uint32_t tf = s->emitters[f];
                if (s->vertices[s->indices[3 * tf]].object != k)
                    continue;
                gi_vec3 q[3];
                gi_scene_triangle_world(s, tf, t, q);
                for (int j = 0; j < 3; j++) {
                    gi_vec3 r = gi_v3_sub(q[j], c);
                    float x = gi_v3_dot(r, c1), y = gi_v3_dot(r, c2);
                    l1 = fminf(l1, x), h1 = fmaxf(h1, x), l2 = fminf(l2, y), h2 = fmaxf(h2, y);
                }
            }
            float area = (h1 - l1) * (h2 - l2);
            if (area < best * (1.0f - 1e-5f)) {
                best = area;
                a1 = c1, a2 = c2, lo1 = l1, hi1 = h1, lo2 = l2, hi2 = h2;
            }
        }
    }
    if (hi2 - lo2 > hi1 - lo1) { /* e1 is the longer edge */
        gi_vec3 tmp = a1;
        a1 = a2;
        a2 = gi_v3_scale(tmp, -1.0f);
        float l1 = lo1, h1 = hi1;
        lo1 = lo2, hi1 = hi2;
        lo2 = -h1, hi2 = -l1;
    }
    l->origin = gi_v3_add(c, gi_v3_add(gi_v3_scale(a1, lo1), gi_v3_scale(a2, lo2)));
    l->e1 = gi_v3_scale(a1, hi1 - lo1);
    l->e2 = gi_v3_scale(a2, hi2 - lo2);
    l->normal = n;
}

uint32_t csm_lights_collect(const gi_scene *s, float t, uint32_t n_points, float linear_aspect,
                            csm_light **out)
{
    *out = NULL;
    uint32_t n = s->light_count;
    unsigned char *emissive = calloc(s->object_count ? s->object_count : 1, 1);
    if (!emissive)
        return 0;
    for (uint32_t e = 0; e < s->emitter_count; e++) {
        uint32_t o = s->vertices[s->indices[3 * s->emitters[e]]].object;
        n += !emissive[o];
        emissive[o] = 1;
    }
    csm_light *l = n ? calloc(n, sizeof *l) : NULL;
    uint32_t count = 0;
    for (uint32_t k = 0; l && k < s->object_count; k++) {
        if (!emissive[k])
            continue;
        csm_light *x = &l[count++];
        x->object = (int)k;
        x->punctual = -1;
        fit_rectangle(s, k, t, x);
        float len1 = gi_v3_length(x->e1), len2 = gi_v3_length(x->e2);
        int linear = len1 > linear_aspect * len2;
        x->kind = linear ? CSM_LIGHT_LINEAR : CSM_LIGHT_AREA;
        x->n_u = n_points;
        x->n_v = linear ? 1u : n_points;
    }
    for (uint32_t i = 0; l && i < s->light_count; i++) {
        if (s->lights[i].type == GI_LIGHT_DIRECTIONAL)
            continue;
        csm_light *x = &l[count++];
        gi_light_frame f = gi_scene_light_at(s, i, t);
        x->kind = CSM_LIGHT_POINT;
        x->object = -1;
        x->punctual = (int)i;
        x->origin = f.position;
        x->normal = f.direction;
        x->n_u = x->n_v = 1;
    }
    free(emissive);
    if (!count) {
        free(l);
        l = NULL;
    }
    *out = l;
    return count;
}

gi_vec3 csm_light_point(gi_vec3 o, gi_vec3 e1, gi_vec3 e2, uint32_t n_u, uint32_t n_v, uint32_t a,
                        uint32_t b)
{
    float fu = ((float)a + 0.5f) / (float)n_u, fv = ((float)b + 0.5f) / (float)n_v;
    return gi_v3_add(o, gi_v3_add(gi_v3_scale(e1, fu), gi_v3_scale(e2, fv)));
}

void csm_light_grid(gi_vec3 o, gi_vec3 e1, gi_vec3 e2, uint32_t n_u, uint32_t n_v, gi_vec3 y,
                    float *u, float *v)
{
    gi_vec3 q = gi_v3_sub(y, o);
    float l1 = gi_v3_dot(e1, e1), l2 = gi_v3_dot(e2, e2);
    *u = n_u > 1 && l1 > 0.0f ? gi_v3_dot(q, e1) / l1 * (float)n_u - 0.5f : 0.0f;
    *v = n_v > 1 && l2 > 0.0f ? gi_v3_dot(q, e2) / l2 * (float)n_v - 0.5f : 0.0f;
}

/* Map q of one (light, object) pair: cube face q / NP at light point
 * q % NP of the light's enumeration order, faces concatenated as kN + i
 * (§3.3, §4.2). */
typedef struct local_views {
    const csm_local_desc *desc;
    gi_vec3 c;
    float R;
} local_views;

static void local_view(void *ctx, uint32_t q, gi_depth_view *out)
{
    const local_views *lv = ctx;
    const csm_local_desc *desc = lv->desc;
    const uint32_t NP = desc->n_u * desc->n_v;
    uint32_t face = q / NP, i = q % NP, a, b;
    gi_csm_order_cell(desc->order, desc->n_u, desc->n_v, i, &a, &b);
    gi_vec3 eye = csm_light_point(desc->o, desc->e1, desc->e2, desc->n_u, desc->n_v, a, b);
    /* everything of the object lies within |eye - c| + R */
    float dist = gi_v3_length(gi_v3_sub(eye, lv->c));
    float zfar = 1.05f * (dist + lv->R) + 1e-6f, znear = 1e-4f * (dist + lv->R);
    gi_depth_cube_view(eye, znear, zfar, (int)face, out);
}

gi_result csm_build_local(const gi_gpu_scene *gs, uint32_t object, const float sphere[4],
                          const csm_local_desc *desc, const gi_host *host, float p0, float p1,
                          gi_csm_data *out, gi_error *err)
{
    local_views lv = {desc, gi_v3(sphere[0], sphere[1], sphere[2]), sphere[3]};
    csm_encode_desc e = {.object = object,
                         .M = desc->M,
                         .count = 6 * desc->n_u * desc->n_v,
                         .metric = GI_DEPTH_RADIAL,
                         .z3 = desc->z3,
                         .sphere = sphere,
                         .shell = desc->shell,
                         .batch = desc->batch,
                         .view = local_view,
                         .ctx = &lv,
                         .what = "cube faces"};
    return csm_encode_maps(gs, &e, host, p0, p1, out, err);
}

int csm_local_visible_nearest(const gi_csm_data *data, const csm_local_desc *desc, gi_vec3 x,
                              float u, float v, float bias)
{
    int ai = (int)floorf(u + 0.5f), bi = (int)floorf(v + 0.5f);
    uint32_t a = (uint32_t)(ai < 0 ? 0 : ai >= (int)desc->n_u ? (int)desc->n_u - 1 : ai);
    uint32_t b = (uint32_t)(bi < 0 ? 0 : bi >= (int)desc->n_v ? (int)desc->n_v - 1 : bi);
    gi_vec3 l = csm_light_point(desc->o, desc->e1, desc->e2, desc->n_u, desc->n_v, a, b);
    gi_vec3 d = gi_v3_sub(x, l);
    float depth = gi_v3_length(d);
    if (!(depth > 0.0f))
        return 1;
    int face = gi_cube_face(d);
    float sx, sy;
    gi_cube_project(face, d, &sx, &sy);
    uint32_t M = data->M;
    int tx = (int)((sx * 0.5f + 0.5f) * (float)M), ty = (int)((sy * 0.5f + 0.5f) * (float)M);
    tx = tx < 0 ? 0 : tx >= (int)M ? (int)M - 1 : tx;
    ty = ty < 0 ? 0 : ty >= (int)M ? (int)M - 1 : ty;
    uint32_t i = gi_csm_order_index(desc->order, desc->n_u, desc->n_v, a, b);
    return gi_csm_visible(data, (uint32_t)ty * M + (uint32_t)tx,
                          (uint32_t)face * desc->n_u * desc->n_v + i, depth, bias);
}
