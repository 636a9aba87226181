/* The OpenImageIO module (gi_image_oiio.so, gi/module.h): reads any image
 * format OIIO knows, for the files the core does not read itself (image_io.c
 * reads EXR through OpenEXR). Loaded only when such a file is read, so that
 * OIIO's hundreds of shared libraries cost nothing to the processes that
 * never need them. No exception and no C++ type leaves this file. */
#include <OpenImageIO/imageio.h>

#include <cstdlib>
#include <cstring>
#include <exception>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "../src/image_internal.h"

namespace
{

/* OIIO messages may span lines; gi_error holds one line. */
std::string one_line(std::string s)
{
    while (!s.empty() && (s.back() == '\n' || s.back() == '\r' || s.back() == ' '))
        s.pop_back();
    for (char &c : s)
        if (c == '\n' || c == '\r')
            c = ' ';
    return s.empty() ? std::string("unknown OpenImageIO error") : s;
}

/* Reads subimage 0 of `path` as float, placed in its display window. The
 * caller (image_io.c) has checked that it is a regular file. */
gi_result read_all(const char *path, gi_channels *ch, gi_error *err)
{
    /* Keep PNG/TIFF alpha as stored; OIIO would premultiply by default. */
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    std::unique_ptr<OIIO::ImageInput> in = OIIO::ImageInput::open(path, &config);
    if (!in)
        return gi_error_set(err, GI_ERR_IO, "%s: %s", path, one_line(OIIO::geterror()).c_str());
    const OIIO::ImageSpec &spec = in->spec();
    if (spec.deep || spec.depth != 1)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "%s: deep or volume images are not supported", path);
    if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0 || spec.nchannels > 1024 ||
        (uint64_t)spec.width * (uint64_t)spec.height > GI_IMAGE_FILE_MAX_PIXELS)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "%s: unsupported image size %dx%d with %d channels", path, spec.width,
                            spec.height, spec.nchannels);
    const int nc = spec.nchannels;
    std::vector<float> buf((size_t)spec.width * spec.height * nc);
    if (!in->read_image(0, 0, 0, nc, OIIO::TypeDesc::FLOAT, buf.data()))
        return gi_error_set(err, GI_ERR_IO, "%s: %s", path, one_line(in->geterror()).c_str());
    in->close();

    /* Place the data window inside the display window (they differ only in
     * cropped files); fall back to the data window when the display window
     * is absurd. */
    bool use_full = spec.full_width > 0 && spec.full_height > 0 &&
                    (uint64_t)spec.full_width * (uint64_t)spec.full_height <= GI_IMAGE_FILE_MAX_PIXELS;
    int fw = use_full ? spec.full_width : spec.width;
    int fh = use_full ? spec.full_height : spec.height;
    int ox = use_full ? spec.x - spec.full_x : 0;
    int oy = use_full ? spec.y - spec.full_y : 0;
    ch->data = (float *)std::calloc((size_t)fw * fh * nc, sizeof(float));
    ch->names = (char **)std::calloc((size_t)nc, sizeof(char *));
    if (!ch->data || !ch->names)
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    ch->width = (uint32_t)fw;
    ch->height = (uint32_t)fh;
    ch->count = nc;
    for (int c = 0; c < nc; c++) {
        ch->names[c] = strdup(c < (int)spec.channelnames.size() ? spec.channelnames[c].c_str() : "");
        if (!ch->names[c])
            return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    }
    for (int y = 0; y < spec.height; y++) {
        int ty = y + oy;
        if (ty < 0 || ty >= fh)
            continue;
        for (int x = 0; x < spec.width; x++) {
            int tx = x + ox;
            if (tx < 0 || tx >= fw)
                continue;
            std::memcpy(&ch->data[((size_t)ty * fw + tx) * nc],
                        &buf[((size_t)y * spec.width + x) * nc], sizeof(float) * nc);
        }
    }
    return GI_OK;
}

} // namespace

extern "C" __attribute__((visibility("default"))) gi_result
gi_oiio_read_channels(const char *path, gi_channels *out, gi_error *err)
{
    std::memset(out, 0, sizeof *out);
    gi_result r;
    try {
        r = read_all(path, out, err);
    } catch (const std::bad_alloc &) {
        r = gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    } catch (const std::exception &e) {
        r = gi_error_set(err, GI_ERR_IO, "%s: %s", path, one_line(e.what()).c_str());
    } catch (...) {
        r = gi_error_set(err, GI_ERR_IO, "%s: unknown exception while reading", path);
    }
    if (r != GI_OK)
        gi_channels_release(out);
    return r;
}
