/* Linear RGBA32F images in memory: allocation and the small whole-image
 * statistics the harness and the tests use. File I/O is in image_io.c. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gi/image.h"

gi_image *gi_image_create(uint32_t width, uint32_t height)
{
    uint64_t pixels = (uint64_t)width * height;
    if (width == 0 || height == 0 || pixels > GI_MAX_IMAGE_ALLOC_PIXELS)
        return NULL;
    gi_image *img = malloc(sizeof *img);
    if (!img)
        return NULL;
    img->rgba = calloc((size_t)pixels * 4, sizeof(float));
    if (!img->rgba) {
        free(img);
        return NULL;
    }
    img->width = width;
    img->height = height;
    return img;
}

void gi_image_free(gi_image *img)
{
    if (!img)
        return;
    free(img->rgba);
    free(img);
}

void gi_image_mean(const gi_image *img, double out[4])
{
    double sum[4] = {0, 0, 0, 0};
    size_t n = (size_t)img->width * img->height;
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 4; c++)
            sum[c] += img->rgba[i * 4 + c];
    for (int c = 0; c < 4; c++)
        out[c] = n ? sum[c] / (double)n : 0.0;
}

uint64_t gi_image_count_nonfinite(const gi_image *img)
{
    uint64_t count = 0;
    size_t n = (size_t)img->width * img->height;
    for (size_t i = 0; i < n; i++) {
        const float *p = img->rgba + i * 4;
        if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2]))
            count++;
    }
    return count;
}

void gi_image_flip_rows(gi_image *img)
{
    size_t row = (size_t)img->width * 4;
    float *tmp = malloc(row * sizeof(float));
    if (tmp) {
        for (uint32_t y = 0; y < img->height / 2; y++) {
            float *a = img->rgba + (size_t)y * row;
            float *b = img->rgba + (size_t)(img->height - 1 - y) * row;
            memcpy(tmp, a, row * sizeof(float));
            memcpy(a, b, row * sizeof(float));
            memcpy(b, tmp, row * sizeof(float));
        }
        free(tmp);
        return;
    }
    /* No scratch row to be had: swap element by element. */
    for (uint32_t y = 0; y < img->height / 2; y++) {
        float *a = img->rgba + (size_t)y * row;
        float *b = img->rgba + (size_t)(img->height - 1 - y) * row;
        for (size_t i = 0; i < row; i++) {
            float t = a[i];
            a[i] = b[i];
            b[i] = t;
        }
    }
}
