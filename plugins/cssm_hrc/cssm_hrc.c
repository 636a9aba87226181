/* The `cssm_hrc` method: Coherent Surface Shadow Maps with hierarchical
 * radiosity and lightcuts-style final gathering (Ritschel, Grosch, Kautz,
 * Seidel, GI 2008).
 *
 * prepare(): the illumination atlas (§3.2.3), a depth cube map per texel in
 * a coherent traversal order compressed by the core's CSM codec (§3.2),
 * the median-cut hierarchy with skip pointers (§4.2), shadow maps of the
 * punctual lights, then the lighting of the atlas (lighting()):
 *   direct:  R1 = kd/pi gather(emission) + punctual lights (shadow maps)
 *            + the environment (§4.7: ray-traced, env_irradiance(), or
 *              with env=cssm by the texels' own cube maps, env_cssm.c);
 *   bounce:  R_k = kd/pi gather(pull(R_{k-1})), k = 2 .. n (§4.1.1);
 *   pull:    the tree of L = emission + sum R_k.
 * With direct=csm (§4.7's alternative, direct_csm.c) R1 is the direct light
 * of every light by Coherent Shadow Maps and Monte Carlo instead, the
 * emitting texels not gathered, and pixels get that direct light too.
 * render(): G-buffer; per pixel the same traversal with a Phong bound
 * (§4.4), VPLs jittered inside their area and averaged over frames (§4.5),
 * distances clamped; plus emission, the punctual lights and the
 * environment per pixel.
 * Pixels thus get light paths of 0 .. n + 1 bounces.
 * The traversal, the CSSM look-ups and the shading run on the CPU (the GL
 * is llvmpipe here); the depth cube maps, shadow maps and G-buffer are
 * drawn by the core's GL passes. */
#include "cssm.h"
#include "env_cssm.h"
#include "direct_csm.h"
#include "motion.h"

#include "gi/cache.h"
#include "gi/algo/cubemap.h"
#include "gi/envmap.h"
#include "gi/kit.h"
#include "gi/lights.h"
#include "gi/log.h"
#include "gi/raytrace.h"
#include "gi/rng.h"
#include "gi/sampling.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct shadow_map {
    int type; /* GI_LIGHT_* */
    uint32_t size;
    gi_vec3 pos, dir; /* light frame */
    float view[16];   /* directional: world -> eye */
    float half;       /* directional: half extent of the orthographic map */
    float *depth;     /* 6 faces (point, spot) or 1 map, size^2 floats each */
} shadow_map;

typedef struct cssm_hrc {
    gi_kit kit;
    int R, M, traversal, bounces, max_cut, jitter, pcf, shadow_size;
    float threshold, clamp_f, bias_f;
    cssm_atlas atlas;
    uint32_t *order;
    cssm_maps maps;
    cssm_tree tree;
    float *texel_L; /* emission + reflected, 3 per texel */
    float *node_L;  /* pulled texel_L */
    float *node_Le; /* pulled emission (texel mode: direct light per pixel) */
    float *node_B;  /* pulled reflected light (texel mode: indirect) */
    float *texel_T; /* texel mode: view-dependent indirect light per texel, 3 per texel */
    uint32_t *ids;  /* G-buffer ids read-back (texel mode) */
    int mode;
    int indirect, mc_samples;  /* §4.6 alternative: Monte Carlo from the atlas as a pdf */
    float *texel_Le, *texel_B; /* emission and reflected light per texel */
    double *cdf[3];            /* pdf tables of texel_L, texel_Le, texel_B */
    shadow_map *shadows;
    uint32_t shadow_count;
    int env_samples; /* environment light: directions per texel (or pixel) */
    int env_pixel;  /* 1: environment light traced per pixel; 0: the texels' irradiance looked up */
    int env_mode;   /* environment visibility: 0 ray tracer, 1 the texels' own CSSMs (env_cssm.c) */
    gi_rt *rt;      /* the scene for the environment's occlusion, NULL without environment */
    float *texel_E; /* environment irradiance per texel, 3 per texel; NULL: no environment */
    float *accum;   /* running average, 4 per pixel */
    float *gb[5];   /* G-buffer read-back: position, normal, albedo, phong, emission */
    uint32_t acc_w, acc_h;
    cssm_motion motion; /* §3.3: moving rigid objects (motion.h); motion.moving < 0: static scene */
    int nodes; /* 1: nodes=compact, the gathers read packed 128-bit nodes (§4.2.1, compact.c) */
    cssm_ctree ct[3]; /* nodes=compact: the packed hierarchy with the intensity of texel_L,
                         emission, reflected */
    int direct, csm_points, csm_samples, csm_M; /* §4.7 "Direct Light": direct=csm (direct_csm.h) */
    cssm_csm_direct *csm;                       /* its CSMs, NULL with direct=maps */
    int prepared;
} cssm_hrc;

