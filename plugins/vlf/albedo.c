/* The albedo of the vlf method's glossy lobe (the normalised Phong lobe of
 * core brdf.h) over the angle of incidence: its fall-off toward grazing,
 * which the non-diffuse reflection of §3.4 divides by (see vlf_field.h). */
#include "vlf_field.h"

#include <math.h>

double vlf_phong_albedo(float n, float cos_t)
{
    /* (n + 2) / (2 pi) * integral over the hemisphere of cos^n(alpha)
     * cos(theta_o) d omega_o, alpha the angle to the reflected direction:
     * with u = cos^(n+1) alpha, (n + 2) / (n + 1) times the mean of
     * max(0, cos theta_o) over u in [0, 1] and phi (a 64 x 64 midpoint rule) */
    const int K = 64;
    double ct = fmin(1.0, fabs((double)cos_t)), st = sqrt(fmax(0.0, 1.0 - ct * ct)), sum = 0.0;
    for (int a = 0; a < K; a++) {
        double ca = pow(((double)a + 0.5) / K, 1.0 / ((double)n + 1.0)),
               sa = sqrt(fmax(0.0, 1.0 - ca * ca));
        for (int b = 0; b < K; b++) {
            double co = ca * ct + sa * st * cos(2.0 * GI_PI * ((double)b + 0.5) / K);
            if (co > 0.0)
                sum += co;
        }
    }
    return ((double)n + 2.0) / ((double)n + 1.0) * sum / (double)(K * K);
}

float vlf_phong_albedo_at(const vlf_face *fc, float cos_t)
{
    float x = fminf(1.0f, fmaxf(0.0f, cos_t)) * (float)(VLF_ALBEDO_TABLE - 1);
    int k = (int)x;
    if (k >= VLF_ALBEDO_TABLE - 1)
        return fc->albedo[VLF_ALBEDO_TABLE - 1];
    float t = x - (float)k;
    return fc->albedo[k] * (1.0f - t) + fc->albedo[k + 1] * t;
}
