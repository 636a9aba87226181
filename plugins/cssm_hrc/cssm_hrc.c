/* The `cssm_hrc` method: Coherent Surface Shadow Maps with hierarchical
 * radiosity and lightcuts-style final gathering (Ritschel, Grosch, Kautz,
 * Seidel, GI 2008). This file holds the descriptor, the parameter table
 * and the lifecycle; cssm_hrc.h lists the files of the steps.
 *
 * prepare(): the illumination atlas (§3.2.3), a depth cube map per texel in
 * a coherent traversal order compressed by the core's CSM codec (§3.2,
 * maps_cache.c; moving objects §3.3, motion_update.c), the median-cut
 * hierarchy with skip pointers (§4.2), shadow maps of the punctual lights
 * (direct_light.c), then the lighting of the atlas (lighting.c):
 *   direct:  R1 = kd/pi gather(emission) + punctual lights (shadow maps)
 *            + the environment (§4.7: ray-traced, cssm_env_irradiance(), or
 *              with env=cssm by the texels' own cube maps, env_cssm.c);
 *   bounce:  R_k = kd/pi gather(pull(R_{k-1})), k = 2 .. n (§4.1.1);
 *   pull:    the tree of L = emission + sum R_k.
 * With direct=csm (§4.7's alternative, direct_csm.c) R1 is the direct light
 * of every light by Coherent Shadow Maps and Monte Carlo instead, the
 * emitting texels not gathered, and pixels get that direct light too.
 * render(): G-buffer; per pixel the same traversal with a Phong bound
 * (§4.4), VPLs jittered inside their area and averaged over frames (§4.5),
 * distances clamped; plus emission, the punctual lights and the
 * environment per pixel (final_gather.c).
 * Pixels thus get light paths of 0 .. n + 1 bounces.
 * With gather=gpu (the default, as the paper) the final gather of
 * render() is a compute pass (gpu_gather.c), and with bounces_on=gpu (the
 * default) so are the HRC bounces' per-texel gathers, solved again in
 * every frame with bounces_every=frame (the default; jittered with
 * jitter=true, §4.5), and texel mode's per-texel gather; the pulls, and the
 * gathers with gather=cpu / bounces_on=cpu or where the final gather's pass
 * does not cover the scene, run on the CPU; the depth cube maps, shadow maps and G-buffer are drawn
 * by the core's GL passes. */
#include "cssm_hrc.h"

#include <stdlib.h>

extern const gi_shader_source gi_cssm_hrc_shaders[];

