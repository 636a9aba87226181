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

#include <cstdlib>
#include <cstring>
#include <exception>
#include <new>
#include <string>
#include <vector>

#include "gi/cache.h"
#include "image_internal.h"

namespace
{

/* OpenEXR messages may span lines; gi_error holds one line. */
std::string one_line(std::string s)
{
    while (!s.empty() && (s.back() == '\n' || s.back() == '\r' || s.back() == ' '))
        s.pop_back();
    for (char &c : s)
        if (c == '\n' || c == '\r')
            c = ' ';
    return s.empty() ? std::string("unknown OpenEXR error") : s;
}

template <typename Body> gi_result guarded(const char *path, const char *doing, gi_error *err, Body body)
{
    try {
        return body();
    } catch (const std::bad_alloc &) {
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    } catch (const std::exception &e) {
        return gi_error_set(err, GI_ERR_IO, "%s: %s", path, one_line(e.what()).c_str());
    } catch (...) {
        return gi_error_set(err, GI_ERR_IO, "%s: unknown exception while %s", path, doing);
    }
}

} // namespace

extern "C" {

gi_result gi_exr_write(const char *path, const gi_image *rgba, const gi_image *const *layers,
                       const char *const *names, uint32_t layer_count, gi_error *err)
{
    return guarded(path, "writing", err, [&]() -> gi_result {
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

gi_result gi_exr_read_channels(const char *path, gi_channels *out, gi_error *err)
{
    std::memset(out, 0, sizeof *out);
    gi_result r = guarded(path, "reading", err, [&]() -> gi_result {
        Imf::InputFile file(path, 1);
        const Imf::Header &h = file.header();
        if (h.hasType() && Imf::isDeepData(h.type()))
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                "%s: deep or volume images are not supported", path);
        const Imath::Box2i dw = h.dataWindow(), disp = h.displayWindow();
        const int64_t w = (int64_t)dw.max.x - dw.min.x + 1, hgt = (int64_t)dw.max.y - dw.min.y + 1;
        int nc = 0;
        for (Imf::ChannelList::ConstIterator it = h.channels().begin(); it != h.channels().end(); ++it)
            nc++;
        if (w <= 0 || hgt <= 0 || nc <= 0 || nc > 1024 ||
            (uint64_t)w * (uint64_t)hgt > GI_IMAGE_FILE_MAX_PIXELS)
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                "%s: unsupported image size %lldx%lld with %d channels", path,
                                (long long)w, (long long)hgt, nc);
        /* Order: R, G, B, A first (as OpenImageIO lists them), then the rest
         * in the file's (alphabetical) order. */
        std::vector<std::string> order;
        for (const char *c : {"R", "G", "B", "A"})
            if (h.channels().findChannel(c))
                order.push_back(c);
        for (Imf::ChannelList::ConstIterator it = h.channels().begin(); it != h.channels().end(); ++it) {
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
            fb.insert(order[c], Imf::Slice(Imf::FLOAT, origin + sizeof(float) * c, xs, ys, 1, 1, 0.0));
        file.setFrameBuffer(fb);
        file.readPixels(dw.min.y, dw.max.y);

        /* Place the data window inside the display window (they differ only
         * in cropped EXRs); the data window alone when the display window is
         * absurd. */
        const int64_t fw0 = (int64_t)disp.max.x - disp.min.x + 1, fh0 = (int64_t)disp.max.y - disp.min.y + 1;
        const bool use_full = fw0 > 0 && fh0 > 0 && (uint64_t)fw0 * (uint64_t)fh0 <= GI_IMAGE_FILE_MAX_PIXELS;
        const int64_t fw = use_full ? fw0 : w, fh = use_full ? fh0 : hgt;
        const int64_t ox = use_full ? (int64_t)dw.min.x - disp.min.x : 0;
        const int64_t oy = use_full ? (int64_t)dw.min.y - disp.min.y : 0;
        out->data = (float *)std::calloc((size_t)fw * fh * nc, sizeof(float));
        out->names = (char **)std::calloc((size_t)nc, sizeof(char *));
        if (!out->data || !out->names)
            return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
        out->width = (uint32_t)fw;
        out->height = (uint32_t)fh;
        out->count = nc;
        for (int c = 0; c < nc; c++) {
            out->names[c] = strdup(order[c].c_str());
            if (!out->names[c])
                return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
        }
        for (int64_t y = 0; y < hgt; y++) {
            int64_t ty = y + oy;
            if (ty < 0 || ty >= fh)
                continue;
            for (int64_t x = 0; x < w; x++) {
                int64_t tx = x + ox;
                if (tx < 0 || tx >= fw)
                    continue;
                std::memcpy(&out->data[((size_t)ty * fw + tx) * nc], &buf[((size_t)y * w + x) * nc],
                            sizeof(float) * nc);
            }
        }
        return GI_OK;
    });
    if (r != GI_OK)
        gi_channels_release(out);
    return r;
}

} // extern "C"