static const gi_param_desc cssm_params[] = {
    {"atlas", GI_PARAM_INT, 32, 8, 128, NULL, "atlas resolution (Sec. 3.2.3, Table 2)",
     "the illumination atlas is atlas x atlas texels; each texel is a surface sample, a cube map "
     "and a leaf"},
    {"M", GI_PARAM_INT, 16, 4, 64, NULL, "6 x M x M (Sec. 3.2.1, Table 2)",
     "cube face size of the CSSM depth cube maps"},
    {"traversal", GI_PARAM_ENUM, 2, 0, 0, "greedy|zigzag|spiral|greedy_atlas",
     "Sec. 3.2.3, Fig. 6/7",
     "order of the cube maps in the codec: greedy (the paper's: evenly distributed surface samples "
     "instead of the "
     "atlas, walked nearest-first), zig-zag or spiral over the charts, greedy_atlas (nearest-first "
     "over the atlas "
     "texels)"},
    {"bounces", GI_PARAM_INT, 3, 0, 3, NULL, "n (Sec. 4.1)",
     "diffuse indirect bounces n: the atlas holds 1 .. n bounces, the final gather adds one"},
    {"threshold", GI_PARAM_FLOAT, 0.1, 0.0, 1.0, NULL, "threshold (Sec. 4.3)",
     "refine a sender while the tone-mapped upper bound of its radiance exceeds this"},
    {"max_cut", GI_PARAM_INT, 1024, 1, 65536, NULL, "maximum cut size (Sec. 4.4)",
     "nodes in one receiver's cut at most"},
    {"jitter", GI_PARAM_BOOL, 1, 0, 1, NULL, "jittering (Sec. 4.5)",
     "final gather: each node's position drawn inside its area every frame, averaged "
     "progressively"},
    {"clamp", GI_PARAM_FLOAT, 0.02, 0.0, 1.0, NULL, "clamping (Sec. 5 Quality)",
     "distances below clamp x scene diameter count as that distance"},
    {"bias", GI_PARAM_FLOAT, 0.004, 0.0, 0.1, NULL, "depth bias (Fig. 14)",
     "CSSM depth bias as a fraction of the scene diameter"},
    {"pcf", GI_PARAM_BOOL, 0, 0, 1, NULL, "PCF (Sec. 3.2.2)",
     "CSSM look-ups filtered over 2 x 2 texels"},
    {"mode", GI_PARAM_ENUM, 0, 0, 0, "pixels|texels", "samples (Table 1, Fig. 17)",
     "pixels: final gather per pixel; texels: view-dependent lightmap, the final (glossy) gather "
     "of the indirect light "
     "per atlas texel with a bicubic look-up, emission and direct light per pixel"},
    {"indirect", GI_PARAM_ENUM, 0, 0, 0, "hrc|mc", "Sec. 4.6 Indirect Light",
     "hrc: the cuts through the hierarchy; mc: the alternative of Sec. 4.6, mc_samples atlas "
     "texels per receiver "
     "and frame drawn with probability proportional to their radiance x area (instant radiosity "
     "with the atlas as "
     "a pdf), CSSM visibility, averaged over frames"},
    {"mc_samples", GI_PARAM_INT, 16, 1, 4096, NULL, NULL,
     "texels drawn per receiver and frame with indirect=mc"},
    {"env_samples", GI_PARAM_INT, 128, 1, 4096, NULL, "direct light (Sec. 4.7)",
     "environment light: directions per atlas texel (half from the map's importance sampler, half "
     "cosine, "
     "multiple importance sampling), occlusion by the core's ray tracer"},
    {"env_pixel", GI_PARAM_BOOL, 1, 0, 1, NULL, NULL,
     "environment light per pixel: 1 traced at the pixel (env_samples per pixel and frame, "
     "averaged over frames), "
     "0 the atlas texels' irradiance by the bicubic look-up (surface samples: the nearest texel)"},
    {"nodes", GI_PARAM_ENUM, 0, 0, 0, "float|compact", "node encoding (Sec. 4.2.1)",
     "float: hierarchy nodes of floats; compact: the paper's 128 bits a node (24-bit centre, "
     "normal and intensity, "
     "8-bit radius, cone and area, 16-bit pointers), decoded as the traversal reads them and "
     "re-encoded at each "
     "pull; at most 65535 nodes (32768 texels)"},
    {"env", GI_PARAM_ENUM, 0, 0, 0, "trace|cssm", "direct light (Sec. 4.7)",
     "environment visibility: trace the core's ray tracer; cssm the escape test in the texels' own "
     "cube maps "
     "(built with the far plane as the mark of 'no surface'; per pixel the maps of the texels "
     "around it); not "
     "with moving objects"},
    {"direct", GI_PARAM_ENUM, 0, 0, 0, "maps|csm", "Sec. 4.7 Direct Light",
     "maps: area lights are emitting atlas texels gathered by the first bounce, punctual lights "
     "shadow-mapped, the "
     "environment ray-traced; csm: the Monte-Carlo direct light of the original CSM (area lights: "
     "csm_points points "
     "on the emitters with a compressed depth cube map each; point/spot lights: a cube map each; "
     "directional and "
     "environment: each object's distant CSM), the HRC bounces gathering the reflected light only"},
    {"csm_points", GI_PARAM_INT, 64, 1, 256, NULL, "N (CSM Sec. 4.2)",
     "direct=csm: points on the area lights (by power), a depth cube map each"},
    {"csm_samples", GI_PARAM_INT, 16, 1, 1024, NULL, "S (CSM Sec. 5.1)",
     "direct=csm: area-light samples per pixel and frame, each shadowed by the nearest point's "
     "cube map"},
    {"csm_M", GI_PARAM_INT, 64, 8, 256, NULL, "M (CSM Sec. 3.3)",
     "direct=csm: cube face size of the lights' maps"},
    {"shadow_size", GI_PARAM_INT, 256, 16, 2048, NULL, NULL,
     "face size of the point/spot lights' shadow cube maps and of directional lights' shadow maps"},
    {0},
};

static gi_result cssm_create(const gi_host *host, const gi_params *params, void **out)
{
    cssm_hrc *c = calloc(1, sizeof *c);
    if (!c)
        return GI_ERR_OUT_OF_MEMORY;
    if (gi_kit_init(&c->kit, host, NULL) != GI_OK) {
        free(c);
        return GI_ERR_INVALID_ARGUMENT;
    }
    c->R = gi_params_int(params, "atlas");
    c->M = gi_params_int(params, "M");
    c->traversal = gi_params_enum(params, "traversal");
    c->bounces = gi_params_int(params, "bounces");
    c->threshold = gi_params_float(params, "threshold");
    c->max_cut = gi_params_int(params, "max_cut");
    c->jitter = gi_params_bool(params, "jitter");
    c->clamp_f = gi_params_float(params, "clamp");
    c->bias_f = gi_params_float(params, "bias");
    c->env_samples = gi_params_int(params, "env_samples");
    c->env_pixel = gi_params_bool(params, "env_pixel");
    c->env_mode = gi_params_enum(params, "env");
    c->pcf = gi_params_bool(params, "pcf");
    c->shadow_size = gi_params_int(params, "shadow_size");
    c->mode = gi_params_enum(params, "mode");
    c->indirect = gi_params_enum(params, "indirect");
    c->mc_samples = gi_params_int(params, "mc_samples");
    c->nodes = gi_params_enum(params, "nodes");
    c->direct = gi_params_enum(params, "direct");
    c->csm_points = gi_params_int(params, "csm_points");
    c->csm_samples = gi_params_int(params, "csm_samples");
    c->csm_M = gi_params_int(params, "csm_M");
    c->motion.moving = -1;
    *out = c;
    return GI_OK;
}

static void release_shadows(cssm_hrc *c)
{
    for (uint32_t i = 0; i < c->shadow_count; i++)
        free(c->shadows[i].depth);
    free(c->shadows);
    c->shadows = NULL;
    c->shadow_count = 0;
}

static void release_prepared(cssm_hrc *c)
{
    cssm_atlas_free(&c->atlas);
    cssm_maps_free(&c->maps);
    cssm_tree_free(&c->tree);
    for (int i = 0; i < 3; i++)
        cssm_ctree_free(&c->ct[i]);
    free(c->order);
    free(c->texel_L);
    free(c->node_L);
    free(c->node_Le);
    free(c->node_B);
    free(c->texel_T);
    c->order = NULL;
    c->texel_L = c->node_L = c->node_Le = c->node_B = c->texel_T = NULL;
    free(c->texel_Le);
    free(c->texel_B);
    free(c->texel_E);
    c->texel_Le = c->texel_B = c->texel_E = NULL;
    gi_rt_free(c->rt);
    c->rt = NULL;
    for (int i = 0; i < 3; i++) {
        free(c->cdf[i]);
        c->cdf[i] = NULL;
    }
    release_shadows(c);
    cssm_csm_direct_free(c->csm);
    free(c->csm);
    c->csm = NULL;
    cssm_motion_free(&c->motion);
    c->prepared = 0;
}

/* Shadow maps of the punctual lights at the scene's time: a radial depth
 * cube at point and spot lights, an orthographic map over the scene's
 * bounding sphere for directional lights (the paper's direct light, §4.7
 * "Direct Light": any method; it uses shadow-mapped spot lights). */
