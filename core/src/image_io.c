/* Image files (gi/image.h). The formats a run writes and reads are handled
 * here with light libraries: EXR through OpenEXR (image_exr.cpp), PNG
 * writing through libpng, PFM by hand. Reading any other format goes to
 * OpenImageIO, which is loaded as a module (gi_image_oiio.so, gi/module.h)
 * only when such a file is read, because linking it costs every process
 * hundreds of shared libraries at start-up.
 *
 * Every file is encoded in memory and written by the core's one atomic
 * writer (gi_file_write_atomic: a temporary file in the destination
 * directory, every write, fsync and close checked, renamed into place), so
 * readers never see a partial file and a full disk is an error. */
#define _POSIX_C_SOURCE 200809L
#include "image_internal.h"

#include "gi/cache.h"
#include "gi/module.h"
#include "gi/tonemap.h"

#include <errno.h>
#include <fcntl.h>
#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

void gi_channels_release(gi_channels *c)
{
    if (!c)
        return;
    if (c->names)
        for (int i = 0; i < c->count; i++)
            free(c->names[i]);
    free(c->names);
    free(c->data);
    memset(c, 0, sizeof *c);
}

gi_result gi_channels_check(const char *path, int64_t w, int64_t h, int nc, gi_error *err)
{
    if (w <= 0 || h <= 0 || nc <= 0 || nc > GI_MAX_IMAGE_FILE_CHANNELS)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "%s: unsupported image size %lldx%lld with %d channels (1..%d)", path,
                            (long long)w, (long long)h, nc, GI_MAX_IMAGE_FILE_CHANNELS);
    const uint64_t pixels = (uint64_t)w * (uint64_t)h;
    if (pixels > GI_MAX_IMAGE_FILE_PIXELS || pixels * (uint64_t)nc > GI_MAX_IMAGE_FILE_VALUES)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "%s: image size %lldx%lld with %d channels exceeds the limit of %llu "
                            "pixels and %llu values (pixels x channels)",
                            path, (long long)w, (long long)h, nc,
                            (unsigned long long)GI_MAX_IMAGE_FILE_PIXELS,
                            (unsigned long long)GI_MAX_IMAGE_FILE_VALUES);
    return GI_OK;
}

gi_result gi_channels_place(const char *path, const float *buf, int64_t w, int64_t h, int nc,
                            const char *const *names, const gi_channels_window *win,
                            gi_channels *out, gi_error *err)
{
    const int use_full =
        win->full_w > 0 && win->full_h > 0 &&
        (uint64_t)win->full_w * (uint64_t)win->full_h <= GI_MAX_IMAGE_FILE_PIXELS &&
        (uint64_t)win->full_w * (uint64_t)win->full_h * (uint64_t)nc <= GI_MAX_IMAGE_FILE_VALUES;
    const int64_t fw = use_full ? win->full_w : w, fh = use_full ? win->full_h : h;
    const int64_t ox = use_full ? win->x - win->full_x : 0,
                  oy = use_full ? win->y - win->full_y : 0;
    out->data = calloc((size_t)fw * (size_t)fh * (size_t)nc, sizeof(float));
    out->names = calloc((size_t)nc, sizeof(char *));
    if (!out->data || !out->names)
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    out->width = (uint32_t)fw;
    out->height = (uint32_t)fh;
    out->count = nc;
    for (int c = 0; c < nc; c++) {
        out->names[c] = strdup(names[c] ? names[c] : "");
        if (!out->names[c])
            return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    }
    for (int64_t y = 0; y < h; y++) {
        int64_t ty = y + oy;
        if (ty < 0 || ty >= fh)
            continue;
        for (int64_t x = 0; x < w; x++) {
            int64_t tx = x + ox;
            if (tx < 0 || tx >= fw)
                continue;
            memcpy(&out->data[((size_t)ty * (size_t)fw + (size_t)tx) * (size_t)nc],
                   &buf[((size_t)y * (size_t)w + (size_t)x) * (size_t)nc],
                   sizeof(float) * (size_t)nc);
        }
    }
    return GI_OK;
}

static int image_ok(const gi_image *img)
{
    return img && img->rgba && img->width > 0 && img->height > 0 &&
           (uint64_t)img->width * img->height <= GI_MAX_IMAGE_ALLOC_PIXELS;
}

/* The extension of the last path component including the dot, or "" (a
 * leading dot names a hidden file, not an extension). */
static const char *extension_of(const char *path)
{
    const char *slash = strrchr(path, '/');
    const char *base = slash ? slash + 1 : path;
    const char *dot = strrchr(base, '.');
    return dot && dot != base ? dot : "";
}

/* ---- writing -------------------------------------------------------------- */

/* PFM (Debevec's portable float map): "PF\n<w> <h>\n<scale>\n", then rows
 * from the BOTTOM of the picture up, RGB float32 each; a negative scale
 * means little-endian samples. */
