/* Direct irradiance at a surface point by shadow rays: the scene's
 * emitting triangles (sampled by power, a point uniform on the chosen
 * triangle), the environment (the map's sampler and cosine directions
 * combined, gi_envmap_mis_direction) and the punctual lights (one ray
 * each), every ray through the core's ray caster (gi/raytrace.h), so the
 * one rule for sides holds (a single-sided triangle seen from its back
 * neither blocks nor emits).
 *
 * What a method that keeps its own transport for the bounces can use for
 * the first gather when its own visibility is not exact (implicit_vis's
 * `direct=traced`, README "Traced direct light"). The reference path
 * tracer (harness/reference) does the same next-event estimation inside
 * its paths.
 *
 * Use:
 *     gi_direct_rays *d;
 *     if (gi_direct_rays_create(rt, &d, &err) != GI_OK) ...   // after gi_rt_set_time
 *     float E[3];
 *     gi_direct_rays_irradiance(d, x, n, 16, 16, seed, E);    // any number of threads
 *     gi_direct_rays_free(d);
 * The gi_rt must outlive the gi_direct_rays and stay at the time it had
 * when the gi_direct_rays was created (the emitters are placed then). */
#ifndef GI_ALGO_DIRECT_RAYS_H
#define GI_ALGO_DIRECT_RAYS_H

#include "gi/raytrace.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct gi_direct_rays gi_direct_rays;

/* The emitters of rt's scene placed at rt's time, with their power CDF.
 * A scene without emitters, environment or lights is fine (the irradiance
 * is then 0). GI_ERR_OUT_OF_MEMORY, or GI_ERR_INVALID_ARGUMENT for NULL. */
gi_result gi_direct_rays_create(const gi_rt *rt, gi_direct_rays **out, gi_error *err);
void gi_direct_rays_free(gi_direct_rays *d);
/* Emitting triangles (for tests and stats). */
uint32_t gi_direct_rays_emitters(const gi_direct_rays *d);

/* Irradiance E (rgb) at world point x on the side of unit normal n: area
 * lights from area_samples points (stratified in the power CDF), the
 * environment from env_samples directions, each punctual light exactly
 * with one shadow ray. `seed` picks the random numbers (the same seed
 * gives the same E). Rays start at x and ignore hits nearer than 1e-4 of
 * the scene's size (a point is not shadowed by its own surface, nor in a
 * corner by the face beside it). An unbiased estimate: its mean over seeds converges to the
 * direct irradiance. */
void gi_direct_rays_irradiance(const gi_direct_rays *d, gi_vec3 x, gi_vec3 n, uint32_t area_samples,
                               uint32_t env_samples, uint32_t seed, float E[3]);

#ifdef __cplusplus
}
#endif
#endif
