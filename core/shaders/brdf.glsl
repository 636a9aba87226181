// The material model: Lambert + normalised Phong lobe, or an ideal mirror.
// GLSL twin of core/include/gi/brdf.h (read its header for the formulas
// and conventions: wo and wi point away from the surface, N is on wo's
// side, eval and pdf exclude the delta lobe). C out-arrays are return
// values here where a function has a single result.
#ifndef GI_BRDF_GLSL
#define GI_BRDF_GLSL
#include "common.glsl"
#include "sampling.glsl"

struct gi_brdf {
    vec3 kd;    // Lambert albedo
    vec3 ks;    // Phong / mirror reflectance
    float n;    // Phong exponent
    int mirror; // ideal mirror of reflectance ks
};

bool gi_brdf_is_mirror(gi_brdf b)
{
    return b.mirror != 0 || b.n >= GI_MIRROR_EXPONENT;
}

// Probability of sampling the specular lobe: lum(ks) / (lum(kd) + lum(ks)).
float gi_brdf_spec_prob(gi_brdf b)
{
    float ls = gi_luminance(b.ks), ld = gi_luminance(b.kd);
    return ls > 0.0 ? ls / (ld + ls) : 0.0;
}

// 2 (N . wo) N - wo.
vec3 gi_reflect(vec3 wo, vec3 N)
{
    return N * (2.0 * dot(N, wo)) - wo;
}

// Direction about unit axis r with pdf (n + 1) / (2 pi) cos^n(alpha).
vec3 gi_phong_lobe_sample(vec3 r, float n, float u1, float u2)
{
    float cos_a = pow(u1, 1.0 / (n + 1.0));
    float sin_a = sqrt(max(0.0, 1.0 - cos_a * cos_a));
    float phi = 2.0 * GI_PI * u2;
    return gi_to_world(vec3(sin_a * cos(phi), sin_a * sin(phi), cos_a), r);
}
float gi_phong_lobe_pdf(vec3 r, float n, vec3 wi)
{
    float c = dot(r, wi);
    return c > 0.0 ? (n + 1.0) * (0.5 * GI_INV_PI) * pow(c, n) : 0.0;
}

// f(wo, wi) without the cosine, delta lobe excluded.
vec3 gi_brdf_eval(gi_brdf b, vec3 N, vec3 wo, vec3 wi)
{
    if (dot(N, wo) <= 0.0 || dot(N, wi) <= 0.0)
        return vec3(0.0);
    float spec = 0.0;
    if (!gi_brdf_is_mirror(b)) {
        float c = dot(gi_reflect(wo, N), wi);
        if (c > 0.0)
            spec = (b.n + 2.0) * (0.5 * GI_INV_PI) * pow(c, b.n);
    }
    return b.kd * GI_INV_PI + b.ks * spec;
}

// Solid-angle pdf of gi_brdf_sample's non-delta part.
float gi_brdf_pdf(gi_brdf b, vec3 N, vec3 wo, vec3 wi)
{
    float cos_o = dot(N, wo), cos_i = dot(N, wi);
    if (cos_o <= 0.0 || cos_i <= 0.0)
        return 0.0;
    float ps = gi_brdf_spec_prob(b);
    float pdf = (1.0 - ps) * cos_i * GI_INV_PI;
    if (ps > 0.0 && !gi_brdf_is_mirror(b))
        pdf += ps * gi_phong_lobe_pdf(gi_reflect(wo, N), b.n, wi);
    return pdf;
}

// Draws wi; weight = f cos / pdf. Delta sample: is_delta, pdf = P_spec,
// weight = ks / P_spec. Failed sample: pdf 0, weight 0.
void gi_brdf_sample(gi_brdf b, vec3 N, vec3 wo, float u1, float u2, float u3, out vec3 wi,
                    out float pdf, out vec3 weight, out bool is_delta)
{
    wi = N;
    pdf = 0.0;
    is_delta = false;
    weight = vec3(0.0);
    if (dot(N, wo) <= 0.0)
        return;
    float ps = gi_brdf_spec_prob(b);
    vec3 r = gi_reflect(wo, N);
    if (u3 < ps) {
        if (gi_brdf_is_mirror(b)) {
            wi = r;
            pdf = ps;
            is_delta = true;
            weight = b.ks / ps;
            return;
        }
        wi = gi_phong_lobe_sample(r, b.n, u1, u2);
    } else {
        wi = gi_to_world(gi_sample_cosine_hemisphere(u1, u2), N);
    }
    float cos_i = dot(N, wi);
    if (cos_i <= 0.0)
        return;
    float p = gi_brdf_pdf(b, N, wo, wi);
    if (!(p > 0.0))
        return;
    pdf = p;
    weight = gi_brdf_eval(b, N, wo, wi) * cos_i / p;
}
#endif
