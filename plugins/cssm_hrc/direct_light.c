/* The direct light of cssm_hrc (Ritschel et al. 2008, §4.7 "Direct
 * Light": any method will do; the paper uses shadow-mapped spot lights):
 * shadow maps of the punctual lights, the environment traced by the
 * core's ray tracer, or with direct=csm the CSMs of direct_csm.c. Area
 * lights are emitting atlas texels and reach everything through the
 * gathers (lighting.c). */
#include "cssm_hrc.h"

#include "env_cssm.h"

#include "gi/algo/cubemap.h"
#include "gi/lights.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void cssm_release_shadows(cssm_hrc *c)
{
    for (uint32_t i = 0; i < c->shadow_count; i++)
        free(c->shadows[i].depth);
    free(c->shadows);
    c->shadows = NULL;
    c->shadow_count = 0;
}

/* Shadow maps of the punctual lights at the scene's time: a radial depth
 * cube at point and spot lights, an orthographic map over the scene's
 * bounding sphere for directional lights (the paper's direct light, §4.7
 * "Direct Light": any method; it uses shadow-mapped spot lights). */
static gi_result make_shadows(cssm_hrc *c, const gi_gpu_scene *gs, gi_error *err)
{
    cssm_release_shadows(c);
    const gi_scene *s = gs->scene;
    if (!s->light_count)
        return GI_OK;
    c->shadows = calloc(s->light_count, sizeof *c->shadows);
    if (!c->shadows)
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "cssm_hrc: out of memory for shadow maps");
    const uint32_t S = (uint32_t)c->shadow_size;
    const float D = c->atlas.diameter;
    gi_vec3 centre =
        gi_v3(0.5f * (gs->bounds[0] + gs->bounds[3]), 0.5f * (gs->bounds[1] + gs->bounds[4]),
              0.5f * (gs->bounds[2] + gs->bounds[5]));
    for (uint32_t i = 0; i < s->light_count; i++) {
        cssm_shadow_map *m = &c->shadows[c->shadow_count++];
        gi_light_frame f = gi_scene_light_at(s, i, gs->time);
        m->type = (int)s->lights[i].type;
        m->size = S;
        m->pos = f.position;
        m->dir = gi_v3_normalize(f.direction);
        int directional = m->type == GI_LIGHT_DIRECTIONAL;
        gi_depth_desc dd = {.size = S,
                            .surfaces = 1,
                            .metric = directional ? GI_DEPTH_EYE_Z : GI_DEPTH_RADIAL,
                            .receiver_side =
                                GI_SIDES_RECEIVERS /* shadow rays are cast from the receivers */};
        gi_depth_renderer *dr = gi_depth_renderer_create(&dd, err);
        if (!dr) {
            cssm_release_shadows(c);
            return GI_ERR_GL;
        }
        uint32_t layers = directional ? 1u : 6u;
        GLuint tex = gi_depth_texture_create(dr, layers);
        gi_depth_view views[6];
        float dist = gi_v3_length(gi_v3_sub(m->pos, centre));
        if (directional) {
            m->half = 0.5f * D * 1.02f;
            gi_vec3 eye = gi_v3_sub(centre, gi_v3_scale(m->dir, D));
            gi_vec3 up = fabsf(m->dir.y) > 0.9f ? gi_v3(1, 0, 0) : gi_v3(0, 1, 0);
            gi_mat4_look_at(views[0].view, eye, centre, up);
            gi_mat4_ortho(views[0].proj, -m->half, m->half, -m->half, m->half, 1e-3f * D, 2.0f * D);
            views[0].projection = GI_PROJ_ORTHOGRAPHIC;
            views[0].znear = 1e-3f * D;
            views[0].zfar = 2.0f * D;
            memcpy(m->view, views[0].view, sizeof m->view);
        } else {
            gi_depth_cube_views(m->pos, 1e-4f * D, dist + D, views);
        }
        gi_result r = gi_depth_render(dr, gs, views, layers, tex, 0, err);
        m->depth = r == GI_OK ? malloc((size_t)layers * S * S * sizeof *m->depth) : NULL;
        for (uint32_t l = 0; r == GI_OK && l < layers; l++) {
            float *map = m->depth ? gi_depth_read_layer(tex, S, l) : NULL;
            if (!map) {
                r = gi_error_set(err, GI_ERR_OUT_OF_MEMORY,
                                 "cssm_hrc: out of memory for shadow maps");
                break;
            }
            for (size_t t = 0; t < (size_t)S * S; t++)
                m->depth[(size_t)l * S * S + t] = map[4 * t];
            free(map);
        }
        glDeleteTextures(1, &tex);
        gi_depth_renderer_free(dr);
        if (r != GI_OK) {
            cssm_release_shadows(c); /* no light left with a half-made map */
            return r;
        }
    }
    return GI_OK;
}

