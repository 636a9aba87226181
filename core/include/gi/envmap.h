/* Environment map: an equirectangular radiance image with a piecewise-
 * constant importance-sampling distribution (luminance x sin(theta)).
 * C twin of core/shaders/envmap.glsl.
 *
 * Mapping (fixed): for a unit world direction d (+Y up), first rotate by
 * -rotation about +Y, then
 *     u = 0.5 + atan2(d.x, -d.z) / (2 pi),   v = acos(d.y) / pi,
 * with v = 0 the top row of the image. Radiance = texel x intensity.
 * (Both sides compute acos(d.y) as atan2(|d.xz|, d.y), which is accurate
 * near the poles; u is 0.5 at the poles themselves.)
 *
 * Sampling: a marginal CDF over rows and a conditional CDF per row, each
 * stored with a leading 0 and normalised to end at 1 (width+1 and height+1
 * entries). pdf is with respect to solid angle. The same tables are
 * uploaded to the GPU (gpu.h) so both sides draw identical samples.
 * A texel's weight is its luminance x sin(theta of the texel centre); the
 * pdf over (u, v) is read from the CDF differences, and over solid angle it
 * is p(u, v) / (2 pi^2 sin theta). A black map has an all-zero marginal
 * CDF (marg_cdf[height] == 0), samples nothing and has pdf 0 everywhere.
 */
#ifndef GI_ENVMAP_H
#define GI_ENVMAP_H

#include "gi/common.h"
#include "gi/vecmath.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct gi_envmap {
    uint32_t width, height;
    float *rgb;          /* width*height*3 linear radiance, intensity applied */
    float rotation;      /* radians about +Y */
    float *cond_cdf;     /* height rows of (width+1) */
    float *marg_cdf;     /* height+1 */
    float *row_weight;   /* height: unnormalised row sums (informative; the pdf
                            reads the CDFs) */
    double total_weight; /* sum of luminance x sin(theta) x texel area in (u, v),
                            i.e. 1 / (width height) */
} gi_envmap;

/* Builds the map and its CDF from an RGBA image (copied; row 0 = top).
 * NULL on a zero or absurd size or when memory runs out. */
gi_envmap *gi_envmap_create(const float *rgba, uint32_t width, uint32_t height, float intensity,
                            float rotation_deg);
void gi_envmap_free(gi_envmap *env);
/* The texels of an RGBA image (rgba, row 0 = top) whose R, G or B is NaN
 * or infinite, with the first one's column and row in *x, *y (when the
 * count is not 0). A scene's loader refuses a map with any: one such texel
 * turns every pixel that sees it, and every estimate that samples the map,
 * into NaN, which the metrics would then leave out. */
uint64_t gi_envmap_count_nonfinite(const float *rgba, uint32_t width, uint32_t height, uint32_t *x,
                                   uint32_t *y);

/* Direction <-> (u, v) in [0,1)^2, with the rotation applied. */
void gi_envmap_dir_to_uv(const gi_envmap *env, gi_vec3 d, float *u, float *v);
gi_vec3 gi_envmap_uv_to_dir(const gi_envmap *env, float u, float v);
/* Radiance seen in direction d (nearest texel, as the GPU fetches it). */
void gi_envmap_eval(const gi_envmap *env, gi_vec3 d, float out[3]);
/* Draws a direction from (u1, u2) in [0,1)^2 (u2 picks the row through the
 * marginal CDF, u1 the column through that row's conditional CDF, then the
 * position inside the texel is linear); returns its solid-angle pdf
 * (0 if the map is black, *dir then +Y). */
float gi_envmap_sample(const gi_envmap *env, float u1, float u2, gi_vec3 *dir);
float gi_envmap_pdf(const gi_envmap *env, gi_vec3 d);
/* Direction k of K for an estimate of the light the environment sends
 * onto a surface of normal n, from (u1, u2) in [0,1)^2: the first half of
 * the K directions drawn by the map's sampler, the rest cosine-weighted,
 * combined by the balance heuristic (the map's bright parts need its
 * sampler; cosine alone covers the rest of the hemisphere). Returns the
 * estimate's weight cos / (half pdf_map + (K - half) pdf_cos), so that the
 * irradiance is the sum over k of weight x L(w) x visibility; 0 when the
 * direction does not count (below the surface, or a black map). */
float gi_envmap_mis_direction(const gi_envmap *env, gi_vec3 n, uint32_t k, uint32_t K, float u1,
                              float u2, gi_vec3 *w);
/* Mean luminance over the sphere, (1 / 4 pi) Int lum(L) dw = total_weight
 * x pi / 2: a power-like weight for choosing between the map and other
 * lights. */
float gi_envmap_average_radiance(const gi_envmap *env);

#ifdef __cplusplus
}
#endif
#endif
