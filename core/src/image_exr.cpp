/* EXR files through OpenEXR (image_internal.h): the format every run writes
 * and every reference and environment map is read from, kept in the core
 * because OpenEXR is a handful of libraries where OpenImageIO is hundreds
 * (start-up time of every process; gi/module.h). No exception and no C++
 * type leaves this file. */
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfPartType.h>
#include <ImfStdIO.h>
#include <ImfVersion.h>

#include <fstream>
#include <string>
#include <vector>

#include "gi/cache.h"
#include "image_internal.h"

using gi_image_detail::guarded;
using gi_image_detail::guarded_read;

extern "C" {

gi_result gi_exr_write(const char *path, const gi_image *rgba, const gi_image *const *layers,
                       const char *const *names, uint32_t layer_count, gi_error *err)
{
    return guarded(path, "writing", "OpenEXR", err, [&]() -> gi_result {
        Imf::Header header((int)rgba->width, (int)rgba->height);
        header.compression() = Imf::ZIP_COMPRESSION;
        Imf::FrameBuffer fb;
        const size_t xs = 4 * sizeof(float), ys = xs * rgba->width;
        std::vector<std::string> channel_names;
        std::vector<const float *> bases;
        static const char *const rgba_names[4] = {"R", "G", "B", "A"};
        for (int c = 0; c < 4; c++) {
            channel_names.push_back(rgba_names[c]);
            bases.push_back(rgba->rgba + c);
        }
        for (uint32_t l = 0; l < layer_count; l++)
            for (int c = 0; c < 4; c++) {
                channel_names.push_back(std::string(names[l]) + "." + rgba_names[c]);
                bases.push_back(layers[l]->rgba + c);
            }
        for (size_t k = 0; k < channel_names.size(); k++) {
            header.channels().insert(channel_names[k], Imf::Channel(Imf::FLOAT));
            fb.insert(channel_names[k],
                      Imf::Slice(Imf::FLOAT, (char *)const_cast<float *>(bases[k]), xs, ys));
        }
        Imf::StdOSStream os;
        {
            Imf::OutputFile file(os, header, 1);
            file.setFrameBuffer(fb);
            file.writePixels((int)rgba->height);
        }
        std::string bytes = os.str();
        return gi_file_write_atomic(path, bytes.data(), bytes.size(), err);
    });
}

/* The first header's windows and channel count checked against the limits
 * of gi/limits.h before the library opens the file (the display window
 * only places the data, gi_channels_place): Imf::InputFile sizes
 * its line buffers from the header, so a 600-byte file declaring
 * 8,000,000 x 32 pixels cost gigabytes before any check of ours ran. A
 * header the library cannot parse is left to it (its message says why). */
static gi_result check_exr_header(const char *path, gi_error *err)
{
    std::ifstream f(path, std::ios::binary);
    char mv[8];
    if (!f.read(mv, sizeof mv) || !Imf::isImfMagic(mv))
        return GI_OK;
    int version = (int)((unsigned char)mv[4] | (unsigned char)mv[5] << 8 |
                        (unsigned char)mv[6] << 16 | (unsigned)(unsigned char)mv[7] << 24);
    Imf::StdIFStream is(f, path);
    Imf::Header h;
    h.readFrom(is, version);
    const Imath::Box2i dw = h.dataWindow();
    int nc = 0;
    for (Imf::ChannelList::ConstIterator it = h.channels().begin(); it != h.channels().end(); ++it)
        nc++;
    return gi_channels_check(path, (int64_t)dw.max.x - dw.min.x + 1,
                             (int64_t)dw.max.y - dw.min.y + 1, nc, err);
}

gi_result gi_exr_read_channels(const char *path, gi_channels *out, gi_error *err)
{
    return guarded_read(path, "OpenEXR", out, err, [&]() -> gi_result {
        gi_result checked = check_exr_header(path, err);
        if (checked != GI_OK)
            return checked;
        Imf::InputFile file(path, 1);
        const Imf::Header &h = file.header();
        if (h.hasType() && Imf::isDeepData(h.type()))
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                "%s: deep or volume images are not supported", path);
        const Imath::Box2i dw = h.dataWindow(), disp = h.displayWindow();
        const int64_t w = (int64_t)dw.max.x - dw.min.x + 1, hgt = (int64_t)dw.max.y - dw.min.y + 1;
        int nc = 0;
        for (Imf::ChannelList::ConstIterator it = h.channels().begin(); it != h.channels().end();
             ++it)
            nc++;
        gi_result ok = gi_channels_check(path, w, hgt, nc, err);
        if (ok != GI_OK)
            return ok;
        /* Order: R, G, B, A first (as OpenImageIO lists them), then the rest
         * in the file's (alphabetical) order. */
        std::vector<std::string> order;
        for (const char *c : {"R", "G", "B", "A"})
            if (h.channels().findChannel(c))
                order.push_back(c);
        for (Imf::ChannelList::ConstIterator it = h.channels().begin(); it != h.channels().end();
             ++it) {
            std::string n = it.name();
            if (n != "R" && n != "G" && n != "B" && n != "A")
                order.push_back(n);
        }
        std::vector<float> buf((size_t)w * hgt * nc);
        Imf::FrameBuffer fb;
        const size_t xs = sizeof(float) * nc, ys = xs * (size_t)w;
        /* OpenEXR addresses the slice with absolute data-window coordinates. */
        char *origin = (char *)buf.data() - (ptrdiff_t)dw.min.x * (ptrdiff_t)xs -
                       (ptrdiff_t)dw.min.y * (ptrdiff_t)ys;
        for (int c = 0; c < nc; c++)
            fb.insert(order[c],
                      Imf::Slice(Imf::FLOAT, origin + sizeof(float) * c, xs, ys, 1, 1, 0.0));
        file.setFrameBuffer(fb);
        file.readPixels(dw.min.y, dw.max.y);

        std::vector<const char *> names;
        for (const std::string &n : order)
            names.push_back(n.c_str());
        const gi_channels_window win = {dw.min.x,
                                        dw.min.y,
                                        disp.min.x,
                                        disp.min.y,
                                        (int64_t)disp.max.x - disp.min.x + 1,
                                        (int64_t)disp.max.y - disp.min.y + 1};
        return gi_channels_place(path, buf.data(), w, hgt, nc, names.data(), &win, out, err);
    });
}

} // extern "C"