gi_result cssm_make_direct(cssm_hrc *c, const gi_gpu_scene *gs, gi_error *err)
{
    if (!c->direct)
        return make_shadows(c, gs, err);
    const gi_host *host = c->kit.host;
    cssm_csm_direct_free(c->csm);
    if (!c->csm && !(c->csm = calloc(1, sizeof *c->csm)))
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY,
                            "cssm_hrc: out of memory for the direct light's CSMs");
    host->stage_begin(host, "csm_precompute");
    gi_result r = cssm_csm_direct_build(gs, c->atlas.diameter, (uint32_t)c->csm_points,
                                        (uint32_t)c->csm_M, host, c->csm, err);
    host->stage_end(host, "csm_precompute");
    if (r != GI_OK) {
        free(c->csm);
        c->csm = NULL;
        return r;
    }
    host->stat(host, "csm_bytes", (double)cssm_csm_direct_bytes(c->csm));
    host->stat(host, "csm_points", (double)c->csm->area_points);
    host->stat(host, "csm_maps", (double)c->csm->pts.count);
    host->stat(host, "csm_distant_objects", (double)(c->csm->distant ? c->csm->object_count : 0));
    return GI_OK;
}

void cssm_punctual(const cssm_hrc *c, const gi_scene *s, uint32_t i, gi_vec3 x, gi_vec3 n,
                   float e[3])
{
    const cssm_shadow_map *m = &c->shadows[i];
    const gi_light *l = &s->lights[i];
    e[0] = e[1] = e[2] = 0.0f;
    const uint32_t S = m->size;
    const float D = c->atlas.diameter;
    float k;
    if (m->type == GI_LIGHT_DIRECTIONAL) {
        gi_vec3 w = gi_v3_scale(m->dir, -1.0f);
        float cs = gi_v3_dot(n, w);
        if (cs <= 0.0f)
            return;
        gi_vec3 q = gi_mat4_point(m->view, x);
        int tx = (int)((q.x / m->half * 0.5f + 0.5f) * (float)S),
            ty = (int)((q.y / m->half * 0.5f + 0.5f) * (float)S);
        if (tx >= 0 && ty >= 0 && tx < (int)S && ty < (int)S) {
            float z = m->depth[(size_t)ty * S + (size_t)tx];
            float slope = 2.0f * m->half / (float)S * 1.5f;
            if (-q.z > z + c->bias_f * D + slope)
                return;
        }
        k = cs;
    } else {
        gi_vec3 d = gi_v3_sub(x, m->pos);
        float dist = gi_v3_length(d);
        if (!(dist > 0.0f))
            return;
        gi_vec3 w = gi_v3_scale(d, -1.0f / dist);
        float cs = gi_v3_dot(n, w);
        if (cs <= 0.0f)
            return;
        k = cs / (dist * dist) * gi_range_window(dist, l->range);
        if (m->type == GI_LIGHT_SPOT)
            k *= gi_spot_falloff(gi_v3_dot(m->dir, gi_v3_scale(w, -1.0f)), cosf(l->inner_cone),
                                 cosf(l->outer_cone));
        if (k <= 0.0f)
            return;
        int face = gi_cube_face(d);
        float sx, sy;
        gi_cube_project(face, d, &sx, &sy);
        int tx = (int)((sx * 0.5f + 0.5f) * (float)S), ty = (int)((sy * 0.5f + 0.5f) * (float)S);
        tx = tx < 0 ? 0 : tx >= (int)S ? (int)S - 1 : tx;
        ty = ty < 0 ? 0 : ty >= (int)S ? (int)S - 1 : ty;
        float z = m->depth[(size_t)face * S * S + (size_t)ty * S + (size_t)tx];
        float slope = dist * 2.0f / (float)S * 2.0f;
        if (dist > z + c->bias_f * D + slope)
            return;
    }
    for (int j = 0; j < 3; j++)
        e[j] = l->intensity[j] * k;
}

/* The environment's visibility along w from x (cssm_env_irradiance). */
typedef struct env_ray {
    const gi_rt *rt;
    gi_vec3 x;
} env_ray;

static float env_traced(const void *ctx, gi_vec3 w)
{
    const env_ray *r = ctx;
    return gi_rt_occluded(r->rt, r->x, w, 0.0f, INFINITY) ? 0.0f : 1.0f;
}

void cssm_env_irradiance(const gi_envmap *env, const gi_rt *rt, gi_vec3 x, gi_vec3 n, uint32_t K,
                         uint32_t seed, const cssm_receiver *brdf, float e[3])
{
    env_ray r = {rt, x};
    cssm_env_estimate(env, n, K, seed, brdf, env_traced, &r, e);
}