static gi_result write_pfm(const char *path, const gi_image *img, gi_error *err)
{
    const uint32_t one = 1;
    unsigned char first_byte;
    memcpy(&first_byte, &one, 1);
    char header[64];
    int hn = snprintf(header, sizeof header, "PF\n%u %u\n%s\n", img->width, img->height,
                      first_byte == 1 ? "-1.0" : "1.0");
    size_t row_bytes = (size_t)img->width * 3 * sizeof(float);
    size_t size = (size_t)hn + row_bytes * img->height;
    unsigned char *bytes = malloc(size);
    if (!bytes)
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    memcpy(bytes, header, (size_t)hn);
    for (uint32_t k = 0; k < img->height; k++) {
        const float *src = img->rgba + (size_t)(img->height - 1 - k) * img->width * 4;
        float *row = (float *)(void *)(bytes + hn + row_bytes * k);
        for (uint32_t x = 0; x < img->width; x++) {
            float px[3] = {src[(size_t)x * 4], src[(size_t)x * 4 + 1], src[(size_t)x * 4 + 2]};
            memcpy((unsigned char *)row + (size_t)x * 3 * sizeof(float), px, sizeof px);
        }
    }
    gi_result r = gi_file_write_atomic(path, bytes, size, err);
    free(bytes);
    return r;
}

/* 8-bit sRGB RGB after gi_tonemap, through libpng's simplified API (which
 * marks the file sRGB). */
static gi_result write_png(const char *path, const gi_image *img, float exposure, gi_error *err)
{
    size_t n = (size_t)img->width * img->height;
    unsigned char *px = malloc(n * 3);
    if (!px)
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++) {
            float v = gi_tonemap(img->rgba[i * 4 + c], exposure);
            px[i * 3 + c] = (unsigned char)(v * 255.0f + 0.5f);
        }
    png_image pi;
    memset(&pi, 0, sizeof pi);
    pi.version = PNG_IMAGE_VERSION;
    pi.width = img->width;
    pi.height = img->height;
    pi.format = PNG_FORMAT_RGB;
    png_alloc_size_t size = 0;
    gi_result r = GI_OK;
    unsigned char *bytes = NULL;
    if (!png_image_write_to_memory(&pi, NULL, &size, 0, px, 0, NULL) || !size ||
        !(bytes = malloc(size)) || !png_image_write_to_memory(&pi, bytes, &size, 0, px, 0, NULL))
        r = bytes || !size ? gi_error_set(err, GI_ERR_IO, "%s: PNG encoding failed: %s", path,
                                          pi.message[0] ? pi.message : "libpng error")
                           : gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    else
        r = gi_file_write_atomic(path, bytes, size, err);
    png_image_free(&pi);
    free(bytes);
    free(px);
    return r;
}

gi_result gi_image_write(const char *path, const gi_image *img, const gi_image_write_opts *opts,
                         gi_error *err)
{
    if (!path || !*path)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "image write: empty file name");
    if (!image_ok(img))
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: invalid image to write", path);
    const char *ext = extension_of(path);
    if (!strcasecmp(ext, ".exr"))
        return gi_exr_write(path, img, NULL, NULL, 0, err);
    if (!strcasecmp(ext, ".pfm"))
        return write_pfm(path, img, err);
    if (!strcasecmp(ext, ".png"))
        return write_png(path, img, opts ? opts->exposure : 0.0f, err);
    return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                        "%s: unsupported image format '%s' (use .exr, .pfm or .png)", path, ext);
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
    const char *ext = extension_of(path);
    if (strcasecmp(ext, ".exr"))
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "%s: layered images must be .exr, not '%s'", path, ext);
    for (uint32_t l = 0; l < layer_count; l++) {
        if (!image_ok(layers[l]) || layers[l]->width != rgba->width ||
            layers[l]->height != rgba->height)
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                "%s: layer %u is missing or not %ux%u", path, l, rgba->width,
                                rgba->height);
        if (!names[l] || !*names[l])
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: layer %u has no name", path, l);
        for (uint32_t k = 0; k < l; k++)
            if (!strcmp(names[k], names[l]))
                return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: layer name '%s' used twice",
                                    path, names[l]);
    }
    return gi_exr_write(path, rgba, layers, names, layer_count, err);
}

/* ---- reading -------------------------------------------------------------- */

/* Every image read comes here first: only a regular file is handed to a
 * decoder (a FIFO would block it and a device such as /dev/zero never ends;
 * O_NONBLOCK keeps the probe itself from blocking on a FIFO). Sets *is_exr
 * from the file's magic number. */
static gi_result probe(const char *path, int *is_exr, gi_error *err)
{
    int fd = open(path, O_RDONLY | O_CLOEXEC | O_NONBLOCK);
    if (fd < 0)
        return gi_error_set(err, GI_ERR_IO, "%s: %s", path, strerror(errno));
    struct stat st;
    int st_rc = fstat(fd, &st);
    if (st_rc != 0 || !S_ISREG(st.st_mode)) {
        close(fd);
        const char *kind = st_rc != 0                                   ? ""
                           : S_ISDIR(st.st_mode)                        ? " (a directory)"
                           : S_ISFIFO(st.st_mode)                       ? " (a FIFO)"
                           : S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode) ? " (a device)"
                                                                        : "";
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: not a regular file%s", path, kind);
    }
    unsigned char magic[4] = {0};
    ssize_t n = read(fd, magic, sizeof magic);
    close(fd);
    *is_exr =
        n == 4 && magic[0] == 0x76 && magic[1] == 0x2f && magic[2] == 0x31 && magic[3] == 0x01;
    return GI_OK;
}

