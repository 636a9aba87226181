/* Separable filtering with clamped or renormalised borders (see filter.h). */
#include "filter.h"

#include <assert.h>
#include <stddef.h>

static inline int64_t clampi(int64_t v, int64_t lo, int64_t hi)
{
    return v < lo ? lo : v > hi ? hi : v;
}

/* One 1-D pass over n samples spaced `stride` apart. */
static void pass(const double *in, double *out, int64_t n, int64_t stride, const double *k, int r,
                 gi_border border)
{
    double ksum = 0.0;
    for (int i = -r; i <= r; i++)
        ksum += k[i + r];
    for (int64_t x = 0; x < n; x++) {
        double acc = 0.0;
        if (x - r >= 0 && x + r < n) { /* interior: no border rule needed */
            for (int i = -r; i <= r; i++)
                acc += k[i + r] * in[(x + i) * stride];
        } else if (border == GI_BORDER_CLAMP) {
            for (int i = -r; i <= r; i++)
                acc += k[i + r] * in[clampi(x + i, 0, n - 1) * stride];
        } else {
            double wsum = 0.0;
            for (int i = -r; i <= r; i++)
                if (x + i >= 0 && x + i < n) {
                    acc += k[i + r] * in[(x + i) * stride];
                    wsum += k[i + r];
                }
            acc = wsum != 0.0 ? acc * (ksum / wsum) : 0.0;
        }
        out[x * stride] = acc;
    }
}

void gi_filter_separable(const double *in, double *out, double *tmp, uint32_t w, uint32_t h,
                         const double *kx, int rx, const double *ky, int ry, gi_border border)
{
    assert(in && out && tmp && tmp != in && tmp != out && kx && ky && rx >= 0 && ry >= 0);
    for (uint32_t y = 0; y < h; y++)
        pass(in + (size_t)y * w, tmp + (size_t)y * w, w, 1, kx, rx, border);
    for (uint32_t x = 0; x < w; x++)
        pass(tmp + x, out + x, h, w, ky, ry, border);
}