static gi_result make_shadows(cssm_hrc *c, const gi_gpu_scene *gs, gi_error *err)
{
    release_shadows(c);
    const gi_scene *s = gs->scene;
    if (!s->light_count)
        return GI_OK;
    c->shadows = calloc(s->light_count, sizeof *c->shadows);
    if (!c->shadows) {
        snprintf(err->text, sizeof err->text, "cssm_hrc: out of memory for shadow maps");
        return GI_ERR_OUT_OF_MEMORY;
    }
    const uint32_t S = (uint32_t)c->shadow_size;
    const float D = c->atlas.diameter;
    gi_vec3 centre =
        gi_v3(0.5f * (gs->bounds[0] + gs->bounds[3]), 0.5f * (gs->bounds[1] + gs->bounds[4]),
              0.5f * (gs->bounds[2] + gs->bounds[5]));
    for (uint32_t i = 0; i < s->light_count; i++) {
        shadow_map *m = &c->shadows[c->shadow_count++];
        gi_light_frame f = gi_scene_light_at(s, i, gs->time);
        m->type = (int)s->lights[i].type;
        m->size = S;
        m->pos = f.position;
        m->dir = gi_v3_normalize(f.direction);
        int directional = m->type == GI_LIGHT_DIRECTIONAL;
        gi_depth_desc dd = {
            .size = S, .surfaces = 1, .metric = directional ? GI_DEPTH_EYE_Z : GI_DEPTH_RADIAL};
        gi_depth_renderer *dr = gi_depth_renderer_create(&dd, err);
        if (!dr) {
            release_shadows(c);
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
                r = GI_ERR_OUT_OF_MEMORY;
                snprintf(err->text, sizeof err->text, "cssm_hrc: out of memory for shadow maps");
                break;
            }
            for (size_t t = 0; t < (size_t)S * S; t++)
                m->depth[(size_t)l * S * S + t] = map[4 * t];
            free(map);
        }
        glDeleteTextures(1, &tex);
        gi_depth_renderer_free(dr);
        if (r != GI_OK) {
            release_shadows(c); /* no light left with a half-made map */
            return r;
        }
    }
    return GI_OK;
}

/* The direct light's maps: the punctual lights' shadow maps (direct=maps),
 * or the CSMs of direct=csm (§4.7, direct_csm.h), made again when the
 * lights or materials change. Stage timer csm_precompute; stats
 * csm_bytes, csm_points, csm_maps. */
