/* Image files: the C API of image.h on top of OpenImageIO. The only C++
 * translation unit that touches OIIO; no exception and no C++ type leaves it.
 *
 * Writes: .exr float32 RGBA (+ "<layer>.R/G/B/A" channels), .pfm float32 RGB
 * (written here by hand: this OIIO build has no PFM writer), .png 8-bit sRGB
 * after gi_tonemap. Every file is encoded in memory and written by the
 * core's one atomic writer (gi_file_write_atomic: a temporary file in the
 * destination directory, every write, fsync and close checked, renamed into
 * place), so readers never see a partial file and a full disk is an error.
 * Reads: anything OIIO reads, channels chosen by name, row 0 = top. */
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "gi/cache.h"
#include "gi/image.h"
#include "gi/tonemap.h"

namespace
{

/* Same bound as gi_image_create (image.c). */
constexpr uint64_t max_pixels = 1ull << 28;

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

/* The extension of the last path component including the dot, or "". */
std::string extension_of(const std::string &path)
{
    size_t slash = path.find_last_of('/');
    size_t dot = path.find_last_of('.');
    if (dot == std::string::npos || (slash != std::string::npos && dot < slash))
        return std::string();
    /* A leading dot names a hidden file, not an extension. */
    if (dot == (slash == std::string::npos ? 0 : slash + 1))
        return std::string();
    return path.substr(dot);
}

std::string lower(std::string s)
{
    for (char &c : s)
        if (c >= 'A' && c <= 'Z')
            c = (char)(c - 'A' + 'a');
    return s;
}

/* Encodes the file in memory with `encode(bytes)`, then hands the bytes to
 * the core's one atomic writer (cache.h: gi_file_write_atomic: a temporary
 * file beside `path`, every write, fsync and close checked, then renamed
 * into place). Encoders do not check the results of their own writes (a
 * full disk gave a 0-byte PNG under its final name); here nothing reaches
 * the disk but through a writer that does. */
template <typename Encode>
gi_result write_atomically(const std::string &path, gi_error *err, Encode encode)
{
    std::vector<unsigned char> bytes;
    gi_result r;
    try {
        r = encode(bytes);
    } catch (const std::bad_alloc &) {
        r = gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "%s: out of memory", path.c_str());
    } catch (const std::exception &e) {
        r = gi_error_set(err, GI_ERR_IO, "%s: %s", path.c_str(), one_line(e.what()).c_str());
    } catch (...) {
        r = gi_error_set(err, GI_ERR_IO, "%s: unknown exception while writing", path.c_str());
    }
    if (r != GI_OK)
        return r;
    return gi_file_write_atomic(path.c_str(), bytes.data(), bytes.size(), err);
}

/* The file OIIO would write at `path` (its format chosen by the extension),
 * in memory. */
gi_result encode_oiio(const std::string &path, const OIIO::ImageSpec &spec, OIIO::TypeDesc data_type,
                      const void *data, std::vector<unsigned char> &bytes, gi_error *err)
{
    std::unique_ptr<OIIO::ImageOutput> out = OIIO::ImageOutput::create(path);
    if (!out)
        return gi_error_set(err, GI_ERR_IO, "%s: %s", path.c_str(),
                            one_line(OIIO::geterror()).c_str());
    if (!out->supports("ioproxy"))
        return gi_error_set(err, GI_ERR_UNSUPPORTED,
                            "%s: this OpenImageIO cannot encode %s in memory", path.c_str(),
                            out->format_name());
    OIIO::Filesystem::IOVecOutput vec(bytes);
    if (!out->set_ioproxy(&vec) || !out->open(path, spec) || !out->write_image(data_type, data) ||
        !out->close())
        return gi_error_set(err, GI_ERR_IO, "%s: %s", path.c_str(),
                            one_line(out->geterror()).c_str());
    return GI_OK;
}

/* PFM (Debevec's portable float map): "PF\n<w> <h>\n<scale>\n", then rows
 * from the BOTTOM of the picture up, RGB float32 each; a negative scale
 * means little-endian samples. */
