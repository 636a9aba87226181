/* Internals of the image files (image_io.c, image_exr.cpp and the OpenImageIO
 * module core/modules/image_oiio.cpp): a file read into memory with all of
 * its channels, before RGBA is chosen from them, and what the two readers
 * (OpenEXR, OpenImageIO) share: the size check, the placement of the data
 * window in the display window, and (C++) the exception guard. Not a
 * public header. */
#ifndef GI_IMAGE_INTERNAL_H
#define GI_IMAGE_INTERNAL_H

#include "gi/image.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct gi_channels {
    uint32_t width, height;
    int count;
    char **names; /* count names, each malloc'd ("" when the file has none) */
    float *data;  /* width * height * count floats (malloc'd), row 0 = top of the display window */
} gi_channels;

/* Frees what the names and data hold (free()), zeroes the struct. */
void gi_channels_release(gi_channels *c);

/* The readers' size check before decoding (image_io.c), against the limits
 * of gi/limits.h: GI_OK for a data window of w x h pixels of nc channels
 * (1 .. GI_MAX_IMAGE_FILE_CHANNELS) within GI_MAX_IMAGE_FILE_PIXELS and
 * GI_MAX_IMAGE_FILE_VALUES, else GI_ERR_INVALID_ARGUMENT "<path>: image
 * size WxH with N channels exceeds the limit of ...". */
gi_result gi_channels_check(const char *path, int64_t w, int64_t h, int nc, gi_error *err);

/* Where a file's data window lies in its display window (both in the
 * file's pixel coordinates; they differ only in cropped files). */
typedef struct gi_channels_window {
    int64_t x, y;                           /* data window origin */
    int64_t full_x, full_y, full_w, full_h; /* display window */
} gi_channels_window;

/* Fills `out` (zeroed by the caller) from a decoded data window: `buf`
 * holds w x h pixels of nc floats, row 0 at the top; names[c] is channel
 * c's name (NULL: ""). The pixels are placed inside the display window,
 * zeros around them, or make the image alone when the display window is
 * absurd (empty or over GI_MAX_IMAGE_FILE_PIXELS). GI_ERR_OUT_OF_MEMORY
 * leaves what was allocated in `out` for gi_channels_release. */
gi_result gi_channels_place(const char *path, const float *buf, int64_t w, int64_t h, int nc,
                            const char *const *names, const gi_channels_window *win,
                            gi_channels *out, gi_error *err);

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

#include <cstring>
#include <exception>
#include <new>
#include <string>

/* The C++ readers' (image_exr.cpp, image_oiio.cpp) one way out: no
 * exception crosses into C. */
namespace gi_image_detail
{

/* Library messages may span lines; gi_error holds one line. */
inline std::string one_line(std::string s, const char *library)
{
    while (!s.empty() && (s.back() == '\n' || s.back() == '\r' || s.back() == ' '))
        s.pop_back();
    for (char &c : s)
        if (c == '\n' || c == '\r')
            c = ' ';
    return s.empty() ? "unknown " + std::string(library) + " error" : s;
}

/* body()'s result, or the exception it threw as an error about `path`
 * (`doing`: "reading", "writing"; `library` names the library in an
 * empty message). */
template <typename Body>
gi_result guarded(const char *path, const char *doing, const char *library, gi_error *err,
                  Body body)
{
    try {
        return body();
    } catch (const std::bad_alloc &) {
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    } catch (const std::exception &e) {
        return gi_error_set(err, GI_ERR_IO, "%s: %s", path, one_line(e.what(), library).c_str());
    } catch (...) {
        return gi_error_set(err, GI_ERR_IO, "%s: unknown exception while %s", path, doing);
    }
}

/* A reader's frame: `out` zeroed, body() run guarded, `out` released on
 * any error. */
template <typename Body>
gi_result guarded_read(const char *path, const char *library, gi_channels *out, gi_error *err,
                       Body body)
{
    std::memset(out, 0, sizeof *out);
    gi_result r = guarded(path, "reading", library, err, body);
    if (r != GI_OK)
        gi_channels_release(out);
    return r;
}

} // namespace gi_image_detail
#endif
#endif