static gi_result make_direct(cssm_hrc *c, const gi_gpu_scene *gs, gi_error *err)
{
    if (!c->direct)
        return make_shadows(c, gs, err);
    const gi_host *host = c->kit.host;
    cssm_csm_direct_free(c->csm);
    if (!c->csm && !(c->csm = calloc(1, sizeof *c->csm))) {
        snprintf(err->text, sizeof err->text,
                 "cssm_hrc: out of memory for the direct light's CSMs");
        return GI_ERR_OUT_OF_MEMORY;
    }
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

/* Irradiance-like factor of punctual light i at point x with normal n
 * (E / colour: intensity x cos / d^2 x spot x range, or E cos), shadowed by
 * its shadow map. Returns the light's irradiance in e[3]. */
static void punctual(const cssm_hrc *c, const gi_scene *s, uint32_t i, gi_vec3 x, gi_vec3 n,
                     float e[3])
{
    const shadow_map *m = &c->shadows[i];
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

/* Environment irradiance at x with normal n (any direct-light method will
 * do, §4.7 "Direct Light"): the estimator of env_cssm.c, each direction
 * counted when the core's ray tracer finds nothing along it. */
typedef struct env_ray {
    const gi_rt *rt;
    gi_vec3 x;
} env_ray;

static float env_traced(const void *ctx, gi_vec3 w)
{
    const env_ray *r = ctx;
    return gi_rt_occluded(r->rt, r->x, w, 0.0f, INFINITY) ? 0.0f : 1.0f;
}

static void env_irradiance(const gi_envmap *env, const gi_rt *rt, gi_vec3 x, gi_vec3 n, uint32_t K,
                           uint32_t seed, const cssm_receiver *brdf, float e[3])
{
    env_ray r = {rt, x};
    cssm_env_estimate(env, n, K, seed, brdf, env_traced, &r, e);
}

static cssm_gather_opts gather_opts(const cssm_hrc *c, float exposure, uint32_t *rng)
{
    cssm_gather_opts o = {.threshold = c->threshold,
                          .max_cut = (uint32_t)c->max_cut,
                          .exposure = exposure,
                          .clamp = c->clamp_f * c->atlas.diameter,
                          .bias = c->bias_f * c->atlas.diameter,
                          .pcf = c->pcf,
                          .rng = rng};
    return o;
}

static gi_vec3 offset(const cssm_hrc *c, gi_vec3 p, gi_vec3 n)
{
    return cssm_receiver_point(&c->maps, &c->atlas, p, n);
}

/* nodes=compact: the packed hierarchy (§4.2.1), one per light set, after
 * the float one was built; stats of the node memory either way. */
static gi_result make_compact(cssm_hrc *c, gi_error *err)
{
    const gi_host *host = c->kit.host;
    for (int i = 0; i < 3; i++)
        cssm_ctree_free(&c->ct[i]);
    host->stat(host, "node_count", (double)c->tree.count);
    if (!c->nodes) { /* a float node and its pulled radiance */
        host->stat(host, "node_bytes",
                   (double)c->tree.count * (double)(sizeof(cssm_node) + 3 * sizeof(float)));
        return GI_OK;
    }
    for (int i = 0; i < 3; i++) {
        gi_result r = cssm_ctree_build(&c->tree, &c->atlas, &c->ct[i], err);
        if (r != GI_OK)
            return r;
    }
    host->stat(host, "node_bytes", (double)c->tree.count * (double)sizeof(cssm_pnode));
    host->stat(host, "node_side_bytes", (double)c->tree.count * 2.0 * sizeof(uint32_t));
    return GI_OK;
}

/* The atlas' lighting (§4.1, Fig. 8) with the punctual lights' direct
 * light per texel added to the first bounce. */
static gi_result lighting(cssm_hrc *c, const gi_gpu_scene *gs)
{
    const gi_host *host = c->kit.host;
    const cssm_atlas *a = &c->atlas;
    const uint32_t N = a->count, NN = c->tree.count;
    float *D = calloc(3 * (size_t)N, sizeof *D);
    free(c->texel_L);
    free(c->node_L);
    c->texel_L = calloc(3 * (size_t)N, sizeof *c->texel_L);
    c->node_L = calloc(3 * (size_t)NN, sizeof *c->node_L);
    if (!D || !c->texel_L || !c->node_L) {
        free(D);
        return gi_kit_fail(&c->kit, GI_ERR_OUT_OF_MEMORY,
                           "cssm_hrc: out of memory for the lighting");
    }
    host->stage_begin(host, "direct");
    free(c->texel_E);
    c->texel_E = NULL;
    const gi_envmap *env = gs->scene->has_environment && !c->csm ? gs->scene->envmap : NULL;
    if (env && c->maps.escape) { /* env=cssm: the texels' own cube maps (env_cssm.c) */
        c->texel_E = calloc(3 * (size_t)N, sizeof *c->texel_E);
        if (!c->texel_E) {
            free(D);
            host->stage_end(host, "direct");
            return gi_kit_fail(&c->kit, GI_ERR_OUT_OF_MEMORY,
                               "cssm_hrc: out of memory for the lighting");
        }
        cssm_env_texels(env, a, &c->maps, (uint32_t)c->env_samples, c->pcf, c->texel_E);
        for (uint32_t i = 0; i < N; i++)
            for (int k = 0; k < 3; k++)
                D[3 * i + k] += a->texels[i].albedo[k] / GI_PI * c->texel_E[3 * i + k];
    } else if (env) {
        gi_rt *rt = NULL;
        gi_error rerr;
        gi_rt_free(c->rt);
        c->rt = NULL;
        c->texel_E = calloc(3 * (size_t)N, sizeof *c->texel_E);
        gi_result rr =
            c->texel_E ? gi_rt_create(gs->scene, gs->time, &rt, &rerr) : GI_ERR_OUT_OF_MEMORY;
        if (rr != GI_OK) {
            free(D);
            host->stage_end(host, "direct");
            return c->texel_E ? gi_kit_fail_with(&c->kit, rr, &rerr)
                              : gi_kit_fail(&c->kit, GI_ERR_OUT_OF_MEMORY,
                                            "cssm_hrc: out of memory for the lighting");
        }
        for (uint32_t i = 0; i < N; i++) {
            const cssm_texel *x = &a->texels[i];
            float *e = &c->texel_E[3 * i];
            env_irradiance(env, rt, offset(c, x->p, x->n), x->n, (uint32_t)c->env_samples, i, NULL,
                           e);
            for (int k = 0; k < 3; k++)
                D[3 * i + k] += x->albedo[k] / GI_PI * e[k];
        }
        c->rt = rt; /* kept for the per-pixel environment light */
    }
    for (uint32_t i = 0; i < N && c->shadow_count; i++) {
        const cssm_texel *x = &a->texels[i];
        for (uint32_t l = 0; l < c->shadow_count; l++) {
            float e[3];
            punctual(c, gs->scene, l, offset(c, x->p, x->n), x->n, e);
            for (int k = 0; k < 3; k++)
                D[3 * i + k] += x->albedo[k] / GI_PI * e[k];
        }
    }
    if (c->csm) /* §4.7: every light's direct light by the CSMs, the fixed estimate over the light
                   points */
        for (uint32_t i = 0; i < N; i++) {
            const cssm_texel *x = &a->texels[i];
            cssm_receiver rc = {.x = offset(c, x->p, x->n), .n = x->n, .self = (int32_t)i};
            memcpy(rc.kd, x->albedo, sizeof rc.kd);
            cssm_csm_direct_eval(c->csm, gs->scene, &rc, 0, (uint32_t)c->env_samples, i,
                                 c->bias_f * a->diameter, c->pcf, &D[3 * i]);
        }
    host->stage_end(host, "direct");
    cssm_gather_opts o = gather_opts(c, 0.0f, NULL);
    o.no_emission = c->csm != NULL; /* R1 = the CSMs' direct light alone */
    cssm_gather_stats st = {0};
    gi_error err;
    const float *direct = c->shadow_count || env || c->csm ? D : NULL;
    gi_result r =
        cssm_solve_ex(&c->tree, c->nodes ? &c->ct[0] : NULL, a, &c->maps, &o, (uint32_t)c->bounces,
                      direct, host, c->texel_L, c->node_L, &st, &err);
    free(D);
    if (r != GI_OK)
        return gi_kit_fail_with(&c->kit, r, &err);
    free(c->node_Le);
    free(c->node_B);
    free(c->texel_T);
    c->node_Le = calloc(3 * (size_t)NN, sizeof *c->node_Le);
    c->node_B = calloc(3 * (size_t)NN, sizeof *c->node_B);
    c->texel_T = calloc(3 * (size_t)N, sizeof *c->texel_T);
    float *tmp = calloc(3 * (size_t)N, sizeof *tmp);
    if (!c->node_Le || !c->node_B || !c->texel_T || !tmp) {
        free(tmp);
        return gi_kit_fail(&c->kit, GI_ERR_OUT_OF_MEMORY,
                           "cssm_hrc: out of memory for the lighting");
    }
    for (uint32_t i = 0; i < N; i++)
        memcpy(&tmp[3 * i], a->texels[i].emission, 3 * sizeof(float));
    cssm_tree_pull(&c->tree, a, tmp, c->node_Le);
    if (c->nodes)
        cssm_ctree_pull(&c->ct[1], a, tmp);
    for (size_t k = 0; k < 3 * (size_t)N; k++)
        tmp[k] = c->texel_L[k] - tmp[k];
    cssm_tree_pull(&c->tree, a, tmp, c->node_B);
    if (c->nodes)
        cssm_ctree_pull(&c->ct[2], a, tmp);
    /* per-texel values and pdf tables for indirect=mc */
    free(c->texel_Le);
    free(c->texel_B);
    c->texel_B = tmp;
    c->texel_Le = calloc(3 * (size_t)N, sizeof *c->texel_Le);
    for (int i = 0; i < 3; i++) {
        free(c->cdf[i]);
        c->cdf[i] = malloc(((size_t)N + 1) * sizeof *c->cdf[i]);
    }
    if (!c->texel_Le || !c->cdf[0] || !c->cdf[1] || !c->cdf[2])
        return gi_kit_fail(&c->kit, GI_ERR_OUT_OF_MEMORY,
                           "cssm_hrc: out of memory for the lighting");
    for (uint32_t i = 0; i < N; i++)
        memcpy(&c->texel_Le[3 * i], a->texels[i].emission, 3 * sizeof(float));
    cssm_pdf_build(a, c->texel_L, c->cdf[0]);
    cssm_pdf_build(a, c->texel_Le, c->cdf[1]);
    cssm_pdf_build(a, c->texel_B, c->cdf[2]);
    if (st.receivers)
        host->stat(host, "cut_size_atlas", (double)st.nodes / (double)st.receivers);
    return GI_OK;
}

#define CSSM_FORMAT_VERSION 2u
static const char cache_magic[8] = {'G', 'I', 'C', 'S', 'S', 'M', '\r', '\n'};

/* Cache name: the meshes, their placement at prepare time and every
 * parameter that changes the maps. */
static void cache_name(const cssm_hrc *c, const gi_gpu_scene *gs, char *name, size_t size)
{
    const gi_scene *s = gs->scene;
    uint32_t key[5] = {CSSM_FORMAT_VERSION, (uint32_t)c->R, (uint32_t)c->M, (uint32_t)c->traversal,
                       c->atlas.count};
    uint64_t h = gi_hash64("gibench-cssm", 12, 0);
    h = gi_hash64(key, sizeof key, h);
    if (c->maps.escape) /* env=cssm: escape intervals (env_cssm.h) */
        h = gi_hash64("escape", 6, h);
    for (uint32_t k = 0; k < s->object_count; k++) {
        uint64_t oh = gi_scene_object_hash(s, k);
        float m[16];
        gi_scene_object_transform(s, k, gs->time, m);
        h = gi_hash64(&oh, sizeof oh, h);
        h = gi_hash64(m, sizeof m, h);
    }
    snprintf(name, size, "cssm_hrc-%016llx.bin", (unsigned long long)h);
}

/* The six compressed faces of a cache file; 1 on a hit. */
static int cache_load(cssm_hrc *c, const char *path)
{
    size_t size = 0;
    unsigned char *bytes = gi_file_read_all(path, &size);
    if (!bytes)
        return 0;
    int ok = size >= 16 && !memcmp(bytes, cache_magic, 8);
    size_t at = 16;
    uint64_t dont_care = 0;
    if (ok)
        memcpy(&dont_care, bytes + 8, 8);
    for (int f = 0; f < 6 && ok; f++) {
        uint64_t n = 0;
        gi_error err;
        ok = at + 8 <= size;
        if (ok)
            memcpy(&n, bytes + at, 8);
        ok = ok && n <= size - at - 8 &&
             gi_csm_data_read(bytes + at + 8, (size_t)n, &c->maps.face[f], &err) == GI_OK &&
             c->maps.face[f].M == (uint32_t)c->M && c->maps.face[f].N == c->atlas.count;
        at += 8 + (size_t)n;
    }
    free(bytes);
    if (!ok) {
        c->kit.host->log(c->kit.host, GI_LOG_WARN, "%s: unusable cache file; recomputing", path);
        for (int f = 0; f < 6; f++)
            gi_csm_data_free(&c->maps.face[f]);
        return 0;
    }
    c->maps.dont_care = dont_care;
    return 1;
}

static void cache_store(cssm_hrc *c, const char *path)
{
    void *part[6] = {0};
    size_t sz[6] = {0}, total = 16;
    gi_error err = {{0}};
    int ok = 1;
    for (int f = 0; f < 6 && ok; f++) {
        ok = gi_csm_data_write(&c->maps.face[f], &part[f], &sz[f], &err) == GI_OK;
        total += 8 + sz[f];
    }
    unsigned char *buf = ok ? malloc(total) : NULL;
    if (buf) {
        memcpy(buf, cache_magic, 8);
        memcpy(buf + 8, &c->maps.dont_care, 8);
        size_t at = 16;
        for (int f = 0; f < 6; f++) {
            uint64_t n = sz[f];
            memcpy(buf + at, &n, 8);
            memcpy(buf + at + 8, part[f], sz[f]);
            at += 8 + sz[f];
        }
        if (gi_file_write_atomic(path, buf, total, &err) != GI_OK)
            ok = 0;
    }
    if (!ok || !buf)
        c->kit.host->log(c->kit.host, GI_LOG_WARN, "cssm_hrc: not cached: %s",
                         err.text[0] ? err.text : "no memory");
    free(buf);
    for (int f = 0; f < 6; f++)
        free(part[f]);
}

static gi_result load_or_build_maps(cssm_hrc *c, const gi_gpu_scene *gs, gi_error *err)
{
    const gi_host *host = c->kit.host;
    char name[64], *path = NULL;
    /* env=cssm with direct=maps: with direct=csm the environment goes through the distant CSMs */
    const int escape = c->env_mode == 1 && gs->scene->has_environment && !c->direct;
    c->maps.escape = escape;
    cache_name(c, gs, name, sizeof name);
    path = host->cache_dir ? gi_cache_path(host->cache_dir, name) : NULL;
    gi_result r = cssm_maps_setup(&c->atlas, c->order, (uint32_t)c->M, &c->maps, err);
    if (r != GI_OK) {
        free(path);
        return r;
    }
    c->maps.escape = escape;
    if (path && cache_load(c, path)) {
        host->stat(host, "cache_hit", 1.0);
        free(path);
        return GI_OK;
    }
    cssm_maps_free(&c->maps);
    cssm_build_opts bo = {.escape = escape};
    r = cssm_maps_build_ex(gs, &c->atlas, c->order, (uint32_t)c->M, &bo, host, &c->maps, err);
    if (r == GI_OK && path)
        cache_store(c, path);
    host->stat(host, "cache_hit", 0.0);
    free(path);
    return r;
}

/* Reports the hull check of §3.3 at time t: stats hull_overlap and
 * hull_intrusion, and a warning when the look-ups are not valid. */
static void check_hulls(cssm_hrc *c, const gi_scene *s, float t)
{
    const gi_host *host = c->kit.host;
    host->stage_begin(host, "hull");
    uint32_t bad = cssm_motion_check(&c->motion, s, t);
    host->stage_end(host, "hull");
    if (bad)
        host->log(
            host, GI_LOG_WARN,
            "t = %.3f s: %s; the visibility through the moving object is wrong there (Sec. 3.3)", t,
            c->motion.what);
}

/* §3.3 with moving objects: the static CSSM (the scene without the
 * movers, their texels "don't care"), each mover's own CSSM and CSM in its
 * frame, with two or more movers the static objects' CSMs (motion.c). Not
 * cached. */
/* Compressed sizes of the §3.3 maps of moving objects: their own CSSMs,
 * their CSMs, and (several movers) the static objects' CSMs. */
static void motion_bytes(const cssm_motion *m, double *self_bytes, double *csm_bytes,
                         double *static_bytes)
{
    *self_bytes = *csm_bytes = *static_bytes = 0.0;
    for (uint32_t k = 0; m->movers && k < m->mover_count; k++) {
        *self_bytes += (double)cssm_maps_bytes(&m->movers[k].self);
        *csm_bytes += (double)m->movers[k].csm.data.bytes_compressed;
    }
    for (uint32_t k = 0; m->static_csm && k < m->object_count; k++)
        *static_bytes += (double)m->static_csm[k].data.bytes_compressed;
}

static gi_result build_moving(cssm_hrc *c, const gi_gpu_scene *gs, gi_error *err)
{
    const gi_host *host = c->kit.host;
    gi_result r = cssm_motion_init(gs->scene, gs->time, &c->atlas, &c->motion, err);
    if (r != GI_OK)
        return r;
    cssm_build_opts o = {.skip_objects = c->motion.object_moves, .dont_care = c->motion.on_moving};
    r = cssm_maps_build_ex(gs, &c->atlas, c->order, (uint32_t)c->M, &o, host, &c->maps, err);
    if (r == GI_OK)
        r = cssm_motion_build_maps(&c->motion, gs, &c->atlas, c->order, (uint32_t)c->M, host, err);
    if (r != GI_OK)
        return r;
    c->maps.motion = &c->motion;
    host->stat(host, "cache_hit", 0.0);
    double self_bytes, csm_bytes, static_bytes;
    motion_bytes(&c->motion, &self_bytes, &csm_bytes, &static_bytes);
    host->stat(host, "moving_objects", (double)c->motion.mover_count);
    host->stat(host, "moving_cssm_bytes", self_bytes);
    host->stat(host, "moving_csm_bytes", csm_bytes);
    if (c->motion.mover_count > 1)
        host->stat(host, "static_csm_bytes", static_bytes);
    check_hulls(c, gs->scene, gs->time);
    return GI_OK;
}

static gi_result cssm_prepare(void *inst, const gi_gpu_scene *gs)
{
    cssm_hrc *c = inst;
    release_prepared(c);
    gi_kit_prepare(&c->kit, gs);
    const gi_host *host = c->kit.host;
    gi_error err;
    uint32_t moving = 0;
    cssm_motion_find(gs->scene, &moving);
    if (moving && gi_scene_deforms(gs->scene))
        return gi_kit_fail(&c->kit, GI_ERR_UNSUPPORTED,
                           "cssm_hrc: deforming objects are not supported");
    if (moving && c->env_mode == 1 && gs->scene->has_environment)
        return gi_kit_fail(&c->kit, GI_ERR_UNSUPPORTED,
                           "cssm_hrc: env=cssm does not support moving objects (use env=trace)");
    if (moving && c->direct)
        return gi_kit_fail(&c->kit, GI_ERR_UNSUPPORTED,
                           "cssm_hrc: direct=csm does not support moving objects (its maps hold "
                           "the static scene)");
    host->stage_begin(host, "atlas");
    gi_result r =
        cssm_atlas_build(gs->scene, gs->time, (uint32_t)c->R, c->traversal == 0, &c->atlas, &err);
    host->stage_end(host, "atlas");
    if (r != GI_OK)
        return gi_kit_fail_with(&c->kit, r, &err);
    const cssm_atlas *a = &c->atlas;
    host->stat(host, "atlas_texels", (double)a->count);
    host->stat(host, "atlas_chart_texels", (double)a->chart_texels);
    host->stat(host, "atlas_charts", (double)a->chart_count);
    host->stat(host, "atlas_coverage", a->covered_area / a->surface_area);
    if (c->nodes && (r = cssm_ctree_check(a->count, &err)) != GI_OK) /* before the maps are made */
        return gi_kit_fail_with(&c->kit, r, &err);
    host->stage_begin(host, "traversal");
    c->order = cssm_traverse(a, c->traversal == 3 ? CSSM_GREEDY : (cssm_traversal)c->traversal);
    host->stage_end(host, "traversal");
    if (!c->order)
        return gi_kit_fail(&c->kit, GI_ERR_OUT_OF_MEMORY,
                           "cssm_hrc: out of memory for the traversal");
    r = moving ? build_moving(c, gs, &err) : load_or_build_maps(c, gs, &err);
    if (r != GI_OK)
        return gi_kit_fail_with(&c->kit, r, &err);
    uint64_t bc = cssm_maps_bytes(&c->maps), bu = cssm_maps_bytes_uncompressed(&c->maps);
    host->stat(host, "cssm_bytes", (double)bc);
    host->stat(host, "cssm_bytes_uncompressed", (double)bu);
    double self_bytes, csm_bytes, static_bytes;
    motion_bytes(&c->motion, &self_bytes, &csm_bytes, &static_bytes);
    host->stat(host, "compression_ratio", bc ? (double)bu / (double)bc : 0.0);
    host->stat(host, "segments_per_texel",
               (double)cssm_maps_segments(&c->maps) / (6.0 * c->M * c->M));
    host->stat(host, "dont_care_share", (double)c->maps.dont_care / (double)c->maps.face_texels);
    host->stage_begin(host, "hierarchy");
    r = cssm_tree_build(a, &c->tree, &err);
    if (r == GI_OK)
        r = make_compact(c, &err);
    host->stage_end(host, "hierarchy");
    if (r != GI_OK)
        return gi_kit_fail_with(&c->kit, r, &err);
    host->stage_begin(host, "direct");
    r = make_direct(c, gs, &err);
    host->stage_end(host, "direct");
    if (r != GI_OK)
        return gi_kit_fail_with(&c->kit, r, &err);
    /* data_bytes counts the compressed visibility maps, the bulk of what is
     * kept: the CSSM, the movers' maps and, with direct=csm, the lights'
     * CSMs; the atlas and the hierarchy are not counted. */
    host->stat(host, "data_bytes",
               (double)bc + self_bytes + csm_bytes + static_bytes +
                   (c->csm ? (double)cssm_csm_direct_bytes(c->csm) : 0.0));
    r = lighting(c, gs);
    if (r != GI_OK)
        return r;
    c->prepared = 1;
    return GI_OK;
}

static gi_result cssm_update(void *inst, const gi_gpu_scene *gs, const gi_changes *changes)
{
    cssm_hrc *c = inst;
    gi_kit_update(&c->kit, gs, changes);
    if (!c->prepared)
        return gi_kit_fail(&c->kit, GI_ERR_INVALID_ARGUMENT, "cssm_hrc: update before prepare");
    if (changes->flags & GI_CHANGED_VERTICES)
        return gi_kit_fail(&c->kit, GI_ERR_UNSUPPORTED,
                           "cssm_hrc: deforming objects are not supported");
    int moved = 0;
    if (changes->flags & GI_CHANGED_TRANSFORMS) {
        if (c->motion.moving < 0)
            return gi_kit_fail(&c->kit, GI_ERR_UNSUPPORTED,
                               "cssm_hrc: an object moved that was not animated at prepare time");
        /* §3.3: A's texels placed by T, the hierarchy made again over the
         * moved texels (a median cut of a few thousand points: what a fresh
         * prepare would make), the atlas lit again; the CSSMs and the CSMs
         * are not made again (D T^-1) */
        const gi_host *host = c->kit.host;
        gi_error err;
        host->stage_begin(host, "motion");
        cssm_motion_place(&c->motion, gs->scene, gs->time, &c->atlas);
        host->stage_end(host, "motion");
        host->stage_begin(host, "hierarchy");
        cssm_tree_free(&c->tree);
        gi_result r = cssm_tree_build(&c->atlas, &c->tree, &err);
        if (r == GI_OK)
            r = make_compact(c, &err);
        host->stage_end(host, "hierarchy");
        if (r != GI_OK) { /* what was made before is gone: render refuses until the next prepare */
            c->prepared = 0;
            return gi_kit_fail_with(&c->kit, r, &err);
        }
        check_hulls(c, gs->scene, gs->time);
        moved = 1;
    }
    if (moved || (changes->flags & (GI_CHANGED_LIGHTS | GI_CHANGED_MATERIALS))) {
        gi_error err;
        if (changes->flags & GI_CHANGED_MATERIALS) {
            /* materials are read into the atlas texels */
            for (uint32_t i = 0; i < c->atlas.count; i++) {
                cssm_texel *x = &c->atlas.texels[i];
                gi_vec3 p[3];
                gi_scene_triangle_world(gs->scene, x->triangle, gs->time, p);
                cssm_texel_material(gs->scene, x->triangle, p, x);
            }
        }
        const gi_host *host = c->kit.host;
        host->stage_begin(host, "direct");
        gi_result r = make_direct(c, gs, &err);
        host->stage_end(host, "direct");
        if (r != GI_OK) { /* what was made before is gone: render refuses until the next prepare */
            c->prepared = 0;
            return gi_kit_fail_with(&c->kit, r, &err);
        }
        r = lighting(c, gs);
        if (r != GI_OK)
            c->prepared = 0;
        return r;
    }
    return GI_OK;
}

static gi_result read_gbuffer(cssm_hrc *c, uint32_t w, uint32_t h)
{
    const gi_gbuffer *g = c->kit.gbuffer;
    GLuint tex[5] = {g->tex_position, g->tex_normal, g->tex_albedo, g->tex_phong, g->tex_emission};
    size_t n = (size_t)w * h * 4;
    for (int i = 0; i < 5; i++) {
        if (c->acc_w != w || c->acc_h != h || !c->gb[i]) {
            free(c->gb[i]);
            c->gb[i] = malloc(n * sizeof(float));
            if (!c->gb[i])
                return gi_kit_fail(&c->kit, GI_ERR_OUT_OF_MEMORY,
                                   "cssm_hrc: out of memory for the G-buffer");
        }
        glGetTextureImage(tex[i], 0, GL_RGBA, GL_FLOAT, (GLsizei)(n * sizeof(float)), c->gb[i]);
    }
    if (c->mode == 1 || c->motion.moving >= 0 || c->texel_E) { /* triangle ids: charts, movers */
        if (c->acc_w != w || c->acc_h != h || !c->ids) {
            free(c->ids);
            c->ids = malloc(n * sizeof *c->ids);
            if (!c->ids)
                return gi_kit_fail(&c->kit, GI_ERR_OUT_OF_MEMORY,
                                   "cssm_hrc: out of memory for the G-buffer");
        }
        glGetTextureImage(g->tex_ids, 0, GL_RGBA_INTEGER, GL_UNSIGNED_INT,
                          (GLsizei)(n * sizeof *c->ids), c->ids);
    }
    if (c->acc_w != w || c->acc_h != h || !c->accum) {
        free(c->accum);
        c->accum = calloc(n, sizeof(float));
        if (!c->accum)
            return gi_kit_fail(&c->kit, GI_ERR_OUT_OF_MEMORY,
                               "cssm_hrc: out of memory for the image");
        c->acc_w = w, c->acc_h = h;
    }
    return GI_OK;
}

/* One gather of light set `which` (0: emission + reflected, 1: emission,
 * 2: reflected) by the hierarchy's cut, or by Monte Carlo (indirect=mc). */
static void gather(const cssm_hrc *c, int which, const cssm_receiver *rc, const cssm_gather_opts *o,
                   float out[3], cssm_gather_stats *st)
{
    if (c->indirect == 1) {
        const float *tv = which == 0 ? c->texel_L : which == 1 ? c->texel_Le : c->texel_B;
        cssm_gather_mc(&c->atlas, &c->maps, tv, c->cdf[which], (uint32_t)c->mc_samples, rc, o, out);
        return;
    }
    if (c->nodes) {
        cssm_cgather(&c->ct[which], &c->atlas, &c->maps, rc, o, out, st);
        return;
    }
    const float *nv = which == 0 ? c->node_L : which == 1 ? c->node_Le : c->node_B;
    cssm_gather(&c->tree, &c->atlas, &c->maps, nv, rc, o, out, st);
}

/* The nearest atlas texel to P whose normal faces the same way (brute
 * force; only for surface samples, which have no chart). -1: none. */
static int32_t nearest_texel(const cssm_atlas *a, gi_vec3 P, gi_vec3 n)
{
    int32_t best = -1;
    float bd = INFINITY;
    for (uint32_t i = 0; i < a->count; i++) {
        if (gi_v3_dot(a->texels[i].n, n) <= 0.0f)
            continue;
        gi_vec3 d = gi_v3_sub(a->texels[i].p, P);
        float dd = gi_v3_dot(d, d);
        if (dd < bd)
            bd = dd, best = (int32_t)i;
    }
    return best;
}

static gi_result cssm_render(void *inst, const gi_view *view, const gi_target *target)
{
    cssm_hrc *c = inst;
    gi_kit *kit = &c->kit;
    const gi_host *host = kit->host;
    if (!c->prepared)
        return gi_kit_fail(kit, GI_ERR_INVALID_ARGUMENT, "cssm_hrc: render before prepare");
    /* frames differ: average them */
    const int random = c->jitter || c->indirect == 1 || (c->texel_E && c->env_pixel) || c->csm;
    gi_result r = gi_kit_frame_begin(kit, view, GI_KIT_GBUFFER | (random ? 0u : GI_KIT_NO_AVERAGE));
    if (r != GI_OK)
        return r;
    r = gi_kit_render_gbuffer(kit, view, "gbuffer");
    if (r != GI_OK)
        return r;
    const uint32_t w = view->width, h = view->height;
    r = read_gbuffer(c, w, h);
    if (r != GI_OK)
        return r;
    const gi_scene *s = kit->scene->scene;
    const uint32_t frame = kit->frames;
    cssm_gather_stats st = {0};
    const int texels = c->mode == 1;
    if (texels) {
        /* Fig. 17 right: the final, glossy gather of the indirect light once
         * per atlas texel toward the eye */
        host->stage_begin(host, "texel_gather");
        for (uint32_t i = 0; i < c->atlas.count; i++) {
            const cssm_texel *x = &c->atlas.texels[i];
            cssm_receiver rc = {.x = offset(c, x->p, x->n),
                                .n = x->n,
                                .self = (int32_t)i,
                                .glossy = 1,
                                .exponent = fminf(x->exponent, 1000.0f)};
            memcpy(rc.kd, x->albedo, sizeof rc.kd);
            memcpy(rc.ks, x->ks, sizeof rc.ks);
            rc.wo = gi_v3_normalize(gi_v3_sub(view->eye, x->p));
            uint32_t rng = gi_rng_init(i, frame, view->seed ^ 0x7e1u);
            cssm_gather_opts o = gather_opts(c, view->exposure, random ? &rng : NULL);
            gather(c, 2, &rc, &o, &c->texel_T[3 * i], &st);
        }
        host->stage_end(host, "texel_gather");
    }
    host->stage_begin(host, "final_gather");
    for (uint32_t y = 0; y < h; y++)
        for (uint32_t x = 0; x < w; x++) {
            size_t p = (size_t)y * w + x;
            const float *pos = &c->gb[0][4 * p], *nor = &c->gb[1][4 * p], *alb = &c->gb[2][4 * p];
            const float *ph = &c->gb[3][4 * p], *em = &c->gb[4][4 * p];
            float out[3] = {0, 0, 0};
            if (pos[3] > 0.0f) {
                gi_vec3 P = gi_v3(pos[0], pos[1], pos[2]),
                        Nn = gi_v3_normalize(gi_v3(nor[0], nor[1], nor[2]));
                cssm_receiver rc = {
                    .x = offset(c, P, Nn), .n = Nn, .self = -1, .glossy = 1, .exponent = ph[3]};
                if (c->motion.moving >= 0) { /* §3.3: the pixel's object and proxy texel */
                    uint32_t tri = c->ids[4 * p + 2];
                    int32_t proxy = cssm_motion_proxy(&c->motion, s, &c->atlas, tri, P, Nn);
                    rc.proxy1 = proxy >= 0 ? (uint32_t)proxy + 1u : 0u;
                    rc.moving = cssm_motion_mover1(&c->motion, s, tri);
                }
                memcpy(rc.kd, alb, 3 * sizeof(float));
                memcpy(rc.ks, ph, 3 * sizeof(float));
                if (alb[3] > 0.5f) /* mirrors: their Phong lobe stands in (README) */
                    rc.exponent = fminf(rc.exponent, 1000.0f);
                rc.wo = gi_v3_normalize(gi_v3_sub(view->eye, P));
                uint32_t rng = gi_rng_init((uint32_t)p, frame, view->seed ^ 0xc55u);
                cssm_gather_opts o = gather_opts(c, view->exposure, random ? &rng : NULL);
                if (!texels) {
                    gather(c, c->csm ? 2 : 0, &rc, &o, out,
                           &st); /* with direct=csm the reflected light only */
                } else {
                    /* direct light of the emitting texels per pixel, the indirect light from the
                     * lightmap */
                    if (!c->csm)
                        gather(c, 1, &rc, &o, out, NULL);
                    uint32_t tri = c->ids[4 * p + 2];
                    int32_t chart = tri < s->triangle_count ? c->atlas.tri_chart[tri] : -1;
                    float ind[3] = {0, 0, 0}, u, v;
                    int ok = 0;
                    if (chart >= 0) {
                        cssm_chart_coords(&c->atlas, (uint32_t)chart, P, &u, &v);
                        ok = cssm_chart_bicubic(&c->atlas, (uint32_t)chart, u, v, c->texel_T, ind);
                    }
                    if (!ok) /* surface samples have no atlas position: gathered per pixel */
                        gather(c, 2, &rc, &o, ind, &st);
                    for (int k = 0; k < 3; k++)
                        out[k] += ind[k];
                }
                if (c->csm) /* §4.7: the direct light of every light by the CSMs, S new light points
                               a frame */
                    cssm_csm_direct_eval(
                        c->csm, s, &rc, (uint32_t)c->csm_samples, (uint32_t)c->env_samples,
                        gi_pcg_hash((uint32_t)p ^ gi_pcg_hash(frame ^ view->seed ^ 0xd1cu)),
                        c->bias_f * c->atlas.diameter, c->pcf, out);
                for (uint32_t l = 0; l < c->shadow_count; l++) {
                    float e[3];
                    punctual(c, s, l, rc.x, Nn, e);
                    if (e[0] <= 0.0f && e[1] <= 0.0f && e[2] <= 0.0f)
                        continue;
                    gi_vec3 wi = c->shadows[l].type == GI_LIGHT_DIRECTIONAL
                                     ? gi_v3_scale(c->shadows[l].dir, -1.0f)
                                     : gi_v3_normalize(gi_v3_sub(c->shadows[l].pos, P));
                    gi_vec3 rr = gi_v3_sub(gi_v3_scale(Nn, 2.0f * gi_v3_dot(Nn, rc.wo)), rc.wo);
                    float cl = gi_v3_dot(rr, wi);
                    float lobe = cl > 0.0f
                                     ? (rc.exponent + 2.0f) / (2.0f * GI_PI) * powf(cl, rc.exponent)
                                     : 0.0f;
                    for (int k = 0; k < 3; k++)
                        out[k] += (rc.kd[k] / GI_PI + rc.ks[k] * lobe) * e[k];
                }
                if (c->texel_E) { /* environment: the texels' irradiance, bicubic (surface samples:
                                     nearest) */
                    uint32_t tri = c->ids[4 * p + 2];
                    int32_t chart = tri < s->triangle_count ? c->atlas.tri_chart[tri] : -1;
                    float e[3] = {0, 0, 0}, u, v;
                    int ok = 0;
                    if (c->env_pixel &&
                        c->maps.escape) { /* env=cssm: the maps of the texels around it */
                        cssm_env_proxy px;
                        cssm_env_proxies(&c->atlas, &c->maps, s, tri, P, Nn, c->pcf, &px);
                        if (px.count)
                            cssm_env_estimate(
                                s->envmap, Nn, (uint32_t)c->env_samples,
                                gi_pcg_hash((uint32_t)p ^ gi_pcg_hash(frame ^ view->seed)), &rc,
                                cssm_env_proxy_vis, &px, e);
                        for (int k = 0; k < 3; k++)
                            out[k] += e[k];
                    } else if (c->env_pixel) { /* reflected radiance (diffuse and glossy) traced at
                                                  the pixel */
                        env_irradiance(s->envmap, c->rt, rc.x, Nn, (uint32_t)c->env_samples,
                                       gi_pcg_hash((uint32_t)p ^ gi_pcg_hash(frame ^ view->seed)),
                                       &rc, e);
                        for (int k = 0; k < 3; k++)
                            out[k] += e[k];
                    } else {
                        if (chart >= 0) {
                            cssm_chart_coords(&c->atlas, (uint32_t)chart, P, &u, &v);
                            ok =
                                cssm_chart_bicubic(&c->atlas, (uint32_t)chart, u, v, c->texel_E, e);
                        }
                        if (!ok) {
                            int32_t near = nearest_texel(&c->atlas, P, Nn);
                            if (near >= 0)
                                memcpy(e, &c->texel_E[3 * near], sizeof e);
                        }
                        for (int k = 0; k < 3; k++)
                            out[k] += rc.kd[k] / GI_PI * e[k];
                    }
                }
                for (int k = 0; k < 3; k++)
                    out[k] += em[k];
            } else if (c->texel_E || (c->csm && s->has_environment &&
                                      s->envmap)) { /* the environment past the scene */
                gi_vec3 f = gi_mat4_point(view->inv_view_proj,
                                          gi_v3(((float)x + 0.5f) / (float)w * 2.0f - 1.0f,
                                                ((float)y + 0.5f) / (float)h * 2.0f - 1.0f, 1.0f));
                gi_envmap_eval(s->envmap, gi_v3_normalize(gi_v3_sub(f, view->eye)), out);
            }
            float *acc = &c->accum[4 * p];
            float wgt = 1.0f / (float)(frame + 1);
            for (int k = 0; k < 3; k++)
                acc[k] = frame ? acc[k] + (out[k] - acc[k]) * wgt : out[k];
            acc[3] = 1.0f;
        }
    host->stage_end(host, "final_gather");
    glTextureSubImage2D(target->texture, 0, 0, 0, (GLsizei)w, (GLsizei)h, GL_RGBA, GL_FLOAT,
                        c->accum);
    gi_kit_frame_end(kit);
    if (c->motion.moving >= 0) {
        host->stat(host, "hull_overlap", (double)c->motion.overlaps);
        host->stat(host, "hull_intrusion", (double)c->motion.intrusions);
        for (uint32_t k = 0; k < c->motion.pair_count; k++) { /* per pair of objects with a mover */
            const cssm_hull_pair *pr = &c->motion.pairs[k];
            char pair[72], name[96];
            snprintf(pair, sizeof pair, "%.30s.%.30s",
                     s->objects[pr->a].name ? s->objects[pr->a].name : "?",
                     s->objects[pr->b].name ? s->objects[pr->b].name : "?");
            snprintf(name, sizeof name, "hull_overlap.%s", pair);
            host->stat(host, name, (double)pr->overlap);
            snprintf(name, sizeof name, "hull_intrusion.%s", pair);
            host->stat(host, name, (double)pr->intrusion);
        }
    }
    if (st.receivers) {
        host->stat(host, "cut_size_pixels", (double)st.nodes / (double)st.receivers);
        host->stat(host, "clamped_share", (double)st.clamped / (double)st.nodes);
    }
    gi_error err;
    if (gi_gl_check("cssm_hrc: upload", &err) != GI_OK)
        return gi_kit_fail_with(kit, GI_ERR_GL, &err);
    return GI_OK;
}

static void cssm_destroy(void *inst)
{
    cssm_hrc *c = inst;
    if (!c)
        return;
    release_prepared(c);
    for (int i = 0; i < 5; i++)
        free(c->gb[i]);
    free(c->accum);
    free(c->ids);
    gi_kit_free(&c->kit);
    free(c);
}

static const char *cssm_last_error(void *inst)
{
    return inst ? gi_kit_last_error(&((cssm_hrc *)inst)->kit) : "";
}

GI_METHOD_EXPORT(cssm, .id = "cssm_hrc",
                 .title = "Coherent Surface Shadow Maps + hierarchical radiosity",
                 .citation = "Ritschel, Grosch, Kautz, Seidel. Interactive Illumination with "
                             "Coherent Surface Shadow Maps. GI 2008",
                 .version = "0.1",
                 .caps = GI_CAP_DIRECT | GI_CAP_INDIRECT | GI_CAP_GLOSSY | GI_CAP_AREA_LIGHTS |
                         GI_CAP_POINT_LIGHTS | GI_CAP_DIRECTIONAL | GI_CAP_ENVIRONMENT |
                         GI_CAP_VISIBILITY | GI_CAP_PROGRESSIVE | GI_CAP_PRECOMPUTE |
                         GI_CAP_RIGID_MOTION | GI_CAP_TEXTURES,
                 .max_bounces = 3, .params = cssm_params);
