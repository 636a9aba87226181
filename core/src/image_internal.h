/* Internals of the image files (image_io.c, image_exr.cpp and the OpenImageIO
 * module core/modules/image_oiio.cpp): a file read into memory with all of
 * its channels, before RGBA is chosen from them. Not a public header. */
#ifndef GI_IMAGE_INTERNAL_H
#define GI_IMAGE_INTERNAL_H

#include "gi/image.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Same bound as gi_image_create (image.c). */
#define GI_IMAGE_FILE_MAX_PIXELS (1ull << 28)

typedef struct gi_channels {
    uint32_t width, height;
    int count;
    char **names; /* count names, each malloc'd ("" when the file has none) */
    float *data;  /* width * height * count floats (malloc'd), row 0 = top of the display window */
} gi_channels;

/* Frees what the names and data hold (free()), zeroes the struct. */
void gi_channels_release(gi_channels *c);

/* EXR through OpenEXR (image_exr.cpp): every channel as float, placed in the
 * display window (the data window when the display window is absurd). */
gi_result gi_exr_read_channels(const char *path, gi_channels *out, gi_error *err);
/* Float32 RGBA plus "<name>.R/G/B/A" per layer, ZIP compression, written
 * through gi_file_write_atomic. Arguments already checked by the caller. */
gi_result gi_exr_write(const char *path, const gi_image *rgba, const gi_image *const *layers,
                       const char *const *names, uint32_t layer_count, gi_error *err);

/* The OpenImageIO module's entry point (gi_image_oiio.so): any format OIIO
 * reads, subimage 0, every channel as float. */
typedef gi_result (*gi_oiio_read_channels_fn)(const char *path, gi_channels *out, gi_error *err);
#define GI_OIIO_MODULE "gi_image_oiio.so"
#define GI_OIIO_READ_SYMBOL "gi_oiio_read_channels"

#ifdef __cplusplus
}
#endif
#endif