gi_result encode_pfm(const gi_image *img, std::vector<unsigned char> &bytes)
{
    const uint32_t one = 1;
    unsigned char first_byte;
    std::memcpy(&first_byte, &one, 1);
    const bool little_endian = first_byte == 1;

    char header[64];
    int hn = std::snprintf(header, sizeof header, "PF\n%u %u\n%s\n", img->width, img->height,
                           little_endian ? "-1.0" : "1.0");
    size_t row_bytes = (size_t)img->width * 3 * sizeof(float);
    bytes.resize((size_t)hn + row_bytes * img->height);
    std::memcpy(bytes.data(), header, (size_t)hn);
    std::vector<float> row((size_t)img->width * 3);
    for (uint32_t k = 0; k < img->height; k++) {
        const float *src = img->rgba + (size_t)(img->height - 1 - k) * img->width * 4;
        for (uint32_t x = 0; x < img->width; x++)
            for (int c = 0; c < 3; c++)
                row[(size_t)x * 3 + c] = src[(size_t)x * 4 + c];
        std::memcpy(bytes.data() + hn + row_bytes * k, row.data(), row_bytes);
    }
    return GI_OK;
}

gi_result encode_png(const std::string &path, const gi_image *img, float exposure,
                     std::vector<unsigned char> &bytes, gi_error *err)
{
    size_t n = (size_t)img->width * img->height;
    std::vector<unsigned char> px(n * 3);
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++) {
            float v = gi_tonemap(img->rgba[i * 4 + c], exposure);
            px[i * 3 + c] = (unsigned char)(v * 255.0f + 0.5f);
        }
    OIIO::ImageSpec spec((int)img->width, (int)img->height, 3, OIIO::TypeDesc::UINT8);
    spec.attribute("oiio:ColorSpace", "sRGB");
    return encode_oiio(path, spec, OIIO::TypeDesc::UINT8, px.data(), bytes, err);
}

bool image_ok(const gi_image *img)
{
    return img && img->rgba && img->width > 0 && img->height > 0 &&
           (uint64_t)img->width * img->height <= max_pixels;
}

/* A file read into memory with all of its channels. */
struct channels {
    uint32_t width = 0, height = 0;
    int count = 0;
    std::vector<std::string> names;
    int alpha_channel = -1;
    std::vector<float> data; /* width*height*count, row 0 = top of the display window */
};

/* Reads subimage 0 of `path` as float, placed in its display window. */
bool read_all(const char *path, channels *ch, gi_error *err)
{
    /* Every image read comes here: only a regular file is opened by the
     * decoder. A FIFO would block it and a device (/dev/zero) never ends;
     * O_NONBLOCK keeps the probe itself from blocking on a FIFO. */
    int fd = open(path, O_RDONLY | O_CLOEXEC | O_NONBLOCK);
    if (fd < 0) {
        gi_error_set(err, GI_ERR_IO, "%s: %s", path, std::strerror(errno));
        return false;
    }
    struct stat st;
    int st_rc = fstat(fd, &st);
    close(fd);
    if (st_rc != 0 || !S_ISREG(st.st_mode)) {
        const char *kind = st_rc != 0              ? ""
                           : S_ISDIR(st.st_mode)  ? " (a directory)"
                           : S_ISFIFO(st.st_mode) ? " (a FIFO)"
                           : S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode) ? " (a device)"
                                                                        : "";
        gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: not a regular file%s", path, kind);
        return false;
    }
    /* Keep PNG/TIFF alpha as stored; OIIO would premultiply by default. */
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    std::unique_ptr<OIIO::ImageInput> in = OIIO::ImageInput::open(path, &config);
    if (!in) {
        gi_error_set(err, GI_ERR_IO, "%s: %s", path, one_line(OIIO::geterror()).c_str());
        return false;
    }
    const OIIO::ImageSpec &spec = in->spec();
    if (spec.deep || spec.depth != 1) {
        gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: deep or volume images are not supported",
                     path);
        return false;
    }
    if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0 || spec.nchannels > 1024 ||
        (uint64_t)spec.width * (uint64_t)spec.height > max_pixels) {
        gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                     "%s: unsupported image size %dx%d with %d channels", path, spec.width,
                     spec.height, spec.nchannels);
        return false;
    }
    const int nc = spec.nchannels;
    std::vector<float> buf((size_t)spec.width * spec.height * nc);
    if (!in->read_image(0, 0, 0, nc, OIIO::TypeDesc::FLOAT, buf.data())) {
        gi_error_set(err, GI_ERR_IO, "%s: %s", path, one_line(in->geterror()).c_str());
        return false;
    }
    in->close();

    /* Place the data window inside the display window (they differ only in
     * cropped EXRs); fall back to the data window when the display window is
     * absurd. */
    bool use_full = spec.full_width > 0 && spec.full_height > 0 &&
                    (uint64_t)spec.full_width * (uint64_t)spec.full_height <= max_pixels;
    int fw = use_full ? spec.full_width : spec.width;
    int fh = use_full ? spec.full_height : spec.height;
    int ox = use_full ? spec.x - spec.full_x : 0;
    int oy = use_full ? spec.y - spec.full_y : 0;
    ch->width = (uint32_t)fw;
    ch->height = (uint32_t)fh;
    ch->count = nc;
    ch->alpha_channel = spec.alpha_channel;
    ch->names.clear();
    for (int c = 0; c < nc; c++)
        ch->names.push_back(c < (int)spec.channelnames.size() ? spec.channelnames[c]
                                                              : std::string());
    if (fw == spec.width && fh == spec.height && ox == 0 && oy == 0) {
        ch->data.swap(buf);
        return true;
    }
    ch->data.assign((size_t)fw * fh * nc, 0.0f);
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
    return true;
}

