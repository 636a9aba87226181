// Sampling building blocks: warps from [0,1)^2 to disk, hemisphere, sphere,
// cone and triangle with their pdfs, the power heuristic, and the local
// shading frame of gi_onb. GLSL twin of core/include/gi/sampling.h (same
// names and operation order); gi_onb is the twin of vecmath.h's.
#ifndef GI_SAMPLING_GLSL
#define GI_SAMPLING_GLSL
#include "common.glsl"

// Orthonormal basis around unit n (Duff et al. 2017). s copies the sign
// bit of n.z exactly as C's copysignf does, -0.0 included.
void gi_onb(vec3 n, out vec3 t, out vec3 b)
{
    float s = uintBitsToFloat((floatBitsToUint(n.z) & 0x80000000u) | 0x3f800000u);
    float a = -1.0 / (s + n.z);
    float c = n.x * n.y * a;
    t = vec3(1.0 + s * n.x * n.x * a, s * c, -s * n.x);
    b = vec3(c, s + n.y * n.y * a, -n.y);
}

vec3 gi_to_world(vec3 local, vec3 n)
{
    vec3 t, b;
    gi_onb(n, t, b);
    return vec3(t.x * local.x + b.x * local.y + n.x * local.z,
                t.y * local.x + b.y * local.y + n.y * local.z,
                t.z * local.x + b.z * local.y + n.z * local.z);
}

vec3 gi_to_local(vec3 world, vec3 n)
{
    vec3 t, b;
    gi_onb(n, t, b);
    return vec3(dot(world, t), dot(world, b), dot(world, n));
}

// Concentric map of the unit square onto the unit disk (Shirley-Chiu).
vec2 gi_sample_concentric_disk(float u1, float u2)
{
    float a = 2.0 * u1 - 1.0, b = 2.0 * u2 - 1.0;
    if (a == 0.0 && b == 0.0)
        return vec2(0.0);
    float r, phi;
    if (abs(a) > abs(b)) {
        r = a;
        phi = (GI_PI / 4.0) * (b / a);
    } else {
        r = b;
        phi = (GI_PI / 2.0) - (GI_PI / 4.0) * (a / b);
    }
    return vec2(r * cos(phi), r * sin(phi));
}

// Cosine-weighted hemisphere about +z (Malley); pdf = cos(theta) / pi.
vec3 gi_sample_cosine_hemisphere(float u1, float u2)
{
    vec2 d = gi_sample_concentric_disk(u1, u2);
    float z = sqrt(max(0.0, 1.0 - d.x * d.x - d.y * d.y));
    return vec3(d.x, d.y, z);
}
float gi_cosine_hemisphere_pdf(float cos_theta)
{
    return cos_theta > 0.0 ? cos_theta * GI_INV_PI : 0.0;
}

// Uniform over the unit sphere; pdf = 1 / (4 pi).
vec3 gi_sample_uniform_sphere(float u1, float u2)
{
    float z = 1.0 - 2.0 * u1;
    float r = sqrt(max(0.0, 1.0 - z * z));
    float phi = 2.0 * GI_PI * u2;
    return vec3(r * cos(phi), r * sin(phi), z);
}
float gi_uniform_sphere_pdf()
{
    return 1.0 / (4.0 * GI_PI);
}

// Uniform over the hemisphere about +z; pdf = 1 / (2 pi).
vec3 gi_sample_uniform_hemisphere(float u1, float u2)
{
    float z = u1;
    float r = sqrt(max(0.0, 1.0 - z * z));
    float phi = 2.0 * GI_PI * u2;
    return vec3(r * cos(phi), r * sin(phi), z);
}
float gi_uniform_hemisphere_pdf()
{
    return 1.0 / (2.0 * GI_PI);
}

// Uniform over the cone about +z with cos(half angle) = cos_max.
vec3 gi_sample_uniform_cone(float u1, float u2, float cos_max)
{
    float z = (1.0 - u1) + u1 * cos_max;
    float r = sqrt(max(0.0, 1.0 - z * z));
    float phi = 2.0 * GI_PI * u2;
    return vec3(r * cos(phi), r * sin(phi), z);
}
float gi_uniform_cone_pdf(float cos_max)
{
    return 1.0 / (2.0 * GI_PI * (1.0 - cos_max));
}

// Uniform barycentrics (b0, b1, b2) on a triangle (square-root method).
vec3 gi_sample_uniform_triangle(float u1, float u2)
{
    float su = sqrt(u1);
    float b0 = 1.0 - su;
    float b1 = u2 * su;
    return vec3(b0, b1, 1.0 - b0 - b1);
}

// Veach's power heuristic (beta = 2) weight of strategy f.
float gi_power_heuristic(float nf, float f_pdf, float ng, float g_pdf)
{
    float f = nf * f_pdf, g = ng * g_pdf;
    if (!(f > 0.0))
        return 0.0;
    float r = g / f;
    return 1.0 / (1.0 + r * r);
}
#endif
