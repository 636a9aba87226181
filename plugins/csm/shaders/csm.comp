// Coherent Shadow Maps, §5: per G-buffer pixel S samples of the environment
// and S samples of the area lights, every point/spot and directional light
// once, visibility from the CSMs of all objects (orthographic maps for
// distant and semi-local light, cube maps for local light), progressive
// average over frames (plugins/csm/csm.c).
#include "scene.glsl"
#include "brdf.glsl"
#include "sampling.glsl"
#include "rng.glsl"
#include "envmap.glsl"
#include "lights.glsl"
#include "csm_query.glsl"
#include "csm_local.glsl"
#include "gbuffer_read.glsl"
#include "accumulate.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

// 256 stratified patterns of S points in the unit square (§5.1).
layout(std430, binding = 13) readonly buffer CsmPatterns { vec2 csm_patterns[]; };

uniform int u_S;
uniform int u_distant; // 1: the objects have orthographic CSMs
uniform int u_mode; // 0 shade; Table 2 visibility benchmarks: 1 random, 2 coherent
// Debug buffers (debug.c): 0 the image; 1 the shaded direct light without
// emission; 2 the same unshadowed (every visibility 1); 3 the mean length of
// the CSM texel lists (segments) the pixel's queries read.
uniform int u_debug;

// Monte Carlo samples taken this frame (S per surface pixel), for the
// samples-per-second figure of Table 2.
layout(std430, binding = 17) buffer CsmCount { uint csm_sample_count; };

// Table 2's visibility benchmarks: S shadow tests in uniform directions on
// the sphere, returning the visible fraction. "random": each pixel its own
// stratified pattern with its own shift (as shading uses); "coherent": every
// pixel of the frame the same pattern and no shift, so that sample s tests
// the same direction at every pixel.
float visibility_test(vec3 x, vec3 N, uint pattern, vec2 cp, inout uint rng)
{
    float sum = 0.0;
    for (int s = 0; s < u_S; s++) {
        vec2 u = fract(csm_patterns[pattern * uint(u_S) + uint(s)] + cp);
        sum += csm_visibility(x, N, gi_sample_uniform_sphere(u.x, u.y), rng);
    }
    return sum / float(u_S);
}

// §5.1: diffuse surfaces draw from the environment's radiance CDF, specular
// ones from the Phong lobe; a surface with both picks the lobe by Russian
// roulette on lum(k_s) / (lum(k_d) + lum(k_s)). Each lobe is estimated by
// its own strategy (f_lobe L cos V / (P_lobe pdf)).
vec3 environment(gi_brdf b, vec3 x, vec3 N, vec3 wo, uint pattern, vec2 cp, inout uint rng)
{
    float p_spec = gi_brdf_spec_prob(b);
    gi_brdf bd = b, bs = b;
    bd.ks = vec3(0.0);
    bs.kd = vec3(0.0);
    vec3 sum = vec3(0.0);
    for (int s = 0; s < u_S; s++) {
        vec2 u = fract(csm_patterns[pattern * uint(u_S) + uint(s)] + cp);
        bool spec = gi_rng_next_float(rng) < p_spec;
        vec3 w;
        vec3 c;
        if (spec) {
            if (gi_brdf_is_mirror(b)) {
                w = gi_reflect(wo, N);
                if (dot(N, w) <= 0.0)
                    continue;
                c = b.ks / p_spec;
            } else {
                vec3 r = gi_reflect(wo, N);
                w = gi_phong_lobe_sample(r, b.n, u.x, u.y);
                float pdf = gi_phong_lobe_pdf(r, b.n, w);
                float cw = dot(N, w);
                if (pdf <= 0.0 || cw <= 0.0)
                    continue;
                c = gi_brdf_eval(bs, N, wo, w) * cw / (pdf * p_spec);
            }
        } else {
            float pdf = gi_envmap_sample(u.x, u.y, w);
            float cw = dot(N, w);
            if (pdf <= 0.0 || cw <= 0.0)
                continue;
            c = gi_brdf_eval(bd, N, wo, w) * cw / (pdf * (1.0 - p_spec));
        }
        if (all(equal(c, vec3(0.0))))
            continue;
        float v = u_debug == 2 ? 1.0 : csm_visibility(x, N, w, rng);
        if (v > 0.0)
            sum += c * v * gi_envmap_eval(w);
    }
    return sum / float(u_S);
}

