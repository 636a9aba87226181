/* The OpenImageIO module (gi_image_oiio.so, gi/module.h): reads any image
 * format OIIO knows, for the files the core does not read itself (image_io.c
 * reads EXR through OpenEXR). Loaded only when such a file is read, so that
 * OIIO's hundreds of shared libraries cost nothing to the processes that
 * never need them. No exception and no C++ type leaves this file. */
#include <OpenImageIO/imageio.h>

#include <memory>
#include <string>
#include <vector>

#include "../src/image_internal.h"

namespace
{

/* Reads subimage 0 of `path` as float, placed in its display window. The
 * caller (image_io.c) has checked that it is a regular file. */
gi_result read_all(const char *path, gi_channels *ch, gi_error *err)
{
    /* Keep PNG/TIFF alpha as stored; OIIO would premultiply by default. */
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    std::unique_ptr<OIIO::ImageInput> in = OIIO::ImageInput::open(path, &config);
    if (!in)
        return gi_error_set(err, GI_ERR_IO, "%s: %s", path,
                            gi_image_detail::one_line(OIIO::geterror(), "OpenImageIO").c_str());
    const OIIO::ImageSpec &spec = in->spec();
    if (spec.deep || spec.depth != 1)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "%s: deep or volume images are not supported", path);
    const int nc = spec.nchannels;
    gi_result ok = gi_channels_check(path, spec.width, spec.height, nc, err);
    if (ok != GI_OK)
        return ok;
    std::vector<float> buf((size_t)spec.width * spec.height * nc);
    if (!in->read_image(0, 0, 0, nc, OIIO::TypeDesc::FLOAT, buf.data()))
        return gi_error_set(err, GI_ERR_IO, "%s: %s", path,
                            gi_image_detail::one_line(in->geterror(), "OpenImageIO").c_str());
    in->close();
    std::vector<const char *> names;
    for (int c = 0; c < nc; c++)
        names.push_back(c < (int)spec.channelnames.size() ? spec.channelnames[c].c_str() : "");
    const gi_channels_window win = {spec.x,      spec.y,          spec.full_x,
                                    spec.full_y, spec.full_width, spec.full_height};
    return gi_channels_place(path, buf.data(), spec.width, spec.height, nc, names.data(), &win, ch,
                             err);
}

} // namespace

extern "C" __attribute__((visibility("default"))) gi_result
gi_oiio_read_channels(const char *path, gi_channels *out, gi_error *err)
{
    return gi_image_detail::guarded_read(path, "OpenImageIO", out, err,
                                         [&]() { return read_all(path, out, err); });
}