int find_channel(const channels &ch, const std::string &name)
{
    for (int c = 0; c < ch.count; c++)
        if (ch.names[c] == name)
            return c;
    return -1;
}

/* Builds RGBA from channel indices; src[3] < 0 means alpha 1. */
gi_image *gather(const channels &ch, const int src[4], const char *path, gi_error *err)
{
    gi_image *img = gi_image_create(ch.width, ch.height);
    if (!img) {
        gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "%s: out of memory for %ux%u pixels", path,
                     ch.width, ch.height);
        return nullptr;
    }
    size_t n = (size_t)ch.width * ch.height;
    for (size_t i = 0; i < n; i++) {
        const float *p = &ch.data[i * ch.count];
        float *q = img->rgba + i * 4;
        for (int c = 0; c < 3; c++)
            q[c] = p[src[c]];
        q[3] = src[3] >= 0 ? p[src[3]] : 1.0f;
    }
    return img;
}

template <typename Body> gi_image *guarded_read(const char *path, gi_error *err, Body body)
{
    try {
        return body();
    } catch (const std::bad_alloc &) {
        gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    } catch (const std::exception &e) {
        gi_error_set(err, GI_ERR_IO, "%s: %s", path, one_line(e.what()).c_str());
    } catch (...) {
        gi_error_set(err, GI_ERR_IO, "%s: unknown exception while reading", path);
    }
    return nullptr;
}

} // namespace

extern "C" {

gi_result gi_image_write(const char *path, const gi_image *img, const gi_image_write_opts *opts,
                         gi_error *err)
{
    if (!path || !*path)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "image write: empty file name");
    if (!image_ok(img))
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: invalid image to write", path);
    float exposure = opts ? opts->exposure : 0.0f;
    try {
        std::string p(path);
        std::string ext = extension_of(p);
        std::string kind = lower(ext);
        if (kind == ".exr") {
            OIIO::ImageSpec spec((int)img->width, (int)img->height, 4, OIIO::TypeDesc::FLOAT);
            spec.attribute("compression", "zip");
            return write_atomically(p, err, [&](std::vector<unsigned char> &bytes) {
                return encode_oiio(p, spec, OIIO::TypeDesc::FLOAT, img->rgba, bytes, err);
            });
        }
        if (kind == ".pfm")
            return write_atomically(
                p, err, [&](std::vector<unsigned char> &bytes) { return encode_pfm(img, bytes); });
        if (kind == ".png")
            return write_atomically(p, err, [&](std::vector<unsigned char> &bytes) {
                return encode_png(p, img, exposure, bytes, err);
            });
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "%s: unsupported image format '%s' (use .exr, .pfm or .png)", path,
                            ext.c_str());
    } catch (const std::bad_alloc &) {
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    } catch (const std::exception &e) {
        return gi_error_set(err, GI_ERR_IO, "%s: %s", path, one_line(e.what()).c_str());
    } catch (...) {
        return gi_error_set(err, GI_ERR_IO, "%s: unknown exception while writing", path);
    }
}