static gi_result read_channels(const char *path, gi_channels *ch, gi_error *err)
{
    int is_exr = 0;
    gi_result r = probe(path, &is_exr, err);
    if (r != GI_OK)
        return r;
    if (is_exr)
        return gi_exr_read_channels(path, ch, err);
    char what[512];
    snprintf(what, sizeof what, "reading %.480s (not an EXR file)", path);
    gi_oiio_read_channels_fn fn;
    void *sym = gi_module_symbol(GI_OIIO_MODULE, GI_OIIO_READ_SYMBOL, what, err);
    if (!sym)
        return GI_ERR_UNSUPPORTED;
    memcpy(&fn, &sym, sizeof fn);
    return fn(path, ch, err);
}

static int find_channel(const gi_channels *ch, const char *name)
{
    for (int c = 0; c < ch->count; c++)
        if (ch->names[c] && !strcmp(ch->names[c], name))
            return c;
    return -1;
}

/* RGBA from channel indices; src[3] < 0 means alpha 1. */
static gi_image *gather(const gi_channels *ch, const int src[4], const char *path, gi_error *err)
{
    gi_image *img = gi_image_create(ch->width, ch->height);
    if (!img) {
        gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "%s: out of memory for %ux%u pixels", path,
                     ch->width, ch->height);
        return NULL;
    }
    size_t n = (size_t)ch->width * ch->height;
    for (size_t i = 0; i < n; i++) {
        const float *p = &ch->data[i * ch->count];
        float *q = img->rgba + i * 4;
        for (int c = 0; c < 3; c++)
            q[c] = p[src[c]];
        q[3] = src[3] >= 0 ? p[src[3]] : 1.0f;
    }
    return img;
}

gi_image *gi_image_read(const char *path, gi_error *err)
{
    if (!path || !*path) {
        gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "image read: empty file name");
        return NULL;
    }
    gi_channels ch;
    memset(&ch, 0, sizeof ch);
    if (read_channels(path, &ch, err) != GI_OK)
        return NULL;
    int src[4];
    int r = find_channel(&ch, "R"), g = find_channel(&ch, "G"), b = find_channel(&ch, "B");
    if (r >= 0 && g >= 0 && b >= 0) {
        src[0] = r, src[1] = g, src[2] = b, src[3] = find_channel(&ch, "A");
    } else if (ch.count == 1) {
        src[0] = src[1] = src[2] = 0, src[3] = -1;
    } else if (ch.count == 2) { /* grey + alpha */
        src[0] = src[1] = src[2] = 0, src[3] = 1;
    } else {
        src[0] = 0, src[1] = 1, src[2] = 2, src[3] = ch.count >= 4 ? 3 : -1;
    }
    gi_image *img = gather(&ch, src, path, err);
    gi_channels_release(&ch);
    return img;
}

gi_image *gi_image_read_layer(const char *path, const char *name, gi_error *err)
{
    if (!path || !*path || !name || !*name) {
        gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "image read: empty file or layer name");
        return NULL;
    }
    gi_channels ch;
    memset(&ch, 0, sizeof ch);
    if (read_channels(path, &ch, err) != GI_OK)
        return NULL;
    size_t len = strlen(name);
    char *key = malloc(len + 3);
    gi_image *img = NULL;
    if (!key) {
        gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
        goto done;
    }
    int src[4];
    const char *suffix[5] = {"R", "G", "B", "A", "Y"};
    int idx[5];
    for (int k = 0; k < 5; k++) {
        snprintf(key, len + 3, "%s.%s", name, suffix[k]);
        idx[k] = find_channel(&ch, key);
    }
    if (idx[0] >= 0 && idx[1] >= 0 && idx[2] >= 0) {
        src[0] = idx[0], src[1] = idx[1], src[2] = idx[2], src[3] = idx[3];
    } else {
        /* A single-channel layer ("depth" or "depth.Y") reads as grey. */
        int y = idx[4] >= 0 ? idx[4] : find_channel(&ch, name);
        if (y < 0) {
            char list[1024] = "";
            size_t used = 0;
            for (int c = 0; c < ch.count && used < sizeof list; c++)
                used += (size_t)snprintf(list + used, sizeof list - used, "%s%s", c ? ", " : "",
                                         ch.names[c]);
            gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: no layer '%s' (channels: %s)", path,
                         name, list);
            goto done;
        }
        src[0] = src[1] = src[2] = y, src[3] = idx[3];
    }
    img = gather(&ch, src, path, err);
done:
    free(key);
    gi_channels_release(&ch);
    return img;
}
