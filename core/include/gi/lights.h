/* Light helpers shared by the reference and the GPU methods; C twin of
 * core/shaders/lights.glsl.
 *
 * Punctual lights (KHR_lights_punctual, radiometric): a point light of
 * radiant intensity I gives irradiance I cos(theta) / d^2 at distance d; a
 * spot light scales that by gi_spot_falloff; a directional light gives
 * E cos(theta). `range` > 0 windows the falloff smoothly to zero at d =
 * range (the glTF extension's recommended window); 0 means no window.
 *
 * Area lights: emissive triangles emit from their front face (counter-
 * clockwise winding, glTF's front) only, unless the material is double-
 * sided. A point y drawn uniformly on triangle T with area A has area
 * density 1 / A; seen from x the solid-angle density is d^2 / (A cos_y).
 */
#ifndef GI_LIGHTS_H
#define GI_LIGHTS_H

#include "gi/scene.h"
#include "gi/vecmath.h"

#ifdef __cplusplus
extern "C" {
#endif

/* glTF spot falloff: 0 outside the outer cone, 1 inside the inner cone,
 * smooth (squared linear ramp in cos) between. */
static inline float gi_spot_falloff(float cos_angle, float cos_inner, float cos_outer)
{
    if (cos_inner <= cos_outer)
        return cos_angle >= cos_outer ? 1.0f : 0.0f;
    float t = (cos_angle - cos_outer) / (cos_inner - cos_outer);
    t = t < 0.0f ? 0.0f : (t > 1.0f ? 1.0f : t);
    return t * t;
}

/* Range window of KHR_lights_punctual: (1 - (d / range)^4)^2 clamped, 1
 * when range is 0. */
static inline float gi_range_window(float d, float range)
{
    if (range <= 0.0f)
        return 1.0f;
    float r = d / range;
    float w = 1.0f - r * r * r * r;
    w = w < 0.0f ? 0.0f : w;
    return w * w;
}

/* Cosine at the emitter toward x for a triangle with geometric normal ng
 * (unnormalised cross product order p1-p0, p2-p0), given w = unit direction
 * from x to the light point; 0 when x is behind a one-sided emitter. */
static inline float gi_emitter_cos(gi_vec3 ng_unit, gi_vec3 w_to_light, int double_sided)
{
    float c = -gi_v3_dot(ng_unit, w_to_light);
    if (double_sided)
        return fabsf(c);
    return c > 0.0f ? c : 0.0f;
}

/* Toward KHR punctual light `lt` placed at `f` (gi_scene_light_at) from
 * world point x: the unit direction *w, the distance *dist (INFINITY for a
 * directional light) and *scale, such that the irradiance on a surface of
 * normal n is intensity x max(n . w, 0) x scale (1 / d^2 with the range
 * window and the spot cone; 1 for a directional light). Returns 0 when x
 * is at the light's position (no direction). */
static inline int gi_punctual_toward(const gi_light *lt, gi_light_frame f, gi_vec3 x, gi_vec3 *w,
                                     float *dist, float *scale)
{
    if (lt->type == GI_LIGHT_DIRECTIONAL) {
        *w = gi_v3_normalize(gi_v3_scale(f.direction, -1.0f));
        *dist = INFINITY;
        *scale = 1.0f;
        return 1;
    }
    gi_vec3 d = gi_v3_sub(f.position, x);
    float r = gi_v3_length(d);
    if (!(r > 0.0f))
        return 0;
    *w = gi_v3_scale(d, 1.0f / r);
    *dist = r;
    *scale = gi_range_window(r, lt->range) / (r * r);
    if (lt->type == GI_LIGHT_SPOT)
        *scale *= gi_spot_falloff(-gi_v3_dot(*w, gi_v3_normalize(f.direction)),
                                  cosf(lt->inner_cone), cosf(lt->outer_cone));
    return 1;
}

#ifdef __cplusplus
}
#endif
#endif