gi_result gi_image_write_exr_layers(const char *path, const gi_image *rgba,
                                    const gi_image *const *layers, const char *const *names,
                                    uint32_t layer_count, gi_error *err)
{
    if (!path || !*path)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "image write: empty file name");
    if (!image_ok(rgba))
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: invalid image to write", path);
    if (layer_count > 0 && (!layers || !names))
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: layers or names missing", path);
    try {
        std::string p(path);
        std::string ext = extension_of(p);
        if (lower(ext) != ".exr")
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                "%s: layered images must be .exr, not '%s'", path, ext.c_str());
        std::vector<std::string> channel_names = {"R", "G", "B", "A"};
        for (uint32_t l = 0; l < layer_count; l++) {
            if (!image_ok(layers[l]) || layers[l]->width != rgba->width ||
                layers[l]->height != rgba->height)
                return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                    "%s: layer %u is missing or not %ux%u", path, l, rgba->width,
                                    rgba->height);
            if (!names[l] || !*names[l])
                return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: layer %u has no name", path,
                                    l);
            for (uint32_t k = 0; k < l; k++)
                if (std::strcmp(names[k], names[l]) == 0)
                    return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                        "%s: layer name '%s' used twice", path, names[l]);
            for (const char *c : {".R", ".G", ".B", ".A"})
                channel_names.push_back(std::string(names[l]) + c);
        }
        const int nc = 4 + 4 * (int)layer_count;
        size_t n = (size_t)rgba->width * rgba->height;
        std::vector<float> px(n * nc);
        for (size_t i = 0; i < n; i++) {
            float *q = &px[i * nc];
            std::memcpy(q, rgba->rgba + i * 4, 4 * sizeof(float));
            for (uint32_t l = 0; l < layer_count; l++)
                std::memcpy(q + 4 + 4 * l, layers[l]->rgba + i * 4, 4 * sizeof(float));
        }
        OIIO::ImageSpec spec((int)rgba->width, (int)rgba->height, nc, OIIO::TypeDesc::FLOAT);
        spec.channelnames = channel_names;
        spec.alpha_channel = 3;
        spec.attribute("compression", "zip");
        return write_atomically(p, err, [&](std::vector<unsigned char> &bytes) {
            return encode_oiio(p, spec, OIIO::TypeDesc::FLOAT, px.data(), bytes, err);
        });
    } catch (const std::bad_alloc &) {
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    } catch (const std::exception &e) {
        return gi_error_set(err, GI_ERR_IO, "%s: %s", path, one_line(e.what()).c_str());
    } catch (...) {
        return gi_error_set(err, GI_ERR_IO, "%s: unknown exception while writing", path);
    }
}

gi_image *gi_image_read(const char *path, gi_error *err)
{
    if (!path || !*path) {
        gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "image read: empty file name");
        return nullptr;
    }
    return guarded_read(path, err, [&]() -> gi_image * {
        channels ch;
        if (!read_all(path, &ch, err))
            return nullptr;
        int src[4];
        int r = find_channel(ch, "R"), g = find_channel(ch, "G"), b = find_channel(ch, "B");
        if (r >= 0 && g >= 0 && b >= 0) {
            src[0] = r, src[1] = g, src[2] = b, src[3] = find_channel(ch, "A");
        } else if (ch.count == 1) {
            src[0] = src[1] = src[2] = 0, src[3] = -1;
        } else if (ch.count == 2) { /* grey + alpha */
            src[0] = src[1] = src[2] = 0, src[3] = 1;
        } else {
            src[0] = 0, src[1] = 1, src[2] = 2, src[3] = ch.count >= 4 ? 3 : -1;
        }
        return gather(ch, src, path, err);
    });
}

gi_image *gi_image_read_layer(const char *path, const char *name, gi_error *err)
{
    if (!path || !*path || !name || !*name) {
        gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "image read: empty file or layer name");
        return nullptr;
    }
    return guarded_read(path, err, [&]() -> gi_image * {
        channels ch;
        if (!read_all(path, &ch, err))
            return nullptr;
        std::string prefix = std::string(name) + ".";
        int r = find_channel(ch, prefix + "R"), g = find_channel(ch, prefix + "G");
        int b = find_channel(ch, prefix + "B"), a = find_channel(ch, prefix + "A");
        int src[4];
        if (r >= 0 && g >= 0 && b >= 0) {
            src[0] = r, src[1] = g, src[2] = b, src[3] = a;
        } else {
            /* A single-channel layer ("depth" or "depth.Y") reads as grey. */
            int y = find_channel(ch, prefix + "Y");
            if (y < 0)
                y = find_channel(ch, name);
            if (y < 0) {
                std::string list;
                for (const std::string &s : ch.names)
                    list += (list.empty() ? "" : ", ") + s;
                gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: no layer '%s' (channels: %s)", path,
                             name, list.c_str());
                return nullptr;
            }
            src[0] = src[1] = src[2] = y, src[3] = a;
        }
        return gather(ch, src, path, err);
    });
}

} // extern "C"
