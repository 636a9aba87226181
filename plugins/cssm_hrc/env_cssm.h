/* Environment light of the cssm_hrc plugin (§4.7 "Direct Light"; §4: the
 * CSM shadows environment maps): the Monte Carlo estimator over
 * environment directions (the core's sampler gi/envmap.h and
 * cosine-weighted directions, balance heuristic) with the visibility of a
 * direction given by a callback, and that callback for `env=cssm`: the
 * escape test in a texel's own coherent surface shadow map.
 *
 * With `env=cssm` the cube maps are built with escape intervals
 * (cssm_build_opts.escape): a face texel that saw a surface enters the
 * codec as [z1, min(z2, far)), one that saw none as [far, inf), so a run of
 * maps never mixes the two and a decoded z_avg >= far means "no surface in
 * this direction": the direction escapes to the environment. */
#ifndef CSSM_ENV_CSSM_H
#define CSSM_ENV_CSSM_H

#include "cssm.h"

#include "gi/envmap.h"

/* Visibility of the environment in unit direction w: 1 escapes, 0 blocked
 * (fractions with filtering). */
typedef float (*cssm_env_vis_fn)(const void *ctx, gi_vec3 w);

/* The environment light at a point with unit normal n: K directions, half
 * drawn by the environment map's importance sampler, half cosine-weighted,
 * combined by the balance heuristic, each weighted by vis(ctx, w). brdf
 * NULL: irradiance E in e[3]; otherwise the radiance reflected toward
 * brdf->wo by its diffuse + normalised Phong BRDF. seed picks the
 * directions (the same seed, the same directions whatever vis is). */
void cssm_env_estimate(const gi_envmap *env, gi_vec3 n, uint32_t K, uint32_t seed,
                       const cssm_receiver *brdf, cssm_env_vis_fn vis, const void *ctx, float e[3]);

/* Whether direction w escapes from texel j's cube map (maps built with
 * escape intervals): z_avg >= far in the face texel of w. pcf: the 2 x 2
 * face texels around w, bilinearly weighted (a fraction). */
float cssm_escape(const cssm_maps *m, uint32_t j, gi_vec3 w, int pcf);

/* The environment irradiance of every atlas texel (3 per texel into
 * texel_E): cssm_env_estimate with the texel's own escape test, K
 * directions, seed = texel index (the same directions as the traced
 * estimate of env=trace). */
void cssm_env_texels(const gi_envmap *env, const cssm_atlas *a, const cssm_maps *m, uint32_t K,
                     int pcf, float *texel_E);

/* What cssm_escape asks of one texel's map for a direction w: below the
 * plane of the texel the map holds "don't care", counted as blocked. */
typedef struct cssm_env_texel_ctx {
    const cssm_maps *m;
    uint32_t texel;
    gi_vec3 n; /* the texel's normal */
    int pcf;
} cssm_env_texel_ctx;
float cssm_env_texel_vis(const void *ctx, gi_vec3 w);

/* The texels whose cube maps stand in for a pixel (pixels have no map). */
#define CSSM_ENV_PROXIES 4
typedef struct cssm_env_proxy {
    const cssm_maps *m;
    const cssm_atlas *a;
    uint32_t count; /* 0: none found */
    uint32_t texel[CSSM_ENV_PROXIES];
    float weight[CSSM_ENV_PROXIES];
    int pcf;
} cssm_env_proxy;

/* The proxies of a pixel at P (normal n) on scene triangle tri: on a chart
 * the 2 x 2 chart texels around P with bilinear weights (those that
 * exist); elsewhere (surface samples) the 4 nearest texels of the same
 * object whose normal is within 60 degrees of n, weighted by inverse
 * squared distance (brute force over the texels). */
void cssm_env_proxies(const cssm_atlas *a, const cssm_maps *m, const gi_scene *s, uint32_t tri,
                      gi_vec3 P, gi_vec3 n, int pcf, cssm_env_proxy *out);
/* The pixel's visibility of direction w: the proxies' escape tests,
 * weighted, over the proxies whose plane w lies above; 0 when it lies
 * below all of them (as for one texel; counting it as escaping instead
 * changed the images' squared error by under 0.3 %). ctx: a
 * cssm_env_proxy. */
float cssm_env_proxy_vis(const void *ctx, gi_vec3 w);

#endif