// §5.1 "Sampling local illumination": area lights by their radiance
// distribution (an emissive triangle by power from the core's emitter CDF,
// then a uniform point on it, both from one stratified pattern point),
// visibility by the CSM of the light the triangle belongs to.
vec3 area_lights(gi_brdf b, vec3 x, vec3 N, vec3 wo, uint own, uint pattern, vec2 cp, inout uint rng)
{
    vec3 sum = vec3(0.0);
    for (int s = 0; s < u_S; s++) {
        vec2 u = fract(csm_patterns[pattern * uint(u_S) + uint(s)] + cp);
        // u.x picks the triangle and, rescaled within its CDF interval,
        // the point on it, so the pattern's strata cover the whole light
        uint e = gi_emitter_find(u.x);
        GiEmitter em = gi_emitters[e];
        float cdf0 = e > 0u ? gi_emitters[e - 1u].cdf : 0.0;
        float ux = em.pdf > 0.0 ? clamp((u.x - cdf0) / em.pdf, 0.0, 0.99999994) : 0.0;
        vec3 p0, p1, p2;
        gi_triangle_world(em.triangle, p0, p1, p2);
        vec3 bc = gi_sample_uniform_triangle(ux, u.y);
        vec3 y = bc.x * p0 + bc.y * p1 + bc.z * p2;
        vec3 ng = cross(p1 - p0, p2 - p0);
        float area = 0.5 * length(ng);
        if (area <= 0.0 || em.pdf <= 0.0)
            continue;
        vec3 d = y - x;
        float dist2 = dot(d, d);
        vec3 w = d * inversesqrt(dist2);
        float cos_x = dot(N, w);
        GiMaterial lm = gi_materials[gi_triangle_material(em.triangle)];
        float cos_y = gi_emitter_cos(ng / (2.0 * area), w, (lm.flags & GI_MATERIAL_DOUBLE_SIDED) != 0u);
        if (cos_x <= 0.0 || cos_y <= 0.0)
            continue;
        uint j = csm_light_cells[gi_vertices[gi_indices[3u * em.triangle]].object];
        float v = j < csm_light_count && u_debug != 2 ? csm_light_visibility(j, x, N, y, own, rng) : 1.0;
        if (v > 0.0)
            sum += gi_brdf_eval(b, N, wo, w) * lm.emission * cos_x * cos_y * v * area / (dist2 * em.pdf);
    }
    return sum / float(u_S);
}

// Point, spot (cube maps at one point, or semi-local) and directional
// lights (orthographic maps), each once per frame.
vec3 punctual_lights(gi_brdf b, vec3 x, vec3 N, vec3 wo, uint own, inout uint rng)
{
    vec3 sum = vec3(0.0);
    for (uint i = 0u; i < gi_light_count(); i++) {
        GiLight l = gi_lights[i];
        vec3 w, E;
        if (l.type == GI_LIGHT_DIRECTIONAL) {
            w = -l.direction;
            E = l.intensity;
        } else {
            vec3 d = l.position - x;
            float dist = length(d);
            w = d / dist;
            E = l.intensity * gi_range_window(dist, l.range) / (dist * dist);
            if (l.type == GI_LIGHT_SPOT)
                E *= gi_spot_falloff(dot(-w, l.direction), l.cos_inner, l.cos_outer);
        }
        float c = dot(N, w);
        if (c <= 0.0 || all(equal(E, vec3(0.0))))
            continue;
        float v = 1.0;
        if (l.type == GI_LIGHT_DIRECTIONAL) {
            if (u_distant != 0 && u_debug != 2)
                v = csm_visibility(x, N, w, rng);
        } else {
            for (uint j = 0u; j < csm_light_count; j++)
                if (csm_lights[j].info.w == (0x80000000u | i) && u_debug != 2) {
                    v = csm_light_visibility(j, x, N, l.position, own, rng);
                    break;
                }
        }
        if (v > 0.0)
            sum += gi_brdf_eval(b, N, wo, w) * E * c * v;
    }
    return sum;
}

void main()
{
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, u_size)))
        return;
    GiSurface sf = gi_gbuffer_surface(px);
    vec3 L = gi_background(px);
    if (sf.hit) {
        vec3 x = sf.position, N = sf.normal;
        vec3 wo = normalize(u_eye - x);
        gi_brdf b = sf.brdf;
        uint pix = uint(px.y * u_size.x + px.x);
        uint rng = gi_rng_init(pix, u_frame, u_seed);
        // Pattern from the pixel and the frame through a hash (§5.1), with a
        // per-pixel-and-frame Cranley-Patterson shift so that the running
        // average converges to the integral, not to 256 fixed point sets.
        uint pattern = gi_pcg_hash(pix ^ gi_pcg_hash(u_frame * 0x9E3779B9u + u_seed)) & 255u;
        vec2 cp = vec2(gi_rng_next_float(rng), gi_rng_next_float(rng));
        atomicAdd(csm_sample_count, uint(u_S));
        if (u_mode == 2) {
            pattern = gi_pcg_hash(u_frame * 0x9E3779B9u + u_seed) & 255u;
            cp = vec2(0.0);
        }
        L = sf.emission;
        if (u_mode != 0)
            L = vec3(visibility_test(x, N, pattern, cp, rng));
        else if (gi_has_environment())
            L += environment(b, x, N, wo, pattern, cp, rng);
        uint own = gi_gbuffer_ids_at(px).x;
        if (u_mode == 0) {
            if (gi_emitter_count() > 0u)
                L += area_lights(b, x, N, wo, own, (pattern + 97u) & 255u, cp, rng);
            L += punctual_lights(b, x, N, wo, own, rng);
        }
        if (u_debug == 1 || u_debug == 2)
            L -= sf.emission;
        if (u_debug == 3)
            L = vec3(csm_dbg_lookups > 0.0 ? csm_dbg_segments / csm_dbg_lookups : 0.0);
    } else if (u_debug != 0) {
        L = vec3(0.0);
    }
    gi_accumulate_store(px, L);
}
