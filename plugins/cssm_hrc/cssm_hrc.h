/* The cssm_hrc plugin's instance and what its files share (Ritschel,
 * Grosch, Kautz, Seidel, GI 2008):
 *   cssm_hrc.c       the descriptor, the parameter table cssm_params and
 *                    the lifecycle functions;
 *   direct_light.c   the direct light of the punctual lights and the
 *                    environment (§4.7 "Direct Light"), or direct=csm;
 *   lighting.c       the hierarchy's packed nodes (§4.2.1) and the atlas'
 *                    lighting (§4.1, Fig. 8);
 *   maps_cache.c     the CSSM (§3.2) of a static scene, cached on disk;
 *   motion_update.c  moving rigid objects (§3.3) at prepare and update;
 *   final_gather.c   the per-pixel final gather (§4.4, §4.5) and shading;
 *   gpu_gather.c     the same final gather as a GL compute pass (gather=gpu,
 *                    shaders/cssm_gather.comp; §4 "HRC on the GPU"), and
 *                    the HRC bounces' per-texel gathers (bounces_on=gpu,
 *                    shaders/cssm_bounce.comp; §4.1.1);
 *   stats.c          the stats the plugin reports.
 * The parts of the paper these call (atlas, CSSM, hierarchy) are in
 * cssm.h, motion.h, env_cssm.h and direct_csm.h. */
#ifndef CSSM_HRC_H
#define CSSM_HRC_H

#include "cssm.h"
#include "direct_csm.h"
#include "motion.h"

#include "gi/envmap.h"
#include "gi/kit.h"
#include "gi/log.h"
#include "gi/raytrace.h"

/* gpu_gather.c: a program per set of the defines pcf, jitter, rep_centroid, glossy */
#define CSSM_GPU_PROGS 16
#define CSSM_GPU_BUFFERS 7 /* gpu_gather.c: nodes, leaves, texels, offsets, z_avg, i_end, stats */

typedef struct cssm_shadow_map {
    int type; /* GI_LIGHT_* */
    uint32_t size;
    gi_vec3 pos, dir; /* light frame */
    float view[16];   /* directional: world -> eye */
    float half;       /* directional: half extent of the orthographic map */
    float *depth;     /* 6 faces (point, spot) or 1 map, size^2 floats each */
} cssm_shadow_map;

typedef struct cssm_hrc {
    gi_kit kit;
    int R, M, traversal, bounces, max_cut, jitter, pcf, shadow_size;
    int rep_centroid; /* rep=centroid: the area rule of representatives (hrc.c pick_leaf) */
    float threshold, clamp_f, bias_f;
    cssm_atlas atlas;
    uint32_t *order;
    cssm_maps maps;
    cssm_tree tree;
    float *texel_D; /* direct light not from emitting texels (punctual, environment, direct=csm) */
    int has_direct; /* texel_D is not all zero: a light that is not an atlas texel */
    int bounces_every; /* 0 frame: render() solves the HRC bounces every frame; 1 change */
    float *texel_L;    /* emission + reflected, 3 per texel */
    float *node_L;     /* pulled texel_L */
    float *node_Le;    /* pulled emission (texel mode: direct light per pixel) */
    float *node_B;     /* pulled reflected light (texel mode: indirect) */
    float *texel_T;    /* texel mode: view-dependent indirect light per texel, 3 per texel */
    uint32_t *ids;     /* G-buffer ids read-back (texel mode) */
    int mode;
    int indirect, mc_samples;  /* §4.6 alternative: Monte Carlo from the atlas as a pdf */
    float *texel_Le, *texel_B; /* emission and reflected light per texel */
    double *cdf[3];            /* pdf tables of texel_L, texel_Le, texel_B */
    cssm_shadow_map *shadows;
    uint32_t shadow_count;
    int env_samples; /* environment light: directions per texel (or pixel) */
    int env_pixel;  /* 1: environment light traced per pixel; 0: the texels' irradiance looked up */
    int env_mode;   /* environment visibility: 0 ray tracer, 1 the texels' own CSSMs (env_cssm.c) */
    gi_rt *rt;      /* the scene for the environment's occlusion, NULL without environment */
    int vis;        /* 1: vis=trace, the gathers' visibility by ray queries (Fig. 14) */
    gi_rt *vis_rt;  /* vis=trace: the scene for those queries */
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
    int gather;      /* gather=gpu (0) or cpu (1): where the per-pixel final gather runs */
    int gpu_on;      /* gather=gpu and the scene and options are ones the GPU pass covers */
    int gpu_texels;  /* gather=gpu, mode=texels: the per-texel gather is a pass (static, hrc) */
    int gpu_dirty;   /* the lighting changed since the GPU node buffer was filled */
    int gpu_maps_ok; /* the texels, albedo and CSSM faces are in the GPU buffers */
    GLuint gpu_prog[CSSM_GPU_PROGS]; /* cssm_gather.comp per define set (gpu_gather.c) */
    int bounces_on; /* bounces_on=gpu (0) or cpu (1): where the HRC bounces' gathers run */
    GLuint gpu_bounce_prog[CSSM_GPU_PROGS]; /* cssm_bounce.comp per define set */
    GLuint gpu_bounce_buf[2];               /* texels' albedo, gathered radiance */
    cssm_gather_opts bounce_opts;           /* the solve's gather options, for the compute pass */
    GLuint gpu_buf[CSSM_GPU_BUFFERS];
    /* the read-only buffers as buffer textures (the shaders read those):
     * nodes, leaves, texels, offsets, z_avg, i_end; then the albedo */
    GLuint gpu_tex[CSSM_GPU_BUFFERS];
    uint32_t gpu_off_base[6], gpu_seg_base[6]; /* each face's first offset and segment */
    /* CPU time of the frames after the first since prepare (stats.c, frame_cpu_ms) */
    uint32_t cpu_frames;
    double cpu_process_s, cpu_main_s, cpu_t0[2];
    int prepared;
} cssm_hrc;

