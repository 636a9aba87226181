// Unshadowed environment light on Lambertian surfaces by cosine-weighted
// sampling (example_env.c). The kit's includes give the G-buffer
// (gi_gbuffer_surface), the view (u_size, u_frame, u_seed, gi_background)
// and the running average (gi_accumulate_store).
#include "gbuffer_read.glsl"
#include "accumulate.glsl"
#include "sampling.glsl"
#include "rng.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

uniform int u_samples;

void main()
{
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(px, u_size)))
        return;
    GiSurface s = gi_gbuffer_surface(px);
    vec3 L = gi_background(px);
    if (s.hit) {
        L = s.emission;
        if (gi_has_environment()) {
            uint rng = gi_rng_init(uint(px.y * u_size.x + px.x), u_frame, u_seed);
            vec3 sum = vec3(0.0);
            for (int i = 0; i < u_samples; i++) {
                vec3 local = gi_sample_cosine_hemisphere(gi_rng_next_float(rng), gi_rng_next_float(rng));
                sum += gi_envmap_eval(gi_to_world(local, s.normal));
            }
            L += s.brdf.kd * sum / float(u_samples);
        }
    }
    gi_accumulate_store(px, L);
}
