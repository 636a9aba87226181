/* Linear RGBA32F images and their files: EXR through OpenEXR, PNG written
 * through libpng, PFM by hand; every other format read through OpenImageIO,
 * loaded as a module on the first such read (gi/module.h).
 *
 * gi_image_create / gi_image_read return an image you own; free it with
 * gi_image_free. Pixels are row-major, row 0 = top of the picture, 4 floats a
 * pixel. Writing picks the format from the file name:
 *   .exr  float32 RGBA (extra named channels with gi_image_write_exr_layers)
 *   .pfm  float32 RGB (alpha dropped)
 *   .png  8-bit sRGB RGB after tonemapping (exposure in stops; see tonemap.h;
 *         alpha dropped)
 * Writes go to a temporary name in the same directory and are renamed into
 * place, so a reader never sees a half-written file.
 */
#ifndef GI_IMAGE_H
#define GI_IMAGE_H

#include "gi/common.h"
#include "gi/limits.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct gi_image {
    uint32_t width, height;
    float *rgba;
} gi_image;

/* Zero-filled; NULL when a side is 0, the image is absurdly large (more than
 * 2^28 pixels) or memory runs out. */
gi_image *gi_image_create(uint32_t width, uint32_t height);
void gi_image_free(gi_image *img);
/* Reads EXR (OpenEXR) and any format OpenImageIO knows (the module
 * gi_image_oiio.so; without it such a read fails with GI_ERR_UNSUPPORTED
 * and a line naming the module); 1-3 channel files are expanded to
 * RGBA (grey to RGB, alpha 1; 2 channels are grey + alpha). Channels named
 * R, G, B (and A) are used wherever they are in the file. Values are as
 * stored: an 8-bit sRGB PNG reads as its display values in [0, 1], not
 * linearised. NULL + err ("path: reason") on failure. */
gi_image *gi_image_read(const char *path, gi_error *err);

typedef struct gi_image_write_opts {
    float exposure; /* stops, PNG only; 0 = none */
} gi_image_write_opts;

/* opts may be NULL (defaults). Any other extension is an error
 * (GI_ERR_INVALID_ARGUMENT); messages read "path: reason". */
gi_result gi_image_write(const char *path, const gi_image *img, const gi_image_write_opts *opts,
                         gi_error *err);

/* An EXR with extra float channels beside RGBA, e.g. a variance image:
 * names[i] is the prefix of layer i ("variance" gives variance.R/G/B/A). */
gi_result gi_image_write_exr_layers(const char *path, const gi_image *rgba,
                                    const gi_image *const *layers, const char *const *names,
                                    uint32_t layer_count, gi_error *err);
/* Reads layer `name` (e.g. "variance") of such an EXR: channels name.R/G/B
 * (name.A optional), or a single channel name.Y or name read as grey.
 * NULL + err if absent. */
gi_image *gi_image_read_layer(const char *path, const char *name, gi_error *err);

/* Mean of each channel over all pixels (double accumulation). */
void gi_image_mean(const gi_image *img, double out[4]);
/* Number of pixels with a NaN or Inf in R, G or B. */
uint64_t gi_image_count_nonfinite(const gi_image *img);
/* Flip rows in place (GL readback is bottom-up). */
void gi_image_flip_rows(gi_image *img);

#ifdef __cplusplus
}
#endif
#endif
