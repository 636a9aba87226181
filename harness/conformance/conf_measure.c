/* gibench conformance: what the checks measure in an image (docs/conformance.md): its mean, NaN,
 * Inf and negative pixels, and the relative difference of two images. */
#include "conf.h"

#include <math.h>
#include <stdio.h>

conf_img_stats conf_measure(const gi_image *img)
{
    conf_img_stats st = {0, 0, 0};
    size_t n = (size_t)img->width * img->height, used = 0;
    double sum = 0.0;
    for (size_t i = 0; i < n; i++) {
        const float *p = &img->rgba[4 * i];
        if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2])) {
            st.nonfinite++;
            continue;
        }
        if (p[0] < 0.0f || p[1] < 0.0f || p[2] < 0.0f)
            st.negative++;
        sum += (p[0] + p[1] + p[2]) / 3.0;
        used++;
    }
    st.mean = used ? sum / (double)used : 0.0;
    return st;
}

/* Mean absolute difference over RGB relative to the mean of b (same size). */
double conf_rel_diff(const gi_image *a, const gi_image *b)
{
    size_t n = (size_t)a->width * a->height;
    double d = 0.0, m = 0.0;
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++) {
            d += fabs((double)a->rgba[4 * i + c] - (double)b->rgba[4 * i + c]);
            m += fabs((double)b->rgba[4 * i + c]);
        }
    return d / (m + 1e-12);
}

/* "finite and non-negative", else a reason. */
int conf_sane(const gi_image *img, char *why, size_t size)
{
    conf_img_stats st = conf_measure(img);
    if (st.nonfinite) {
        snprintf(why, size, "%llu of %u pixels are NaN or Inf", (unsigned long long)st.nonfinite,
                 img->width * img->height);
        return 0;
    }
    if (st.negative) {
        snprintf(why, size, "%llu of %u pixels are negative", (unsigned long long)st.negative,
                 img->width * img->height);
        return 0;
    }
    return 1;
}
