// Unshadowed direct light on the G-buffer (plugins/direct/direct.c).
#include "scene.glsl"
#include "brdf.glsl"
#include "sampling.glsl"
#include "rng.glsl"
#include "envmap.glsl"
#include "lights.glsl"
#include "gbuffer_read.glsl"
#include "accumulate.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

uniform int u_light_samples;
uniform int u_env_samples;
uniform bool u_mis;

// Area lights: emitter by power, point uniform on the triangle.
vec3 area_lights(gi_brdf b, vec3 x, vec3 N, vec3 wo, inout uint rng)
{
    vec3 sum = vec3(0.0);
    for (int s = 0; s < u_light_samples; s++) {
        uint e = gi_emitter_find(gi_rng_next_float(rng));
        GiEmitter em = gi_emitters[e];
        vec3 p0, p1, p2;
        gi_triangle_world(em.triangle, p0, p1, p2);
        vec3 bc = gi_sample_uniform_triangle(gi_rng_next_float(rng), gi_rng_next_float(rng));
        vec3 y = bc.x * p0 + bc.y * p1 + bc.z * p2;
        vec3 ng = cross(p1 - p0, p2 - p0);
        float area = 0.5 * length(ng);
        if (area <= 0.0 || em.pdf <= 0.0)
            continue;
        vec3 d = y - x;
        float dist2 = dot(d, d);
        vec3 w = d * inversesqrt(dist2);
        float cos_x = dot(N, w);
        uint lmi = gi_triangle_material(em.triangle);
        float cos_y = gi_emitter_cos(ng / (2.0 * area), w, gi_material_double_sided(lmi));
        if (cos_x <= 0.0 || cos_y <= 0.0)
            continue;
        float pdf_area = em.pdf / area;
        sum += gi_brdf_eval(b, N, wo, w) * gi_materials[lmi].emission * cos_x * cos_y / (dist2 * pdf_area);
    }
    return sum / float(u_light_samples);
}

vec3 punctual_lights(gi_brdf b, vec3 x, vec3 N, vec3 wo)
{
    vec3 sum = vec3(0.0);
    for (uint i = 0u; i < gi_light_count(); i++) {
        GiLight l = gi_lights[i];
        vec3 w;
        vec3 E;
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
        if (c > 0.0)
            sum += gi_brdf_eval(b, N, wo, w) * E * c;
    }
    return sum;
}

// Environment: light samples and (with MIS) BRDF samples, power heuristic.
vec3 environment(gi_brdf b, vec3 N, vec3 wo, inout uint rng)
{
    vec3 sum = vec3(0.0);
    int n = u_env_samples;
    for (int s = 0; s < n; s++) {
        vec3 w;
        float pdf_l = gi_envmap_sample(gi_rng_next_float(rng), gi_rng_next_float(rng), w);
        float c = dot(N, w);
        if (pdf_l > 0.0 && c > 0.0) {
            float mis = u_mis ? gi_power_heuristic(1.0, pdf_l, 1.0, gi_brdf_pdf(b, N, wo, w)) : 1.0;
            sum += gi_brdf_eval(b, N, wo, w) * gi_envmap_eval(w) * c * mis / pdf_l;
        }
        if (!u_mis)
            continue;
        vec3 wi, weight;
        float pdf_b;
        bool delta;
        gi_brdf_sample(b, N, wo, gi_rng_next_float(rng), gi_rng_next_float(rng), gi_rng_next_float(rng), wi, pdf_b,
                       weight, delta);
        if (pdf_b <= 0.0 || delta) // the delta lobe is added once, exactly, below
            continue;
        float mis = gi_power_heuristic(1.0, pdf_b, 1.0, gi_envmap_pdf(wi));
        sum += weight * gi_envmap_eval(wi) * mis;
    }
    sum = n > 0 ? sum / float(n) : vec3(0.0);
    if (gi_brdf_is_mirror(b))
        sum += b.ks * gi_envmap_eval(gi_reflect(wo, N));
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
        uint rng = gi_rng_init(uint(px.y * u_size.x + px.x), u_frame, u_seed);
        L = sf.emission;
        if (gi_emitter_count() > 0u)
            L += area_lights(sf.brdf, x, N, wo, rng);
        L += punctual_lights(sf.brdf, x, N, wo);
        if (gi_has_environment())
            L += environment(sf.brdf, N, wo, rng);
    }
    gi_accumulate_store(px, L);
}
