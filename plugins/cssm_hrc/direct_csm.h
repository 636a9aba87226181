/* The "Direct Light" alternative of §4.7 of the cssm_hrc paper (option
 * direct=csm): the direct light of the scene's lights by the Monte-Carlo
 * illumination of the original Coherent Shadow Maps (Ritschel et al. 2007,
 * the csm plugin), the atlas then pulled and the indirect bounces left to
 * the HRC simulation.
 *
 *  - area lights (emitting triangles): N points on the emitters, drawn by
 *    power (the core's emitter CDF, a Hammersley set, so the points are
 *    stratified over the emitting area), a depth cube map at each, all of
 *    them compressed by the core's codec in a greedy nearest-first order
 *    (the CSSM build of cssm.c: gi/algo/csm_precompute.h);
 *  - point and spot lights: one such cube map at the light each;
 *  - directional lights and the environment map: per object the core's
 *    distant CSM (gi/algo/csm_distant.h), the visibility of a direction the
 *    product over the objects, directions of the environment drawn from the
 *    core's sampler (gi/envmap.h) and cosine-weighted, balance heuristic.
 *
 * Atlas texels get the fixed estimate over the N points (every point with
 * its own cube map); pixels get S points drawn on the emitters every frame,
 * each shadowed by the cube map of the nearest of the N points (the CSM's
 * nearest filter over light positions, §5.1 of the 2007 paper), averaged
 * over frames. Static scenes only: the maps hold the whole scene in world
 * space (cssm_hrc refuses direct=csm with moving objects). */
#ifndef CSSM_DIRECT_CSM_H
#define CSSM_DIRECT_CSM_H

#include "cssm.h"

#include "gi/algo/csm_distant.h"
#include "gi/gpu.h"

typedef struct cssm_csm_direct {
    cssm_atlas pts;  /* the light points as "texels": position, normal (zero at punctual lights) */
    uint32_t *order; /* their order in the codec (greedy nearest-first) */
    cssm_maps maps;  /* a depth cube map per point */
    uint32_t
        area_points; /* points 0 .. area_points-1 lie on emitters, then one per point/spot light */
    float *pt_Le;    /* per area point: its emitted radiance (3) */
    float *pt_w;     /* per area point: 1 / (N pdf_area) */
    unsigned char *pt_ds; /* per area point: its emitter is double-sided */
    uint32_t
        *light_point;   /* per scene light: its point (point / spot), UINT32_MAX for directional */
    gi_gpu_emitter *em; /* the core's emitter table (read back): triangle, area, cdf, pdf */
    uint32_t em_count;
    gi_csm_distant
        *distant; /* per object (directional lights, environment), NULL when none is needed */
    float (*local_from_world)[16];
    float *scale;    /* per object: world units per local unit (bias conversion) */
    float *sphere_w; /* per object: world bounding sphere (4), for a quick reject */
    uint32_t object_count;
    float diameter;
    float time;
} cssm_csm_direct;

/* Builds everything above for the scene at gs->time: N points on the area
 * lights (0 when there are none), cube faces M x M. host may be NULL; with
 * one: stage timers csm_render and compress (of the precomputation loop),
 * progress, cancellation. GL context current. */
gi_result cssm_csm_direct_build(const gi_gpu_scene *gs, float diameter, uint32_t N, uint32_t M,
                                const gi_host *host, cssm_csm_direct *out, gi_error *err);
void cssm_csm_direct_free(cssm_csm_direct *d);
/* Compressed bytes of the cube maps and of the distant CSMs. */
uint64_t cssm_csm_direct_bytes(const cssm_csm_direct *d);

/* Reflected direct radiance at receiver rc (a texel: kd / pi; a pixel with
 * rc->glossy: kd / pi + the normalised Phong lobe toward rc->wo), added to
 * out[3]. S == 0: the fixed estimate over the N area points (atlas texels);
 * S > 0: S points drawn on the emitters from seed (pixels, one frame).
 * env_samples directions of the environment. bias: depth bias in world
 * units; pcf: 2 x 2 PCF in the cube maps. */
void cssm_csm_direct_eval(const cssm_csm_direct *d, const gi_scene *s, const cssm_receiver *rc,
                          uint32_t S, uint32_t env_samples, uint32_t seed, float bias, int pcf,
                          float out[3]);

/* Visibility of direction w from world point x on a surface of normal n
 * through the objects' distant CSMs (1 lit, 0 blocked; bias in world
 * units, plus a slope-scaled bias of a map texel x tan(n, w)); 1 when none
 * was built. */
int cssm_csm_direct_open(const cssm_csm_direct *d, gi_vec3 x, gi_vec3 n, gi_vec3 w, float bias);

#endif