static const gi_param_desc cssm_params[] = {
    {"atlas", GI_PARAM_INT, 32, 8, 128, GI_QUALITY_UP(2), "atlas resolution (Sec. 3.2.3, Table 2)",
     "the illumination atlas is atlas x atlas texels; each texel is a surface sample, a cube map "
     "and a leaf"},
    {"M", GI_PARAM_INT, 16, 4, 64, GI_QUALITY_UP(2), "6 x M x M (Sec. 3.2.1, Table 2)",
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
    {"rep", GI_PARAM_ENUM, 0, 0, 0, "intensity|centroid", "representative (Sec. 4.4, 4.5)",
     "texel whose CSSM gives a gathered node's visibility (and, with jitter, where it sends "
     "from): intensity, lightcuts' representative drawn by radiant intensity (the paper's "
     "lightcuts); centroid, the texel nearest the node's centroid and uniform leaves with "
     "jitter (the area rule of before, for comparison)"},
    {"clamp", GI_PARAM_FLOAT, 0.02, 0.0, 1.0, NULL, "clamping (Sec. 5 Quality)",
     "distances below clamp x scene diameter count as that distance"},
    {"bias", GI_PARAM_FLOAT, 0.004, 0.0, 0.1, NULL, "depth bias (Fig. 14)",
     "CSSM depth bias as a fraction of the scene diameter"},
    {"pcf", GI_PARAM_BOOL, 0, 0, 1, NULL, "PCF (Sec. 3.2.2)",
     "CSSM look-ups filtered over 2 x 2 texels"},
    {"vis", GI_PARAM_ENUM, 0, 0, 0, "cssm|trace", "visibility (Fig. 14)",
     "cssm: the CSSM look-up (the paper's method); trace: an exact ray query (the core's ray "
     "tracer) from the receiver to each gathered point, in the bounces and the final gather, "
     "the paper's Fig. 14 comparison; runs the C gathers (gather and bounces_on ignored)"},
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
    {"gather", GI_PARAM_ENUM, 0, 0, 0, "gpu|cpu", "Sec. 4 (HRC on the GPU), Fig. 10",
     "where the per-pixel final gather runs: gpu, a compute pass every frame (the paper's); cpu, "
     "the C traversal (the oracle). gpu falls back to cpu, with a log line and stat gather_gpu 0, "
     "for mode=texels' per-pixel part (its per-texel gather is a pass), indirect=mc, direct=csm, "
     "moving objects, punctual lights and environments"},
    {"bounces_on", GI_PARAM_ENUM, 0, 0, 0, "gpu|cpu", "Sec. 4.1.1 (HRC on the GPU), Fig. 8",
     "where the HRC bounces' per-texel gathers run (see bounces_every): gpu, a compute pass "
     "per bounce (the paper's); cpu, the C loop (the oracle)"},
    {"bounces_every", GI_PARAM_ENUM, 0, 0, 0, "frame|change", "Sec. 4.1.1, Table 1",
     "when the HRC bounces are solved: frame, every frame (the paper's: its fps depend on the "
     "bounces), with jitter the senders drawn anew each frame as in the final gather (Sec. "
     "4.5); change, at prepare and when lights, materials or objects change"},
    {"shadow_size", GI_PARAM_INT, 256, 16, 2048, NULL, NULL,
     "face size of the point/spot lights' shadow cube maps and of directional lights' shadow maps"},
    {0},
};

static gi_result cssm_create(const gi_host *host, const gi_params *params, void **out)
{
    cssm_hrc *c = calloc(1, sizeof *c);
    if (!c)
        return GI_ERR_OUT_OF_MEMORY;
    if (gi_kit_init(&c->kit, host, gi_cssm_hrc_shaders) != GI_OK) {
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
    c->rep_centroid = gi_params_enum(params, "rep");
    c->clamp_f = gi_params_float(params, "clamp");
    c->bias_f = gi_params_float(params, "bias");
    c->env_samples = gi_params_int(params, "env_samples");
    c->env_pixel = gi_params_bool(params, "env_pixel");
    c->env_mode = gi_params_enum(params, "env");
    c->pcf = gi_params_bool(params, "pcf");
    c->vis = gi_params_enum(params, "vis");
    c->shadow_size = gi_params_int(params, "shadow_size");
    c->mode = gi_params_enum(params, "mode");
    c->indirect = gi_params_enum(params, "indirect");
    c->mc_samples = gi_params_int(params, "mc_samples");
    c->nodes = gi_params_enum(params, "nodes");
    c->direct = gi_params_enum(params, "direct");
    c->csm_points = gi_params_int(params, "csm_points");
    c->csm_samples = gi_params_int(params, "csm_samples");
    c->csm_M = gi_params_int(params, "csm_M");
    c->gather = gi_params_enum(params, "gather");
    c->bounces_on = gi_params_enum(params, "bounces_on");
    c->bounces_every = gi_params_enum(params, "bounces_every");
    c->motion.moving = -1;
    *out = c;
    return GI_OK;
}

static void release_prepared(cssm_hrc *c)
{
    cssm_atlas_free(&c->atlas);
    cssm_maps_free(&c->maps);
    cssm_tree_free(&c->tree);
    for (int i = 0; i < 3; i++)
        cssm_ctree_free(&c->ct[i]);
    free(c->order);
    free(c->texel_D);
    free(c->texel_L);
    free(c->node_L);
    free(c->node_Le);
    free(c->node_B);
    free(c->texel_T);
    c->order = NULL;
    c->texel_D = NULL;
    c->texel_L = c->node_L = c->node_Le = c->node_B = c->texel_T = NULL;
    free(c->texel_Le);
    free(c->texel_B);
    free(c->texel_E);
    c->texel_Le = c->texel_B = c->texel_E = NULL;
    gi_rt_free(c->rt);
    c->rt = NULL;
    gi_rt_free(c->vis_rt);
    c->vis_rt = NULL;
    for (int i = 0; i < 3; i++) {
        free(c->cdf[i]);
        c->cdf[i] = NULL;
    }
    cssm_release_shadows(c);
    cssm_csm_direct_free(c->csm);
    free(c->csm);
    c->csm = NULL;
    cssm_motion_free(&c->motion);
    c->prepared = 0;
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
    cssm_stats_atlas(c);
    if (c->nodes && (r = cssm_ctree_check(a->count, &err)) != GI_OK) /* before the maps are made */
        return gi_kit_fail_with(&c->kit, r, &err);
    host->stage_begin(host, "traversal");
    c->order = cssm_traverse(a, c->traversal == 3 ? CSSM_GREEDY : (cssm_traversal)c->traversal);
    host->stage_end(host, "traversal");
    if (!c->order)
        return gi_kit_fail(&c->kit, GI_ERR_OUT_OF_MEMORY,
                           "cssm_hrc: out of memory for the traversal");
    r = moving ? cssm_build_moving(c, gs, &err) : cssm_load_or_build_maps(c, gs, &err);
    if (r != GI_OK)
        return gi_kit_fail_with(&c->kit, r, &err);
    cssm_stats_maps(c);
    host->stage_begin(host, "hierarchy");
    r = cssm_tree_build(a, &c->tree, &err);
    if (r == GI_OK)
        r = cssm_make_compact(c, &err);
    host->stage_end(host, "hierarchy");
    if (r != GI_OK)
        return gi_kit_fail_with(&c->kit, r, &err);
    host->stage_begin(host, "direct");
    r = cssm_make_direct(c, gs, &err);
    host->stage_end(host, "direct");
    if (r != GI_OK)
        return gi_kit_fail_with(&c->kit, r, &err);
    cssm_stats_data_bytes(c);
    if (c->vis && (r = gi_rt_create(gs->scene, gs->time, &c->vis_rt, &err)) != GI_OK)
        return gi_kit_fail_with(&c->kit, r, &err);
    if (c->vis && (c->gather == 0 || c->bounces_on == 0))
        host->log(host, GI_LOG_INFO, "vis=trace: the C gathers run (gather=cpu, bounces_on=cpu)");
    r = cssm_lighting(c, gs);
    if (r != GI_OK)
        return r;
    const char *no_gpu = c->gather == 0 && !c->vis ? cssm_gpu_unsupported(c, gs->scene) : NULL;
    if (no_gpu)
        host->log(host, GI_LOG_INFO, "gather=gpu does not cover %s: the C gather runs", no_gpu);
    c->gpu_on = c->gather == 0 && !c->vis && !no_gpu;
    c->gpu_texels = c->gather == 0 && !c->vis && c->mode == 1 && c->indirect == 0 && !moving;
    host->stat(host, "texel_gather_gpu", c->gpu_texels);
    c->gpu_dirty = 1;
    c->cpu_frames = 0, c->cpu_process_s = c->cpu_main_s = 0.0;
    host->stat(host, "gather_gpu", c->gpu_on);
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
        gi_result r = cssm_place_movers(c, gs); /* §3.3, the atlas lit again below */
        if (r != GI_OK)
            return r;
        gi_error err;
        if (c->vis_rt && (r = gi_rt_set_time(c->vis_rt, gs->time, &err)) != GI_OK) {
            c->prepared = 0;
            return gi_kit_fail_with(&c->kit, r, &err);
        }
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
        gi_result r = cssm_make_direct(c, gs, &err);
        host->stage_end(host, "direct");
        if (r != GI_OK) { /* what was made before is gone: render refuses until the next prepare */
            c->prepared = 0;
            return gi_kit_fail_with(&c->kit, r, &err);
        }
        r = cssm_lighting(c, gs);
        if (r != GI_OK)
            c->prepared = 0;
        c->gpu_dirty = 1;
        return r;
    }
    return GI_OK;
}

static gi_result cssm_render(void *inst, const gi_view *view, const gi_target *target)
{
    cssm_hrc *c = inst;
    gi_kit *kit = &c->kit;
    if (!c->prepared)
        return gi_kit_fail(kit, GI_ERR_INVALID_ARGUMENT, "cssm_hrc: render before prepare");
    cssm_stats_cpu_begin(c);
    /* frames differ: average them */
    const int random = c->jitter || c->indirect == 1 || (c->texel_E && c->env_pixel) || c->csm;
    const unsigned what = c->gpu_on ? GI_KIT_GBUFFER | GI_KIT_ACCUMULATE : GI_KIT_GBUFFER;
    gi_result r = gi_kit_frame_begin(kit, view, what | (random ? 0u : GI_KIT_NO_AVERAGE));
    if (r != GI_OK)
        return r;
    /* bounces_every=frame: the n HRC bounces solved every frame (§4.1.1;
     * Table 1's fps fall with n), the senders jittered per frame (§4.5) */
    if (c->bounces_every == 0 &&
        (r = cssm_bounces_solve(c, c->jitter, kit->frames, view->seed)) != GI_OK) {
        c->prepared = 0; /* the light sets may be gone: render refuses until the next prepare */
        return r;
    }
    r = gi_kit_render_gbuffer(kit, view, "gbuffer");
    if (r != GI_OK)
        return r;
    cssm_gather_stats st = {0};
    if (c->gpu_on) { /* §4: the final gather in a compute pass */
        r = cssm_gpu_final_gather(c, view, target, random, &st);
        if (r != GI_OK)
            return r;
        gi_kit_frame_end(kit);
        cssm_stats_cuts(c, &st);
        cssm_stats_cpu_end(c);
        return GI_OK;
    }
    const uint32_t w = view->width, h = view->height;
    r = cssm_read_gbuffer(c, w, h);
    if (r != GI_OK)
        return r;
    const gi_scene *s = kit->scene->scene;
    const uint32_t frame = kit->frames;
    if (c->gpu_texels && (r = cssm_gpu_texel_gather(c, view, frame, random, &st)) != GI_OK)
        return r;
    if (c->mode == 1 && !c->gpu_texels)
        cssm_texel_gather(c, view, frame, random, &st);
    cssm_final_gather(c, view, frame, random, &st);
    glTextureSubImage2D(target->texture, 0, 0, 0, (GLsizei)w, (GLsizei)h, GL_RGBA, GL_FLOAT,
                        c->accum);
    gi_kit_frame_end(kit);
    if (c->motion.moving >= 0)
        cssm_stats_hulls(c, s);
    cssm_stats_cuts(c, &st);
    gi_error err;
    if (gi_gl_check("cssm_hrc: upload", &err) != GI_OK)
        return gi_kit_fail_with(kit, GI_ERR_GL, &err);
    cssm_stats_cpu_end(c);
    return GI_OK;
}

static void cssm_destroy(void *inst)
{
    cssm_hrc *c = inst;
    if (!c)
        return;
    release_prepared(c);
    cssm_gpu_free(c);
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
                 .max_bounces = 3, .params = cssm_params, .debug_buffers = cssm_debug_buffers,
                 .debug_buffer = cssm_debug_buffer);