/* ------------------------------------------------------ direct_light.c */

void cssm_release_shadows(cssm_hrc *c);
/* The direct light's maps: the punctual lights' shadow maps (direct=maps),
 * or the CSMs of direct=csm (§4.7, direct_csm.h), made again when the
 * lights or materials change. Stage timer csm_precompute; stats
 * csm_bytes, csm_points, csm_maps. */
gi_result cssm_make_direct(cssm_hrc *c, const gi_gpu_scene *gs, gi_error *err);
/* Irradiance-like factor of punctual light i at point x with normal n
 * (E / colour: intensity x cos / d^2 x spot x range, or E cos), shadowed by
 * its shadow map. Returns the light's irradiance in e[3]. */
void cssm_punctual(const cssm_hrc *c, const gi_scene *s, uint32_t i, gi_vec3 x, gi_vec3 n,
                   float e[3]);
/* Environment irradiance at x with normal n (any direct-light method will
 * do, §4.7 "Direct Light"): the estimator of env_cssm.c, each direction
 * counted when the core's ray tracer finds nothing along it. */
void cssm_env_irradiance(const gi_envmap *env, const gi_rt *rt, gi_vec3 x, gi_vec3 n, uint32_t K,
                         uint32_t seed, const cssm_receiver *brdf, float e[3]);

/* ---------------------------------------------------------- lighting.c */

/* The gathers' options from the parameters. */
cssm_gather_opts cssm_hrc_gather_opts(const cssm_hrc *c, float exposure, uint32_t *rng);
/* The receiver position of surface point p (cssm_receiver_point). */
gi_vec3 cssm_hrc_offset(const cssm_hrc *c, gi_vec3 p, gi_vec3 n);
/* nodes=compact: the packed hierarchy (§4.2.1), one per light set, after
 * the float one was built; stats of the node memory either way. */
gi_result cssm_make_compact(cssm_hrc *c, gi_error *err);
/* The atlas' lighting (§4.1, Fig. 8) with the punctual lights' direct
 * light per texel added to the first bounce. Fails through the kit. */
gi_result cssm_lighting(cssm_hrc *c, const gi_gpu_scene *gs);
/* The HRC bounces (§4.1, Fig. 8) over the direct light cssm_lighting
 * kept (texel_D): texel_L, node_L and the light sets made anew; with
 * jitter each gather's senders jittered by the streams of (frame, seed)
 * (cssm_gather_opts.atlas_jitter). cssm_lighting calls it without jitter;
 * render() every frame with bounces_every=frame. Fails through the kit. */
gi_result cssm_bounces_solve(cssm_hrc *c, int jitter, uint32_t frame, uint32_t seed);

/* -------------------------------------------------------- maps_cache.c */

/* The static scene's CSSM: read from the cache, or made and stored. */
gi_result cssm_load_or_build_maps(cssm_hrc *c, const gi_gpu_scene *gs, gi_error *err);

/* ----------------------------------------------------- motion_update.c */

/* §3.3 with moving objects, made in prepare(): the static CSSM, each
 * mover's own CSSM and CSM, the static objects' CSMs (motion.c). */
gi_result cssm_build_moving(cssm_hrc *c, const gi_gpu_scene *gs, gi_error *err);
/* §3.3 in update(): the movers placed at the scene's time, the hierarchy
 * made again, the hulls checked. Fails through the kit (unprepared). */
