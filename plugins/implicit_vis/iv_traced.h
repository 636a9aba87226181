/* implicit_vis with `direct=traced` (our remedy, not the paper's; README
 * "Traced direct light"): the direct light by shadow rays through the
 * core's ray caster (gi/algo/direct_rays.h), at every element for the
 * first gather, so the bounces along the links start from it, and at
 * every pixel of the G-buffer for the display, which adds it to the
 * elements' indirect irradiance. The paper's implicit visibility still
 * carries every bounce.
 *
 * Use (a GL context current):
 *     iv_traced *tr = iv_traced_create(scene, time, elements, samples, threads, &err);
 *   per frame:
 *     iv_traced_elements(tr, hier, time, &err);   // tr->elem, 6 per element (iv_lights.direct)
 *     ... illumination, G-buffer ...
 *     iv_traced_pixels(tr, gbuffer, &err);        // tr->ssbo_pixel (IV_SSBO_PIXEL_DIRECT)
 *     iv_traced_free(tr); */
#ifndef IV_TRACED_H
#define IV_TRACED_H

#include "iv.h"

#include "gi/algo/direct_rays.h"
#include "gi/passes.h"

typedef struct iv_traced {
    gi_rt *rt;          /* the scene at the frame's time */
    gi_direct_rays *dr; /* its emitters, made per frame */
    float *elem;        /* 6 per element: direct irradiance on both sides */
    uint32_t elems;
    float *pos, *nrm, *pixel; /* per pixel, 4 floats each: G-buffer read-back, direct irradiance */
    size_t pixels;
    GLuint ssbo_pixel;
    uint32_t samples; /* shadow rays per point for the area lights, as many for the environment */
    uint32_t threads;
    uint32_t frame; /* frames so far: each frame draws new random numbers */
} iv_traced;

iv_traced *iv_traced_create(const gi_scene *s, float t, uint32_t elems, uint32_t samples,
                            uint32_t threads, gi_error *err);
void iv_traced_free(iv_traced *tr);
/* The scene placed at t and each element's direct irradiance (on the back
 * side only for a double-sided disc) into tr->elem. */
gi_result iv_traced_elements(iv_traced *tr, const iv_hier *h, float t, gi_error *err);
/* The direct irradiance at each pixel's surface (the G-buffer's position
 * and eye-facing normal; 0 where nothing was hit) into tr->ssbo_pixel. */
gi_result iv_traced_pixels(iv_traced *tr, const gi_gbuffer *gb, gi_error *err);

#endif