gi_result cssm_place_movers(cssm_hrc *c, const gi_gpu_scene *gs);

/* ------------------------------------------------------ final_gather.c */

/* The G-buffer read back into c->gb (and the ids, the image). Fails
 * through the kit. */
gi_result cssm_read_gbuffer(cssm_hrc *c, uint32_t w, uint32_t h);
/* Texel mode (Fig. 17 right): the glossy gather of the indirect light per
 * atlas texel toward the eye, into c->texel_T. Stage timer texel_gather. */
void cssm_texel_gather(cssm_hrc *c, const gi_view *view, uint32_t frame, int random,
                       cssm_gather_stats *st);
/* Every pixel's radiance averaged into c->accum. Stage timer
 * final_gather. */
void cssm_final_gather(cssm_hrc *c, const gi_view *view, uint32_t frame, int random,
                       cssm_gather_stats *st);

/* -------------------------------------------------------- gpu_gather.c */

/* What gather=gpu does not cover in this scene with these options (its
 * name, for the log line), or NULL: then the C gather runs instead. */
const char *cssm_gpu_unsupported(const cssm_hrc *c, const gi_scene *s);
/* The final gather of every pixel by the compute pass, averaged over the
 * frames in the kit's accumulation image and written to the target; the
 * buffers filled first when gpu_dirty. Stage timer final_gather. Fails
 * through the kit. */
gi_result cssm_gpu_final_gather(cssm_hrc *c, const gi_view *view, const gi_target *target,
                                int random, cssm_gather_stats *st);
/* gather=gpu in texel mode (static scenes, indirect=hrc): the glossy
 * gather of the reflected light per atlas texel toward the eye as a pass
 * of shaders/cssm_bounce.comp (CSSM_GLOSSY 1), read back into c->texel_T;
 * the twin of cssm_texel_gather, same streams. Stage timer texel_gather.
 * Fails through the kit. */
gi_result cssm_gpu_texel_gather(cssm_hrc *c, const gi_view *view, uint32_t frame, int random,
                                cssm_gather_stats *st);
/* Deletes the program and buffers (a GL context is current). */
void cssm_gpu_free(cssm_hrc *c);
/* bounces_on=gpu: points o's atlas_gather at the compute pass of the HRC
 * bounces (shaders/cssm_bounce.comp, §4.1.1), so that cssm_solve_ex runs
 * each per-texel gather there and reads the radiance back; the program is
 * built here, before the solve's timer. Fails (set on the kit) when it
 * does not build. */
gi_result cssm_gpu_bounces(cssm_hrc *c, cssm_gather_opts *o);

/* Debug buffer "indirect" (debug.c): the reflected light (light set 2:
 * every bounce after the first) that the hierarchy's cut gathers at pixel
 * p of the G-buffer read back by the last render(), without jitter. */
void cssm_pixel_reflected(const cssm_hrc *c, const gi_view *view, size_t p, float out[3]);

/* ------------------------------------------------------------- debug.c */

/* The debug buffers (plugin ABI 1.3): atlas and indirect. */
extern const gi_debug_buffer_desc cssm_debug_buffers[];
gi_result cssm_debug_buffer(void *inst, const char *name, const gi_view *view, gi_image **out);

/* ------------------------------------------------------------- stats.c */

/* atlas_texels, atlas_chart_texels, atlas_charts, atlas_coverage. */
void cssm_stats_atlas(const cssm_hrc *c);
/* The CSSM's size and compression. */
void cssm_stats_maps(const cssm_hrc *c);
/* The moving objects' maps (cssm_build_moving). */
void cssm_stats_moving(const cssm_hrc *c);
/* data_bytes: the compressed visibility maps. */
void cssm_stats_data_bytes(const cssm_hrc *c);
/* The last hull check, in all and per pair of objects with a mover. */
void cssm_stats_hulls(const cssm_hrc *c, const gi_scene *s);
/* A frame's CPU time: begin at the start of render(), end after it; the
 * stats frame_cpu_ms (every thread of the process: llvmpipe's included)
 * and frame_main_share (the main thread's part), means over the frames
 * after the first since prepare (the first compiles the shaders). */
void cssm_stats_cpu_begin(cssm_hrc *c);
void cssm_stats_cpu_end(cssm_hrc *c);
/* The process's CPU seconds (every thread, llvmpipe's included) and the
 * calling thread's, now: the stats solve_cpu_ms / solve_main_share. */
void cssm_cpu_now(double t[2]);
/* Cut size and clamped share of a frame's gathers. */
void cssm_stats_cuts(const cssm_hrc *c, const cssm_gather_stats *st);

#endif
