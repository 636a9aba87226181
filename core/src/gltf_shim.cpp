/* glTF 2.0 -> gi_scene: the one C++ file that touches tinygltf.
 *
 * Three stages, each of which may reject the file with
 * "name: /json/pointer: reason":
 *   1. before tinygltf: the GLB container, JSON nesting depth, asset version,
 *      extensionsRequired and every buffer/image URI (relative, inside the
 *      scene directory, percent-decoded). tinygltf reads files only through
 *      the FsCallbacks below, which refuse anything else again.
 *   2. tinygltf (Debian's libtinygltf.so, default configuration: nlohmann
 *      JSON, stb_image, file system callbacks): its own errors pass through
 *      as one line. Images are decoded by our loader callback, which checks
 *      format and size first and defers images stored in buffer views until
 *      their bounds are checked (tinygltf 2.7 hands the decoder an unchecked
 *      pointer for those).
 *   3. conversion: every index, every accessor range (in uint64, overflow-
 *      checked), every value we read, then the scene semantics of scene.h.
 * Validation failures are thrown as Failure and turned into the error text at
 * the C boundary, where every other exception is caught too.
 */
#include "gltf_shim.h"

#include "gi/json_keys.h"
#include "gi/log.h"
#include "gi/tonemap.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <new>
#include <string>
#include <vector>

#include <fcntl.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include <nlohmann/json.hpp>
#include <stb_image.h>
#include <tiny_gltf.h>

namespace
{

constexpr double kPi = 3.14159265358979323846;

/* ---- messages ---------------------------------------------------------- */

struct Failure {
    std::string pointer; /* JSON pointer, "GLB" for the container, "" for tinygltf's own */
    std::string reason;
};

[[noreturn]] void fail(const std::string &pointer, const std::string &reason)
{
    throw Failure{pointer, reason};
}

std::string fmt(const char *f, ...) __attribute__((format(printf, 1, 2)));
std::string fmt(const char *f, ...)
{
    char buf[400];
    va_list ap;
    va_start(ap, f);
    vsnprintf(buf, sizeof buf, f, ap);
    va_end(ap);
    return buf;
}

/* A user-controlled string made safe and short for a one-line message. */
std::string shown(const std::string &s)
{
    const size_t max = 60;
    std::string out = "'";
    for (size_t i = 0; i < s.size() && i < max; i++) {
        unsigned char ch = static_cast<unsigned char>(s[i]);
        out += (ch >= 0x20 && ch < 0x7f) ? static_cast<char>(ch) : '?';
    }
    if (s.size() > max)
        out += "...";
    return out + "'";
}

/* tinygltf's multi-line error text as one line, each part shortened. */
std::string one_line(const std::string &text)
{
    std::string out, line;
    auto flush = [&]() {
        if (line.empty())
            return;
        if (line.size() > 160)
            line = line.substr(0, 160) + "...";
        out += (out.empty() ? "" : "; ") + line;
        line.clear();
    };
    for (char ch : text) {
        if (ch == '\n' || ch == '\r')
            flush();
        else
            line += (static_cast<unsigned char>(ch) < 0x20) ? ' ' : ch;
    }
    flush();
    return out;
}

/* "mesh 4 out of range (2 meshes)" */
std::string out_of_range(const char *what, long long index, size_t count, const char *whats)
{
    return fmt("%s %lld out of range (%zu %s)", what, index, count, whats);
}

/* ---- URIs and files ------------------------------------------------------ */

struct Context {
    std::string name;
    bool has_base = false;
    std::string base;        /* scene directory as given, without trailing '/' */
    std::string prefix;      /* base + '/' */
    std::string real_prefix; /* realpath(base) + '/': where a resolved file must lie */
    /* First refusal by a callback that tinygltf calls (its own text would not
     * say which JSON element it was). */
    std::string refused_pointer, refused;
    uint64_t image_texels = 0; /* decoded so far, against GI_MAX_TEXTURE_TEXELS */
};

bool uri_scheme(const std::string &uri, std::string *scheme)
{
    if (uri.empty() || !isalpha(static_cast<unsigned char>(uri[0])))
        return false;
    for (size_t i = 1; i < uri.size(); i++) {
        unsigned char ch = static_cast<unsigned char>(uri[i]);
        if (ch == ':') {
            *scheme = uri.substr(0, i);
            return true;
        }
        if (!isalnum(ch) && ch != '+' && ch != '-' && ch != '.')
            return false;
    }
    return false;
}

bool is_data_uri(const std::string &uri)
{
    std::string scheme;
    return uri_scheme(uri, &scheme) && scheme.size() == 4 &&
           strncasecmp(scheme.c_str(), "data", 4) == 0;
}

int hex_value(char ch)
{
    if (ch >= '0' && ch <= '9')
        return ch - '0';
    if (ch >= 'a' && ch <= 'f')
        return ch - 'a' + 10;
    if (ch >= 'A' && ch <= 'F')
        return ch - 'A' + 10;
    return -1;
}

/* Percent-decoding exactly as tinygltf applies it before opening a file
 * ('+' becomes a space), but strict: a malformed escape or a NUL byte is an
 * error instead of a silently different name. */
bool decode_uri(const std::string &uri, std::string *out, const char **why)
{
    out->clear();
    for (size_t i = 0; i < uri.size(); i++) {
        char ch = uri[i];
        if (ch == '%') {
            int hi = i + 2 < uri.size() ? hex_value(uri[i + 1]) : -1;
            int lo = i + 2 < uri.size() ? hex_value(uri[i + 2]) : -1;
            if (hi < 0 || lo < 0) {
                *why = "has a malformed percent-escape";
                return false;
            }
            ch = static_cast<char>(hi * 16 + lo);
            i += 2;
        } else if (ch == '+') {
            ch = ' ';
        }
        if (ch == '\0') {
            *why = "contains a NUL byte";
            return false;
        }
        *out += ch;
    }
    return true;
}

/* A decoded relative path that stays inside the scene directory. */
bool relative_path_ok(const std::string &path, const char **why)
{
    if (path.empty()) {
        *why = "is empty";
        return false;
    }
    if (path[0] == '/') {
        *why = "is an absolute path";
        return false;
    }
    if (path.find('\\') != std::string::npos) {
        *why = "contains a backslash";
        return false;
    }
    long depth = 0;
    size_t start = 0;
    while (start <= path.size()) {
        size_t end = path.find('/', start);
        if (end == std::string::npos)
            end = path.size();
        std::string seg = path.substr(start, end - start);
        if (seg == "..") {
            if (--depth < 0) {
                *why = "leaves the scene directory";
                return false;
            }
        } else if (!seg.empty() && seg != ".") {
            depth++;
        }
        start = end + 1;
    }
    return true;
}

/* Whether `path`, with every symbolic link resolved, lies below the scene
 * directory (also resolved). A file that does not exist passes: reading it
 * fails later with its own error. */
bool resolves_inside(const Context &c, const std::string &path)
{
    if (c.real_prefix.empty())
        return true;
    char *real = realpath(path.c_str(), nullptr);
    if (!real)
        return true;
    std::string r(real);
    free(real);
    return r.size() > c.real_prefix.size() &&
           r.compare(0, c.real_prefix.size(), c.real_prefix) == 0;
}

/* The file a relative URI names, or a Failure at `pointer`. */
std::string resolve_uri(const Context &c, const std::string &pointer, const std::string &uri)
{
    std::string scheme, path;
    const char *why = nullptr;
    if (uri_scheme(uri, &scheme))
        fail(pointer, "URI scheme " + shown(scheme) +
                          " is not allowed (only relative paths and data: URIs)");
    if (!c.has_base)
        fail(pointer,
             "external URI " + shown(uri) + " needs a base directory (loaded from memory)");
    if (!decode_uri(uri, &path, &why) || !relative_path_ok(path, &why))
        fail(pointer, "URI " + shown(uri) + " " + why);
    if (!resolves_inside(c, c.prefix + path))
        fail(pointer, "URI " + shown(uri) + " leaves the scene directory through a symbolic link");
    return c.prefix + path;
}

bool stat_regular(const std::string &path, uint64_t *size, int *error)
{
    struct stat st;
    if (stat(path.c_str(), &st) != 0) {
        *error = errno;
        return false;
    }
    if (!S_ISREG(st.st_mode)) {
        *error = EISDIR;
        return false;
    }
    *size = static_cast<uint64_t>(st.st_size);
    return true;
}

/* Files the callbacks may open: below the scene directory, by the rules. */
bool path_allowed(const Context &c, const std::string &path)
{
    const char *why = nullptr;
    return c.has_base && path.size() > c.prefix.size() &&
           path.compare(0, c.prefix.size(), c.prefix) == 0 &&
           relative_path_ok(path.substr(c.prefix.size()), &why) && resolves_inside(c, path);
}

bool read_file(const std::string &path, std::vector<unsigned char> *out, std::string *why)
{
    int fd = open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
    if (fd < 0) {
        *why = strerror(errno);
        return false;
    }
    struct stat st;
    bool ok = fstat(fd, &st) == 0 && S_ISREG(st.st_mode) &&
              static_cast<uint64_t>(st.st_size) <= GI_MAX_FILE_BYTES;
    if (!ok) {
        *why = "not a regular file of at most 1 GiB";
    } else {
        out->resize(static_cast<size_t>(st.st_size));
        size_t done = 0;
        while (ok && done < out->size()) {
            ssize_t n = read(fd, out->data() + done, out->size() - done);
            if (n <= 0) {
                *why = n < 0 ? strerror(errno) : "file shrank while reading";
                ok = false;
            } else {
                done += static_cast<size_t>(n);
            }
        }
    }
    close(fd);
    return ok;
}

bool fs_file_exists(const std::string &path, void *user)
{
    const Context &c = *static_cast<const Context *>(user);
    uint64_t size = 0;
    int error = 0;
    return path_allowed(c, path) && stat_regular(path, &size, &error);
}

std::string fs_expand_path(const std::string &path, void *)
{
    return path; /* never expand '~' or variables */
}

bool fs_read_whole_file(std::vector<unsigned char> *out, std::string *err, const std::string &path,
                        void *user)
{
    Context &c = *static_cast<Context *>(user);
    std::string why;
    if (!path_allowed(c, path))
        why = "refused: outside the scene directory";
    else if (read_file(path, out, &why))
        return true;
    if (c.refused.empty()) {
        c.refused_pointer = "/";
        c.refused = "cannot read " + shown(path) + ": " + why;
    }
    if (err)
        *err = why;
    return false;
}

bool fs_write_whole_file(std::string *err, const std::string &, const std::vector<unsigned char> &,
                         void *)
{
    if (err)
        *err = "writing files is disabled";
    return false;
}

/* ---- images -------------------------------------------------------------- */

bool is_png_or_jpeg(const unsigned char *b, size_t n)
{
    static const unsigned char png[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    return (n >= 8 && memcmp(b, png, 8) == 0) ||
           (n >= 3 && b[0] == 0xff && b[1] == 0xd8 && b[2] == 0xff);
}

/* Decodes PNG/JPEG bytes into image->image (RGBA, 8 or 16 bits) after
 * checking the format and the size in the header, and the texels decoded so
 * far (*texels, updated) against the scene's limit: one small PNG listed as
 * many images must not decode into many GiB. */
bool decode_image(tinygltf::Image *image, int index, const unsigned char *bytes, size_t size,
                  uint64_t *texels, std::string *why)
{
    int w = 0, h = 0, comp = 0;
    if (size > INT_MAX) {
        *why = "image data larger than 2 GiB";
        return false;
    }
    if (!is_png_or_jpeg(bytes, size)) {
        *why = "image is not PNG or JPEG";
        return false;
    }
    if (!stbi_info_from_memory(bytes, static_cast<int>(size), &w, &h, &comp)) {
        *why = "image header cannot be read";
        return false;
    }
    if (w < 1 || h < 1 || w > GI_MAX_TEXTURE_SIZE || h > GI_MAX_TEXTURE_SIZE) {
        *why = fmt("image size %dx%d outside 1..%d", w, h, GI_MAX_TEXTURE_SIZE);
        return false;
    }
    *texels += static_cast<uint64_t>(w) * static_cast<uint64_t>(h);
    if (*texels > GI_MAX_TEXTURE_TEXELS) {
        *why = fmt("images exceed the limit of %u texels in all", GI_MAX_TEXTURE_TEXELS);
        return false;
    }
    std::string err, warn;
    /* no option struct: tinygltf's default expands every image to RGBA */
    if (!tinygltf::LoadImageData(image, index, &err, &warn, 0, 0, bytes, static_cast<int>(size),
                                 nullptr)) {
        *why = "image cannot be decoded: " + one_line(err);
        return false;
    }
    size_t expect = static_cast<size_t>(image->width) * static_cast<size_t>(image->height) * 4u *
                    static_cast<size_t>(image->bits / 8);
    if (image->component != 4 || (image->bits != 8 && image->bits != 16) || image->width != w ||
        image->height != h || image->image.size() != expect) {
        *why = "image decoded to an unexpected layout";
        return false;
    }
    return true;
}

bool load_image_callback(tinygltf::Image *image, const int index, std::string *err, std::string *,
                         int, int, const unsigned char *bytes, int size, void *user)
{
    Context &c = *static_cast<Context *>(user);
    if (image->bufferView >= 0)
        return true; /* decoded by the converter once the view's bounds are checked */
    std::string why;
    if (size >= 0 &&
        decode_image(image, index, bytes, static_cast<size_t>(size), &c.image_texels, &why))
        return true;
    if (c.refused.empty()) {
        c.refused_pointer = fmt("/images/%d", index);
        c.refused = why;
    }
    if (err)
        *err += why + "\n";
    return false;
}

/* ---- stage 1: before tinygltf ------------------------------------------ */

uint32_t le32(const unsigned char *p)
{
    return static_cast<uint32_t>(p[0]) | static_cast<uint32_t>(p[1]) << 8 |
           static_cast<uint32_t>(p[2]) << 16 | static_cast<uint32_t>(p[3]) << 24;
}

struct Glb {
    const char *json;
    size_t json_size;
    uint32_t length; /* what tinygltf is given */
};

Glb check_glb(const unsigned char *d, size_t n)
{
    if (n < 20)
        fail("GLB", fmt("%zu bytes is shorter than the 20-byte header", n));
    if (memcmp(d, "glTF", 4) != 0)
        fail("GLB", "does not start with 'glTF'");
    if (le32(d + 4) != 2)
        fail("GLB", fmt("container version %u is not supported (need 2)", le32(d + 4)));
    uint64_t length = le32(d + 8);
    if (length > n || length < 20)
        fail("GLB", fmt("header length %llu does not match the %zu bytes given",
                        static_cast<unsigned long long>(length), n));
    uint64_t json_len = le32(d + 12);
    if (le32(d + 16) != 0x4E4F534Au)
        fail("GLB", "first chunk is not JSON");
    if (json_len == 0 || 20 + json_len > length)
        fail("GLB", fmt("JSON chunk of %llu bytes does not fit",
                        static_cast<unsigned long long>(json_len)));
    uint64_t rest = length - 20 - json_len;
    if (rest > 0) {
        const unsigned char *bin = d + 20 + json_len;
        if (rest < 8)
            fail("GLB", "truncated BIN chunk header");
        if (le32(bin + 4) != 0x004E4942u)
            fail("GLB", "second chunk is not BIN");
        if (le32(bin) > rest - 8)
            fail("GLB", fmt("BIN chunk of %u bytes runs past the end", le32(bin)));
    }
    return Glb{reinterpret_cast<const char *>(d + 20), static_cast<size_t>(json_len),
               static_cast<uint32_t>(length)};
}

/* tinygltf turns JSON into its Value type recursively: bound the depth. */
void check_nesting(const char *s, size_t n)
{
    const int max_depth = 64;
    int depth = 0;
    bool in_string = false;
    for (size_t i = 0; i < n; i++) {
        char ch = s[i];
        if (in_string) {
            if (ch == '\\')
                i++;
            else if (ch == '"')
                in_string = false;
        } else if (ch == '"') {
            in_string = true;
        } else if (ch == '[' || ch == '{') {
            if (++depth > max_depth)
                fail("/", fmt("JSON nested deeper than %d levels", max_depth));
        } else if (ch == ']' || ch == '}') {
            depth--;
        }
    }
}

using Json = nlohmann::json;

/* "2.0" -> (2, 0); false when not a version number. */
bool parse_version(const std::string &s, long *major, long *minor)
{
    char *end = nullptr;
    if (s.empty() || !isdigit(static_cast<unsigned char>(s[0])))
        return false;
    *major = strtol(s.c_str(), &end, 10);
    if (*end != '.' || !isdigit(static_cast<unsigned char>(end[1])))
        return false;
    *minor = strtol(end + 1, &end, 10);
    return *end == '\0';
}

void check_asset(const Json &j)
{
    auto asset = j.find("asset");
    if (asset == j.end() || !asset->is_object())
        fail("/asset", "missing: every glTF file needs asset.version");
    auto version = asset->find("version");
    if (version == asset->end() || !version->is_string())
        fail("/asset/version", "missing or not a string");
    if (version->get<std::string>() != "2.0")
        fail("/asset/version",
             "glTF version " + shown(version->get<std::string>()) + " is not supported (need 2.0)");
    auto min = asset->find("minVersion");
    if (min == asset->end())
        return;
    long major = 0, minor = 0;
    if (!min->is_string() || !parse_version(min->get<std::string>(), &major, &minor))
        fail("/asset/minVersion", "not a version number");
    if (major > 2 || (major == 2 && minor > 0))
        fail("/asset/minVersion",
             "file needs glTF " + shown(min->get<std::string>()) + "; this loader reads 2.0");
}

void check_required_extensions(const Json &j)
{
    auto req = j.find("extensionsRequired");
    if (req == j.end())
        return;
    if (!req->is_array())
        fail("/extensionsRequired", "not an array");
    for (size_t i = 0; i < req->size(); i++) {
        const Json &e = (*req)[i];
        std::string name = e.is_string() ? e.get<std::string>() : std::string();
        if (name != "KHR_lights_punctual" && name != "KHR_materials_emissive_strength")
            fail(fmt("/extensionsRequired/%zu", i),
                 "extension " + shown(name) +
                     " is required but not supported (supported: "
                     "KHR_lights_punctual, KHR_materials_emissive_strength)");
    }
}

void check_external_file(const Context &c, const std::string &pointer, const std::string &uri)
{
    std::string path = resolve_uri(c, pointer, uri);
    uint64_t size = 0;
    int error = 0;
    if (!stat_regular(path, &size, &error))
        fail(pointer, "cannot open " + shown(uri) + ": " +
                          (error == EISDIR ? "not a regular file" : strerror(error)));
    if (size > GI_MAX_FILE_BYTES)
        fail(pointer, shown(uri) + " is larger than the 1 GiB limit");
}

void check_uris(const Context &c, const Json &j, const char *key)
{
    auto arr = j.find(key);
    if (arr == j.end() || !arr->is_array())
        return;
    for (size_t i = 0; i < arr->size(); i++) {
        const Json &e = (*arr)[i];
        if (!e.is_object())
            continue;
        auto uri = e.find("uri");
        if (uri == e.end() || !uri->is_string())
            continue;
        std::string s = uri->get<std::string>(), pointer = fmt("/%s/%zu/uri", key, i);
        if (!is_data_uri(s))
            check_external_file(c, pointer, s);
        else if (!tinygltf::IsDataURI(s))
            fail(pointer, "data URI must be base64 with a glTF MIME type (" + shown(s) + ")");
        else if (s.back() == ',')
            fail(pointer, "data URI holds no data");
    }
}

void check_before_tinygltf(const Context &c, const char *text, size_t n)
{
    check_nesting(text, n);
    Json j = Json::parse(text, text + n, nullptr, false);
    if (j.is_discarded() || !j.is_object())
        return; /* tinygltf reports the syntax error in its words */
    /* tinygltf keeps the last of two equal keys without a word: refused, as
     * a study's are (gi/json_keys.h) */
    char path[512], key[256];
    size_t line = 0;
    int dup = gi_json_duplicate_key(text, n, path, sizeof path, key, sizeof key, &line);
    if (dup < 0)
        fail("/", "out of memory");
    if (dup > 0)
        fail(path, fmt("duplicate key '%s' (line %zu)", key, line));
    check_asset(j);
    check_required_extensions(j);
    check_uris(c, j, "buffers");
    check_uris(c, j, "images");
}

/* ---- stage 3: conversion ------------------------------------------------ */

bool finite(double v)
{
    return std::isfinite(v);
}

/* Finite and representable as a float. */
bool finite_float(double v)
{
    return std::isfinite(v) && std::fabs(v) <= 3.4e38;
}

uint64_t component_size(int type)
{
    switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
        return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT:
        return 4;
    default:
        return 0;
    }
}

uint64_t component_count(int type)
{
    switch (type) {
    case TINYGLTF_TYPE_SCALAR:
        return 1;
    case TINYGLTF_TYPE_VEC2:
        return 2;
    case TINYGLTF_TYPE_VEC3:
        return 3;
    case TINYGLTF_TYPE_VEC4:
    case TINYGLTF_TYPE_MAT2:
        return 4;
    case TINYGLTF_TYPE_MAT3:
        return 9;
    case TINYGLTF_TYPE_MAT4:
        return 16;
    default:
        return 0;
    }
}

const char *type_name(int type)
{
    switch (type) {
    case TINYGLTF_TYPE_SCALAR:
        return "SCALAR";
    case TINYGLTF_TYPE_VEC2:
        return "VEC2";
    case TINYGLTF_TYPE_VEC3:
        return "VEC3";
    case TINYGLTF_TYPE_VEC4:
        return "VEC4";
    case TINYGLTF_TYPE_MAT2:
        return "MAT2";
    case TINYGLTF_TYPE_MAT3:
        return "MAT3";
    case TINYGLTF_TYPE_MAT4:
        return "MAT4";
    default:
        return "?";
    }
}

const char *component_name(int type)
{
    switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
        return "BYTE";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        return "UNSIGNED_BYTE";
    case TINYGLTF_COMPONENT_TYPE_SHORT:
        return "SHORT";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
        return "UNSIGNED_SHORT";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
        return "UNSIGNED_INT";
    case TINYGLTF_COMPONENT_TYPE_FLOAT:
        return "FLOAT";
    default:
        return "?";
    }
}

const char *mode_name(int mode)
{
    static const char *names[] = {"POINTS",    "LINES",          "LINE_LOOP",   "LINE_STRIP",
                                  "TRIANGLES", "TRIANGLE_STRIP", "TRIANGLE_FAN"};
    return mode >= 0 && mode <= 6 ? names[mode] : "unknown";
}

/* Reads elements of a validated accessor; a missing bufferView reads zeros. */
struct Reader {
    const unsigned char *base = nullptr;
    uint64_t stride = 0;
    size_t count = 0;
    int component = 0;
    uint64_t components = 0;
    bool normalized = false;

    double raw(size_t e, uint64_t k) const
    {
        if (!base)
            return 0.0;
        const unsigned char *p = base + e * stride + k * component_size(component);
        switch (component) {
        case TINYGLTF_COMPONENT_TYPE_BYTE: {
            int8_t v;
            memcpy(&v, p, 1);
            return v;
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
            return *p;
        case TINYGLTF_COMPONENT_TYPE_SHORT: {
            int16_t v;
            memcpy(&v, p, 2);
            return v;
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
            uint16_t v;
            memcpy(&v, p, 2);
            return v;
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
            uint32_t v;
            memcpy(&v, p, 4);
            return v;
        }
        default: {
            float v;
            memcpy(&v, p, 4);
            return v;
        }
        }
    }
    /* Component k of element e, normalised integers mapped as glTF says. */
    double get(size_t e, uint64_t k) const
    {
        double v = raw(e, k);
        if (!normalized)
            return v;
        switch (component) {
        case TINYGLTF_COMPONENT_TYPE_BYTE:
            return std::max(v / 127.0, -1.0);
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
            return v / 255.0;
        case TINYGLTF_COMPONENT_TYPE_SHORT:
            return std::max(v / 32767.0, -1.0);
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
            return v / 65535.0;
        default:
            return v;
        }
    }
};

struct MeshData {
    std::vector<gi_vertex> vertices; /* object index not yet set */
    std::vector<uint32_t> indices;   /* relative to vertices */
    /* Morph targets: per target, 3 floats a vertex (zeros where a primitive's
     * target lacks the attribute). */
    size_t morph_count = 0;
    bool morph_normals = false;
    std::vector<std::vector<float>> tpos, tnrm;
    std::vector<float> weights; /* mesh.weights, or zeros */
    /* Per triangle: 1 when its primitive had no NORMAL (flat normals, own
     * vertices); empty while every primitive had NORMAL. */
    std::vector<uint8_t> flat;
};

/* An object's morph data, moved into the gi_object by build(). */
struct ObjectMorph {
    std::vector<float> pos, nrm, weights; /* target-major; nrm empty if none */
    std::vector<uint8_t> flat;            /* MeshData::flat: flat-normal triangles */
};

struct Track {
    std::vector<float> times, values;
    bool step = false;
};

struct NodeInfo {
    float t[3] = {0, 0, 0}, r[4] = {0, 0, 0, 1}, s[3] = {1, 1, 1};
    Track anim[3]; /* translation, rotation, scale */
    Track weights; /* morph weights, one key = the mesh's target count floats */
};

struct TextureData {
    std::string name;
    uint32_t width = 0, height = 0;
    std::vector<float> rgba;
};

using Value = tinygltf::Value;

const Value *member(const Value &v, const char *key)
{
    if (!v.IsObject() || !v.Has(key))
        return nullptr;
    return &v.Get(key);
}

/* A JSON number held in a Value, as a double; false if it is not one. */
bool number(const Value *v, double *out)
{
    if (!v || !v->IsNumber())
        return false;
    *out = v->GetNumberAsDouble();
    return finite(*out);
}

class Converter
{
  public:
    Converter(const tinygltf::Model &model, Context &ctx) : m(model), c(ctx) {}
    gi_scene *run(char env_pointer[GI_GLTF_POINTER_MAX]);

  private:
    const tinygltf::Model &m;
    Context &c;

    std::vector<gi_material> materials;
    std::vector<std::string> material_names;
    int default_material = -1;
    std::vector<TextureData> textures;
    uint64_t texture_texels = 0;              /* in textures, against GI_MAX_TEXTURE_TEXELS */
    std::map<int, int> texture_of;            /* glTF texture -> textures index */
    std::vector<tinygltf::Image> view_images; /* decoded images stored in buffer views */
    std::vector<int> parents;
    std::vector<NodeInfo> nodes;
    int scene_index = -1;
    std::vector<int> order; /* scene nodes, depth-first pre-order */
    std::vector<bool> mesh_done;
    std::vector<MeshData> meshes;

    std::vector<gi_vertex> vertices;
    std::vector<uint32_t> indices;
    std::vector<gi_object> objects;
    std::vector<std::string> object_names;
    std::vector<ObjectMorph> object_morphs;
    std::vector<gi_light> lights;
    std::vector<std::string> light_names;
    std::vector<gi_camera> cameras;
    std::vector<std::string> camera_names;
    float animation_length = 0.0f;
    bool has_env = false;
    std::string env_uri, env_path;
    float env_intensity = 1.0f, env_rotation = 0.0f;

    void check_buffer_views();
    void check_accessors();
    Reader reader(int accessor) const;
    void check_accessor_kind(int accessor, const char *what, bool ok) const;
    void convert_materials();
    void convert_material(size_t i);
    void read_phong(size_t i, gi_material *g);
    void warn_reduced(size_t i, const std::string &name) const;
    int texture(int index, const std::string &pointer);
    void convert_texture(int index);
    void check_textures() const;
    void check_images();
    void check_cameras() const;
    void check_lights() const;
    int node_light(size_t i) const;
    void check_nodes();
    void node_transform(size_t i);
    void check_graph();
    void choose_scene();
    const MeshData &mesh(int index);
    void convert_primitive(size_t mi, size_t k, MeshData *out);
    void read_positions(const std::string &pp, int acc, std::vector<gi_vertex> *v);
    void read_normals(const std::string &pp, int acc, std::vector<gi_vertex> *v);
    void read_uvs(const std::string &pp, int acc, std::vector<gi_vertex> *v);
    void read_targets(const std::string &pp, const tinygltf::Primitive &prim, size_t nv,
                      bool first_prim, MeshData *out);
    void morph_bounds(gi_object *o, const ObjectMorph &om, const Track &tr) const;
    void read_indices(const std::string &pp, const tinygltf::Primitive &prim, size_t nv,
                      std::vector<uint32_t> *out);
    void instantiate();
    void check_totals();
    void add_object(int node);
    void add_camera(int node);
    void add_light(int node);
    void convert_animations();
    void convert_channel(size_t a, size_t k);
    void read_environment();
    void copy_geometry(gi_scene *s) const;
    void copy_materials(gi_scene *s) const;
    void copy_textures(gi_scene *s) const;
    void copy_nodes(gi_scene *s) const;
    void copy_objects(gi_scene *s) const;
    void copy_lights(gi_scene *s) const;
    void copy_cameras(gi_scene *s) const;
    void copy_emitters_and_environment(gi_scene *s) const;
    gi_scene *build() const;
};

/* bufferView inside its buffer. */
void Converter::check_buffer_views()
{
    for (size_t i = 0; i < m.bufferViews.size(); i++) {
        const tinygltf::BufferView &bv = m.bufferViews[i];
        std::string p = fmt("/bufferViews/%zu", i);
        if (bv.buffer < 0 || static_cast<size_t>(bv.buffer) >= m.buffers.size())
            fail(p + "/buffer", out_of_range("buffer", bv.buffer, m.buffers.size(), "buffers"));
        uint64_t size = m.buffers[static_cast<size_t>(bv.buffer)].data.size();
        uint64_t end = 0;
        if (bv.byteLength == 0)
            fail(p + "/byteLength", "is 0");
        if (__builtin_add_overflow(static_cast<uint64_t>(bv.byteOffset),
                                   static_cast<uint64_t>(bv.byteLength), &end) ||
            end > size)
            fail(p, fmt("byteOffset %zu + byteLength %zu past the end of buffer %d (%llu bytes)",
                        bv.byteOffset, bv.byteLength, bv.buffer,
                        static_cast<unsigned long long>(size)));
    }
}

/* Every accessor's elements inside its bufferView. */
void Converter::check_accessors()
{
    for (size_t i = 0; i < m.accessors.size(); i++) {
        const tinygltf::Accessor &a = m.accessors[i];
        std::string p = fmt("/accessors/%zu", i);
        uint64_t elem = component_size(a.componentType) * component_count(a.type);
        if (component_size(a.componentType) == 0)
            fail(p + "/componentType", fmt("componentType %d is not valid", a.componentType));
        if (a.count == 0)
            fail(p + "/count", "is 0");
        if (a.bufferView < 0)
            continue; /* all zeros (or sparse, rejected where read) */
        if (static_cast<size_t>(a.bufferView) >= m.bufferViews.size())
            fail(p + "/bufferView",
                 out_of_range("bufferView", a.bufferView, m.bufferViews.size(), "bufferViews"));
        const tinygltf::BufferView &bv = m.bufferViews[static_cast<size_t>(a.bufferView)];
        uint64_t stride = bv.byteStride ? bv.byteStride : elem;
        if (stride < elem)
            fail(p, fmt("elements of %llu bytes do not fit bufferView %d's byteStride %zu",
                        static_cast<unsigned long long>(elem), a.bufferView, bv.byteStride));
        uint64_t span = 0;
        bool overflow = __builtin_mul_overflow(static_cast<uint64_t>(a.count) - 1, stride, &span) ||
                        __builtin_add_overflow(span, elem, &span) ||
                        __builtin_add_overflow(span, static_cast<uint64_t>(a.byteOffset), &span);
        if (overflow || span > bv.byteLength) {
            std::string off = a.byteOffset ? fmt("byteOffset %zu + ", a.byteOffset) : "";
            fail(p, off + fmt("count %zu x stride %llu past the end of bufferView %d (%zu bytes)",
                              a.count, static_cast<unsigned long long>(stride), a.bufferView,
                              bv.byteLength));
        }
    }
}

Reader Converter::reader(int accessor) const
{
    const tinygltf::Accessor &a = m.accessors[static_cast<size_t>(accessor)];
    Reader r;
    r.count = a.count;
    r.component = a.componentType;
    r.components = component_count(a.type);
    r.normalized = a.normalized;
    if (a.bufferView >= 0) {
        const tinygltf::BufferView &bv = m.bufferViews[static_cast<size_t>(a.bufferView)];
        const tinygltf::Buffer &b = m.buffers[static_cast<size_t>(bv.buffer)];
        r.stride = bv.byteStride ? bv.byteStride : component_size(a.componentType) * r.components;
        r.base = b.data.data() + bv.byteOffset + a.byteOffset;
    }
    return r;
}

/* Rejects sparse accessors, accessors without data and those of the wrong
 * type for `what`. Every element we read therefore lies in the file, which
 * bounds every allocation by the input size. */
void Converter::check_accessor_kind(int accessor, const char *what, bool ok) const
{
    const tinygltf::Accessor &a = m.accessors[static_cast<size_t>(accessor)];
    std::string p = fmt("/accessors/%d", accessor);
    if (a.sparse.isSparse)
        fail(p + "/sparse", "sparse accessors are not supported");
    if (a.bufferView < 0) /* glTF's all-zero accessor; without sparse data it is useless here */
        fail(p, "accessor without a bufferView is not supported");
    if (!ok)
        fail(p, fmt("%s cannot be %s of %s%s", what, type_name(a.type),
                    a.normalized ? "normalized " : "", component_name(a.componentType)));
}

/* ---- materials and textures ---- */

void Converter::convert_materials()
{
    if (m.materials.size() > GI_MAX_MATERIALS)
        fail("/materials",
             fmt("%zu materials exceed the limit of %d", m.materials.size(), GI_MAX_MATERIALS));
    for (size_t i = 0; i < m.materials.size(); i++)
        convert_material(i);
}

void Converter::convert_material(size_t i)
{
    const tinygltf::Material &mt = m.materials[i];
    std::string p = fmt("/materials/%zu", i);
    gi_material g = {};
    g.albedo_texture = -1;
    const std::vector<double> &bc = mt.pbrMetallicRoughness.baseColorFactor;
    if (bc.size() != 4)
        fail(p + "/pbrMetallicRoughness/baseColorFactor", "needs 4 numbers");
    for (int k = 0; k < 3; k++) {
        if (!finite(bc[k]) || bc[k] < 0.0 || bc[k] > 1.0)
            fail(p + "/pbrMetallicRoughness/baseColorFactor", "values must lie in [0, 1]");
        g.albedo[k] = static_cast<float>(bc[k]);
    }
    double strength = 1.0;
    auto ext = mt.extensions.find("KHR_materials_emissive_strength");
    if (ext != mt.extensions.end()) {
        const Value *s = member(ext->second, "emissiveStrength");
        if (s && (!number(s, &strength) || strength < 0.0))
            fail(p + "/extensions/KHR_materials_emissive_strength/emissiveStrength",
                 "must be a number >= 0");
    }
    if (mt.emissiveFactor.size() != 3)
        fail(p + "/emissiveFactor", "needs 3 numbers");
    for (int k = 0; k < 3; k++) {
        double e = mt.emissiveFactor[static_cast<size_t>(k)];
        if (!finite(e) || e < 0.0)
            fail(p + "/emissiveFactor", "values must be finite and >= 0");
        if (!finite_float(e * strength))
            fail(p + "/extensions/KHR_materials_emissive_strength/emissiveStrength",
                 "emission overflows a float");
        g.emission[k] = static_cast<float>(e * strength);
    }
    const tinygltf::TextureInfo &ti = mt.pbrMetallicRoughness.baseColorTexture;
    if (ti.index != -1) {
        std::string tp = p + "/pbrMetallicRoughness/baseColorTexture";
        if (ti.texCoord != 0)
            fail(tp + "/texCoord", "only TEXCOORD_0 is supported");
        g.albedo_texture = texture(ti.index, tp + "/index");
    }
    g.double_sided = mt.doubleSided ? 1 : 0;
    read_phong(i, &g);
    materials.push_back(g);
    material_names.push_back(mt.name.empty() ? fmt("material%zu", i) : mt.name);
    warn_reduced(i, material_names.back());
}

/* The material model is Lambert + an optional Phong lobe (gi/scene.h);
 * whatever else a glTF material asks for is dropped, and said so, once per
 * material and feature, so that a researcher's own scene is not silently
 * rendered as something else (issue 28). */
void Converter::warn_reduced(size_t i, const std::string &name) const
{
    const tinygltf::Material &mt = m.materials[i];
    const tinygltf::PbrMetallicRoughness &pbr = mt.pbrMetallicRoughness;
    std::vector<std::string> dropped;
    if (pbr.metallicFactor > 0.0)
        dropped.push_back(
            fmt("metallicFactor %g (rendered as metallic 0: diffuse)", pbr.metallicFactor));
    if (pbr.metallicRoughnessTexture.index >= 0)
        dropped.push_back("metallicRoughnessTexture (ignored)");
    if (mt.normalTexture.index >= 0)
        dropped.push_back("normalTexture (ignored: vertex normals only)");
    if (mt.occlusionTexture.index >= 0)
        dropped.push_back("occlusionTexture (ignored)");
    if (mt.emissiveTexture.index >= 0)
        dropped.push_back("emissiveTexture (ignored: emissiveFactor only)");
    if (mt.alphaMode == "BLEND" || mt.alphaMode == "MASK")
        dropped.push_back("alphaMode " + mt.alphaMode + " (rendered opaque)");
    for (const auto &e : mt.extensions)
        if (e.first != "KHR_materials_emissive_strength")
            dropped.push_back(e.first + " (ignored)");
    for (const std::string &d : dropped)
        gi_log(GI_LOG_WARN, "%s: material '%s': %s", c.name.c_str(), name.c_str(), d.c_str());
}

/* extras {"gibench": {"phong": {"ks": [r,g,b], "exponent": n}, "mirror": b}} */
void Converter::read_phong(size_t i, gi_material *g)
{
    std::string p = fmt("/materials/%zu", i);
    const Value *gb = member(m.materials[i].extras, "gibench");
    if (!gb)
        return;
    std::string gp = p + "/extras/gibench";
    if (!gb->IsObject())
        fail(gp, "must be an object");
    bool has_ks = false;
    if (const Value *ph = member(*gb, "phong")) {
        if (!ph->IsObject())
            fail(gp + "/phong", "must be an object");
        const Value *ks = member(*ph, "ks");
        if (!ks || !ks->IsArray() || ks->ArrayLen() != 3)
            fail(gp + "/phong/ks", "must be 3 numbers in [0, 1]");
        const Value::Array &arr = ks->Get<Value::Array>();
        for (int k = 0; k < 3; k++) {
            double v = 0.0;
            if (!number(&arr[static_cast<size_t>(k)], &v) || v < 0.0 || v > 1.0)
                fail(gp + "/phong/ks", "must be 3 numbers in [0, 1]");
            g->ks[k] = static_cast<float>(v);
        }
        double n = 0.0;
        if (!number(member(*ph, "exponent"), &n) || n < 0.0)
            fail(gp + "/phong/exponent", "must be a number >= 0");
        g->exponent = static_cast<float>(std::min(n, 1e30)); /* past GI_MIRROR_EXPONENT anyway */
        has_ks = true;
    }
    if (const Value *mi = member(*gb, "mirror")) {
        if (!mi->IsBool())
            fail(gp + "/mirror", "must be true or false");
        g->mirror = mi->Get<bool>() ? 1 : 0;
    }
    if (g->exponent >= GI_MIRROR_EXPONENT)
        g->mirror = 1;
    if (g->mirror && !has_ks)
        fail(gp, "mirror needs phong.ks (its reflectance)");
    for (int k = 0; k < 3; k++)
        if (g->albedo[k] + g->ks[k] > 1.0001f)
            fail(p, fmt("albedo + ks = %.4g in channel %d exceeds 1 (the material would create "
                        "energy)",
                        static_cast<double>(g->albedo[k] + g->ks[k]), k));
}

void Converter::check_textures() const
{
    for (size_t i = 0; i < m.textures.size(); i++) {
        const tinygltf::Texture &t = m.textures[i];
        std::string p = fmt("/textures/%zu", i);
        if (t.source < -1 || t.source >= static_cast<int>(m.images.size()))
            fail(p + "/source", out_of_range("image", t.source, m.images.size(), "images"));
        if (t.sampler < -1 || t.sampler >= static_cast<int>(m.samplers.size()))
            fail(p + "/sampler", out_of_range("sampler", t.sampler, m.samplers.size(), "samplers"));
    }
}

/* Every image must decode, as tinygltf requires of those it decodes itself:
 * an external file it could not read left only a warning and no pixels;
 * images in buffer views are decoded here, their bounds checked already. */
void Converter::check_images()
{
    view_images.resize(m.images.size());
    for (size_t i = 0; i < m.images.size(); i++) {
        const tinygltf::Image &img = m.images[i];
        std::string p = fmt("/images/%zu", i), why;
        if (img.bufferView >= 0) {
            const tinygltf::BufferView &bv = m.bufferViews[static_cast<size_t>(img.bufferView)];
            const tinygltf::Buffer &b = m.buffers[static_cast<size_t>(bv.buffer)];
            tinygltf::Image &d = view_images[i];
            d.name = img.name;
            if (!decode_image(&d, static_cast<int>(i), b.data.data() + bv.byteOffset, bv.byteLength,
                              &c.image_texels, &why))
                fail(p, why);
        } else if (img.image.empty()) {
            fail(p, "image data could not be read" +
                        (img.uri.empty() ? std::string() : " from " + shown(img.uri)));
        }
    }
}

int Converter::texture(int index, const std::string &pointer)
{
    if (index < 0 || static_cast<size_t>(index) >= m.textures.size())
        fail(pointer, out_of_range("texture", index, m.textures.size(), "textures"));
    auto it = texture_of.find(index);
    if (it != texture_of.end())
        return it->second;
    convert_texture(index);
    texture_of[index] = static_cast<int>(textures.size() - 1);
    return static_cast<int>(textures.size() - 1);
}

/* Decoded sRGB texels -> linear float RGBA. */
void Converter::convert_texture(int index)
{
    const tinygltf::Texture &t = m.textures[static_cast<size_t>(index)];
    if (t.source < 0)
        fail(fmt("/textures/%d", index), "has no source image");
    const tinygltf::Image *img = &m.images[static_cast<size_t>(t.source)];
    if (img->bufferView >= 0)
        img = &view_images[static_cast<size_t>(t.source)];
    TextureData td;
    td.name = !t.name.empty() ? t.name : !img->name.empty() ? img->name : img->uri;
    td.width = static_cast<uint32_t>(img->width);
    td.height = static_cast<uint32_t>(img->height);
    texture_texels += static_cast<uint64_t>(td.width) * td.height;
    if (texture_texels > GI_MAX_TEXTURE_TEXELS)
        fail(fmt("/textures/%d", index),
             fmt("textures exceed the limit of %u texels in all (1 GiB as float RGBA)",
                 GI_MAX_TEXTURE_TEXELS));
    size_t n = static_cast<size_t>(td.width) * td.height * 4;
    td.rgba.resize(n);
    float lut[256];
    for (int v = 0; v < 256; v++)
        lut[v] = gi_srgb_decode(v / 255.0f);
    for (size_t k = 0; k < n; k++) {
        float v;
        if (img->bits == 16) {
            uint16_t s;
            memcpy(&s, &img->image[k * 2], 2);
            v = s / 65535.0f;
            td.rgba[k] = (k % 4 == 3) ? v : gi_srgb_decode(v);
        } else {
            v = img->image[k] / 255.0f;
            td.rgba[k] = (k % 4 == 3) ? v : lut[img->image[k]];
        }
    }
    textures.push_back(std::move(td));
}

/* ---- cameras, lights, nodes ---- */

void Converter::check_cameras() const
{
    for (size_t i = 0; i < m.cameras.size(); i++) {
        const tinygltf::Camera &cam = m.cameras[i];
        std::string p = fmt("/cameras/%zu", i);
        if (cam.type == "orthographic")
            fail(p, "orthographic cameras are not supported");
        const tinygltf::PerspectiveCamera &pc = cam.perspective;
        if (!finite(pc.yfov) || pc.yfov <= 0.0 || pc.yfov >= kPi)
            fail(p + "/perspective/yfov", "must lie in (0, pi)");
        if (!finite_float(pc.znear) || static_cast<float>(pc.znear) <= 0.0f)
            fail(p + "/perspective/znear", "must be > 0");
        if (!finite_float(pc.zfar) || (pc.zfar != 0.0 && pc.zfar <= pc.znear))
            fail(p + "/perspective/zfar", "must be > znear");
        if (!finite_float(pc.aspectRatio) || pc.aspectRatio < 0.0)
            fail(p + "/perspective/aspectRatio", "must be > 0");
    }
}

void Converter::check_lights() const
{
    for (size_t i = 0; i < m.lights.size(); i++) {
        const tinygltf::Light &l = m.lights[i];
        std::string p = fmt("/extensions/KHR_lights_punctual/lights/%zu", i);
        if (l.type != "point" && l.type != "spot" && l.type != "directional")
            fail(p + "/type", "light type " + shown(l.type) + " is not supported");
        if (!l.color.empty() && l.color.size() != 3)
            fail(p + "/color", "needs 3 numbers");
        for (double v : l.color)
            if (!finite(v) || v < 0.0 || !finite_float(v * l.intensity))
                fail(p + "/color", "values must be finite and >= 0");
        if (!finite_float(l.intensity) || l.intensity < 0.0)
            fail(p + "/intensity", "must be finite and >= 0");
        if (!finite_float(l.range) || l.range < 0.0)
            fail(p + "/range", "must be > 0");
        double in = l.spot.innerConeAngle, out = l.spot.outerConeAngle;
        if (l.type == "spot" &&
            !(finite(in) && finite(out) && in >= 0.0 && in < out && out <= kPi / 2 + 1e-6))
            fail(p + "/spot", "needs 0 <= innerConeAngle < outerConeAngle <= pi/2");
    }
}

/* The KHR_lights_punctual light of node i, or -1. */
int Converter::node_light(size_t i) const
{
    auto ext = m.nodes[i].extensions.find("KHR_lights_punctual");
    if (ext == m.nodes[i].extensions.end())
        return -1;
    std::string p = fmt("/nodes/%zu/extensions/KHR_lights_punctual/light", i);
    double v = 0.0;
    if (!number(member(ext->second, "light"), &v) || v != std::floor(v))
        fail(p, "must be a light index");
    if (v < 0.0 || v >= static_cast<double>(m.lights.size()))
        fail(p, fmt("light %.0f out of range (%zu lights)", v, m.lights.size()));
    return static_cast<int>(v);
}

/* Shepperd's method: unit quaternion (x, y, z, w) of rotation matrix r
 * (columns r[0..2]). */
void quat_from_matrix(const double r[3][3], float q[4])
{
    double m00 = r[0][0], m11 = r[1][1], m22 = r[2][2]; /* r[col][row] */
    double tr = m00 + m11 + m22, x, y, z, w;
    if (tr > 0.0) {
        double s = std::sqrt(tr + 1.0) * 2.0;
        w = 0.25 * s;
        x = (r[1][2] - r[2][1]) / s;
        y = (r[2][0] - r[0][2]) / s;
        z = (r[0][1] - r[1][0]) / s;
    } else if (m00 > m11 && m00 > m22) {
        double s = std::sqrt(1.0 + m00 - m11 - m22) * 2.0;
        w = (r[1][2] - r[2][1]) / s;
        x = 0.25 * s;
        y = (r[1][0] + r[0][1]) / s;
        z = (r[2][0] + r[0][2]) / s;
    } else if (m11 > m22) {
        double s = std::sqrt(1.0 + m11 - m00 - m22) * 2.0;
        w = (r[2][0] - r[0][2]) / s;
        x = (r[1][0] + r[0][1]) / s;
        y = 0.25 * s;
        z = (r[2][1] + r[1][2]) / s;
    } else {
        double s = std::sqrt(1.0 + m22 - m00 - m11) * 2.0;
        w = (r[0][1] - r[1][0]) / s;
        x = (r[2][0] + r[0][2]) / s;
        y = (r[2][1] + r[1][2]) / s;
        z = 0.25 * s;
    }
    double l = std::sqrt(x * x + y * y + z * z + w * w);
    q[0] = static_cast<float>(x / l);
    q[1] = static_cast<float>(y / l);
    q[2] = static_cast<float>(z / l);
    q[3] = static_cast<float>(w / l);
}

/* A node's matrix as translation, rotation, scale (glTF requires that it
 * decomposes; shear or projection is an error). */
void decompose(const std::vector<double> &mx, const std::string &p, NodeInfo *n)
{
    if (mx.size() != 16)
        fail(p, "needs 16 numbers");
    for (double v : mx)
        if (!finite_float(v))
            fail(p, "values must be finite");
    if (mx[3] != 0.0 || mx[7] != 0.0 || mx[11] != 0.0 || mx[15] != 1.0)
        fail(p, "is not affine (last row must be 0 0 0 1)");
    double r[3][3], s[3];
    for (int col = 0; col < 3; col++) {
        s[col] = std::sqrt(mx[col * 4] * mx[col * 4] + mx[col * 4 + 1] * mx[col * 4 + 1] +
                           mx[col * 4 + 2] * mx[col * 4 + 2]);
        n->t[col] = static_cast<float>(mx[12 + col]);
    }
    double det = mx[0] * (mx[5] * mx[10] - mx[6] * mx[9]) -
                 mx[4] * (mx[1] * mx[10] - mx[2] * mx[9]) + mx[8] * (mx[1] * mx[6] - mx[2] * mx[5]);
    if (det < 0.0)
        s[0] = -s[0];
    for (int col = 0; col < 3; col++) {
        if (!finite_float(s[col]))
            fail(p, "scale is not finite");
        n->s[col] = static_cast<float>(s[col]);
    }
    if (s[0] == 0.0 || s[1] == 0.0 || s[2] == 0.0)
        return; /* degenerate scale: rotation stays identity */
    for (int col = 0; col < 3; col++)
        for (int row = 0; row < 3; row++)
            r[col][row] = mx[col * 4 + row] / s[col];
    for (int a = 0; a < 3; a++)
        for (int b = a + 1; b < 3; b++) {
            double d = r[a][0] * r[b][0] + r[a][1] * r[b][1] + r[a][2] * r[b][2];
            if (std::fabs(d) > 1e-3)
                fail(p, "is not a translation-rotation-scale matrix (it has shear)");
        }
    quat_from_matrix(r, n->r);
}

void Converter::node_transform(size_t i)
{
    const tinygltf::Node &nd = m.nodes[i];
    std::string p = fmt("/nodes/%zu", i);
    NodeInfo &n = nodes[i];
    if (!nd.matrix.empty()) {
        decompose(nd.matrix, p + "/matrix", &n);
        return;
    }
    auto vec = [&](const std::vector<double> &v, size_t len, const char *key, float *out) {
        if (v.empty())
            return;
        if (v.size() != len)
            fail(p + "/" + key, fmt("needs %zu numbers", len));
        for (size_t k = 0; k < len; k++) {
            if (!finite_float(v[k]))
                fail(p + "/" + key, "values must be finite");
            out[k] = static_cast<float>(v[k]);
        }
    };
    vec(nd.translation, 3, "translation", n.t);
    vec(nd.rotation, 4, "rotation", n.r);
    vec(nd.scale, 3, "scale", n.s);
    double l = std::sqrt(double(n.r[0]) * n.r[0] + double(n.r[1]) * n.r[1] +
                         double(n.r[2]) * n.r[2] + double(n.r[3]) * n.r[3]);
    if (!(l > 1e-6))
        fail(p + "/rotation", "is not a unit quaternion (length 0)");
    for (float &q : n.r)
        q = static_cast<float>(q / l);
}

void Converter::check_nodes()
{
    nodes.assign(m.nodes.size(), NodeInfo());
    for (size_t i = 0; i < m.nodes.size(); i++) {
        const tinygltf::Node &nd = m.nodes[i];
        std::string p = fmt("/nodes/%zu", i);
        if (nd.mesh < -1 || nd.mesh >= static_cast<int>(m.meshes.size()))
            fail(p + "/mesh", out_of_range("mesh", nd.mesh, m.meshes.size(), "meshes"));
        if (nd.camera < -1 || nd.camera >= static_cast<int>(m.cameras.size()))
            fail(p + "/camera", out_of_range("camera", nd.camera, m.cameras.size(), "cameras"));
        if (nd.skin < -1 || nd.skin >= static_cast<int>(m.skins.size()))
            fail(p + "/skin", out_of_range("skin", nd.skin, m.skins.size(), "skins"));
        node_light(i);
        node_transform(i);
    }
    check_graph();
}

/* Children in range, one parent each, no cycles. */
void Converter::check_graph()
{
    size_t n = m.nodes.size();
    parents.assign(n, -1);
    for (size_t i = 0; i < n; i++) {
        const std::vector<int> &ch = m.nodes[i].children;
        for (size_t k = 0; k < ch.size(); k++) {
            std::string p = fmt("/nodes/%zu/children/%zu", i, k);
            int child = ch[k];
            if (child < 0 || static_cast<size_t>(child) >= n)
                fail(p, out_of_range("node", child, n, "nodes"));
            if (static_cast<size_t>(child) == i)
                fail(p, fmt("node %d is its own child (cycle)", child));
            if (parents[static_cast<size_t>(child)] >= 0)
                fail(p, fmt("node %d already has parent node %d (a node has at most one parent)",
                            child, parents[static_cast<size_t>(child)]));
            parents[static_cast<size_t>(child)] = static_cast<int>(i);
        }
    }
    /* With one parent each, a cycle is a parent chain that returns. */
    std::vector<char> state(n, 0); /* 0 unseen, 1 on the current chain, 2 done */
    std::vector<size_t> chain;
    for (size_t i = 0; i < n; i++) {
        chain.clear();
        long x = static_cast<long>(i);
        while (x >= 0 && state[static_cast<size_t>(x)] == 0) {
            state[static_cast<size_t>(x)] = 1;
            chain.push_back(static_cast<size_t>(x));
            x = parents[static_cast<size_t>(x)];
        }
        if (x >= 0 && state[static_cast<size_t>(x)] == 1) {
            int parent = parents[static_cast<size_t>(x)];
            const std::vector<int> &ch = m.nodes[static_cast<size_t>(parent)].children;
            size_t k = 0;
            while (k < ch.size() && ch[k] != x)
                k++;
            fail(fmt("/nodes/%d/children/%zu", parent, k),
                 fmt("node %ld is its own ancestor (cycle)", x));
        }
        for (size_t v : chain)
            state[v] = 2;
    }
}

/* The default scene (or the first; or, with no scenes, all root nodes) in
 * depth-first pre-order. */
void Converter::choose_scene()
{
    std::vector<int> roots;
    if (m.scenes.empty()) {
        if (m.defaultScene != -1)
            fail("/scene", out_of_range("scene", m.defaultScene, 0, "scenes"));
        for (size_t i = 0; i < m.nodes.size(); i++)
            if (parents[i] < 0)
                roots.push_back(static_cast<int>(i));
    } else {
        if (m.defaultScene < -1 || m.defaultScene >= static_cast<int>(m.scenes.size()))
            fail("/scene", out_of_range("scene", m.defaultScene, m.scenes.size(), "scenes"));
        scene_index = m.defaultScene >= 0 ? m.defaultScene : 0;
        for (size_t s = 0; s < m.scenes.size(); s++) {
            std::vector<char> listed(m.nodes.size(), 0);
            const std::vector<int> &sn = m.scenes[s].nodes;
            for (size_t k = 0; k < sn.size(); k++) {
                std::string p = fmt("/scenes/%zu/nodes/%zu", s, k);
                int v = sn[k];
                if (v < 0 || static_cast<size_t>(v) >= m.nodes.size())
                    fail(p, out_of_range("node", v, m.nodes.size(), "nodes"));
                if (parents[static_cast<size_t>(v)] >= 0)
                    fail(p, fmt("node %d is a child of node %d, not a root", v,
                                parents[static_cast<size_t>(v)]));
                if (listed[static_cast<size_t>(v)]++)
                    fail(p, fmt("node %d is listed twice", v));
            }
        }
        roots = m.scenes[static_cast<size_t>(scene_index)].nodes;
    }
    std::vector<int> stack(roots.rbegin(), roots.rend());
    while (!stack.empty()) {
        int v = stack.back();
        stack.pop_back();
        order.push_back(v);
        const std::vector<int> &ch = m.nodes[static_cast<size_t>(v)].children;
        stack.insert(stack.end(), ch.rbegin(), ch.rend());
    }
}

/* ---- meshes ---- */

const MeshData &Converter::mesh(int index)
{
    size_t mi = static_cast<size_t>(index);
    if (!mesh_done[mi]) {
        const tinygltf::Mesh &ms = m.meshes[mi];
        if (ms.primitives.empty())
            fail(fmt("/meshes/%zu/primitives", mi), "mesh has no primitives");
        for (size_t k = 0; k < ms.primitives.size(); k++)
            convert_primitive(mi, k, &meshes[mi]);
        MeshData &md = meshes[mi];
        if (!ms.weights.empty() && ms.weights.size() != md.morph_count)
            fail(fmt("/meshes/%zu/weights", mi),
                 fmt("has %zu weights but the mesh has %zu morph targets", ms.weights.size(),
                     md.morph_count));
        md.weights.assign(md.morph_count, 0.0f);
        for (size_t k = 0; k < ms.weights.size(); k++) {
            if (!finite_float(ms.weights[k]))
                fail(fmt("/meshes/%zu/weights/%zu", mi, k), "weight is not finite");
            md.weights[k] = static_cast<float>(ms.weights[k]);
        }
        mesh_done[mi] = true;
    }
    return meshes[mi];
}

int attribute(const tinygltf::Primitive &prim, const char *name)
{
    auto it = prim.attributes.find(name);
    return it == prim.attributes.end() ? -1 : it->second;
}

void Converter::read_positions(const std::string &pp, int acc, std::vector<gi_vertex> *v)
{
    const tinygltf::Accessor &a = m.accessors[static_cast<size_t>(acc)];
    check_accessor_kind(acc, "POSITION",
                        a.type == TINYGLTF_TYPE_VEC3 &&
                            a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT);
    if (a.count > GI_MAX_VERTICES)
        fail(pp, fmt("%zu vertices exceed the limit of %u", a.count, GI_MAX_VERTICES));
    Reader r = reader(acc);
    v->assign(a.count, gi_vertex());
    for (size_t e = 0; e < a.count; e++)
        for (int k = 0; k < 3; k++) {
            double x = r.get(e, static_cast<uint64_t>(k));
            if (!finite(x))
                fail(fmt("/accessors/%d", acc), fmt("POSITION element %zu is not finite", e));
            (*v)[e].position[k] = static_cast<float>(x);
        }
}

/* Normals as given, normalised; zero ones in a NORMAL accessor (no
 * direction given) become the area-weighted average of the adjacent faces'
 * normals in this primitive. A primitive without NORMAL gets flat_normals. */
void smooth_normals(std::vector<gi_vertex> *v, const std::vector<uint32_t> &idx,
                    const std::vector<bool> &need)
{
    std::vector<double> acc(v->size() * 3, 0.0);
    for (size_t t = 0; t + 2 < idx.size(); t += 3) {
        const float *a = (*v)[idx[t]].position, *b = (*v)[idx[t + 1]].position,
                    *c = (*v)[idx[t + 2]].position;
        double e1[3], e2[3];
        for (int k = 0; k < 3; k++) {
            e1[k] = double(b[k]) - a[k];
            e2[k] = double(c[k]) - a[k];
        }
        double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                       e1[0] * e2[1] - e1[1] * e2[0]}; /* length = 2 x area */
        for (int j = 0; j < 3; j++)
            for (int k = 0; k < 3; k++)
                acc[idx[t + static_cast<size_t>(j)] * 3 + static_cast<size_t>(k)] += n[k];
    }
    for (size_t i = 0; i < v->size(); i++) {
        if (!need[i])
            continue;
        double *n = &acc[i * 3];
        double l = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        float *out = (*v)[i].normal;
        if (l > 0.0 && std::isfinite(l)) {
            for (int k = 0; k < 3; k++)
                out[k] = static_cast<float>(n[k] / l);
        } else { /* unused vertex or only degenerate faces: any unit vector */
            out[0] = 0.0f;
            out[1] = 0.0f;
            out[2] = 1.0f;
        }
    }
}

/* glTF 2.0 §3.7.2.1: "When normals are not specified, client
 * implementations MUST calculate flat normals". Every triangle gets its own
 * three vertices carrying its face normal (cross(p1 - p0, p2 - p0), the
 * front of a counter-clockwise triangle); a degenerate one gets +Z. The
 * morph displacements of the primitive (appended at first_vertex by
 * read_targets) are unshared the same way. */
void flat_normals(std::vector<gi_vertex> *v, std::vector<uint32_t> *idx, size_t first_vertex,
                  MeshData *out)
{
    std::vector<gi_vertex> flat(idx->size());
    for (size_t t = 0; t + 2 < idx->size(); t += 3) {
        const float *a = (*v)[(*idx)[t]].position, *b = (*v)[(*idx)[t + 1]].position,
                    *c = (*v)[(*idx)[t + 2]].position;
        double e1[3], e2[3];
        for (int k = 0; k < 3; k++) {
            e1[k] = double(b[k]) - a[k];
            e2[k] = double(c[k]) - a[k];
        }
        double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                       e1[0] * e2[1] - e1[1] * e2[0]};
        double l = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (size_t j = 0; j < 3; j++) {
            gi_vertex x = (*v)[(*idx)[t + j]];
            for (int k = 0; k < 3; k++)
                x.normal[k] = l > 0.0 && std::isfinite(l) ? static_cast<float>(n[k] / l)
                                                          : (k == 2 ? 1.0f : 0.0f);
            flat[t + j] = x;
        }
    }
    for (size_t k = 0; k < out->morph_count; k++)
        for (std::vector<float> *d : {&out->tpos[k], &out->tnrm[k]}) {
            std::vector<float> seg(idx->size() * 3, 0.0f);
            for (size_t i = 0; i < idx->size(); i++)
                for (size_t c = 0; c < 3; c++)
                    seg[i * 3 + c] = (*d)[(first_vertex + (*idx)[i]) * 3 + c];
            d->resize(first_vertex * 3);
            d->insert(d->end(), seg.begin(), seg.end());
        }
    *v = std::move(flat);
    for (size_t i = 0; i < idx->size(); i++)
        (*idx)[i] = static_cast<uint32_t>(i);
}

void Converter::read_normals(const std::string &pp, int acc, std::vector<gi_vertex> *v)
{
    const tinygltf::Accessor &a = m.accessors[static_cast<size_t>(acc)];
    check_accessor_kind(acc, "NORMAL",
                        a.type == TINYGLTF_TYPE_VEC3 &&
                            a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT);
    if (a.count != v->size())
        fail(pp + "/attributes/NORMAL",
             fmt("accessor %d has %zu elements but POSITION has %zu", acc, a.count, v->size()));
    Reader r = reader(acc);
    for (size_t e = 0; e < a.count; e++) {
        double n[3], l2 = 0.0;
        for (int k = 0; k < 3; k++) {
            n[k] = r.get(e, static_cast<uint64_t>(k));
            if (!finite(n[k]))
                fail(fmt("/accessors/%d", acc), fmt("NORMAL element %zu is not finite", e));
            l2 += n[k] * n[k];
        }
        double l = std::sqrt(l2);
        for (int k = 0; k < 3; k++) /* zero length: left 0 and recomputed */
            (*v)[e].normal[k] = l > 0.0 ? static_cast<float>(n[k] / l) : 0.0f;
    }
}

void Converter::read_uvs(const std::string &pp, int acc, std::vector<gi_vertex> *v)
{
    const tinygltf::Accessor &a = m.accessors[static_cast<size_t>(acc)];
    bool ok = a.type == TINYGLTF_TYPE_VEC2 &&
              (a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT ||
               (a.normalized && (a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                                 a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT)));
    check_accessor_kind(acc, "TEXCOORD_0", ok);
    if (a.count != v->size())
        fail(pp + "/attributes/TEXCOORD_0",
             fmt("accessor %d has %zu elements but POSITION has %zu", acc, a.count, v->size()));
    Reader r = reader(acc);
    for (size_t e = 0; e < a.count; e++)
        for (int k = 0; k < 2; k++) {
            double x = r.get(e, static_cast<uint64_t>(k));
            if (!finite_float(x))
                fail(fmt("/accessors/%d", acc), fmt("TEXCOORD_0 element %zu is not finite", e));
            (*v)[e].uv[k] = static_cast<float>(x);
        }
}

void Converter::read_indices(const std::string &pp, const tinygltf::Primitive &prim, size_t nv,
                             std::vector<uint32_t> *out)
{
    if (prim.indices == -1) {
        if (nv % 3 != 0)
            fail(pp, fmt("non-indexed primitive has %zu vertices, not a multiple of 3", nv));
        out->resize(nv);
        for (size_t i = 0; i < nv; i++)
            (*out)[i] = static_cast<uint32_t>(i);
        return;
    }
    if (prim.indices < 0 || static_cast<size_t>(prim.indices) >= m.accessors.size())
        fail(pp + "/indices",
             out_of_range("accessor", prim.indices, m.accessors.size(), "accessors"));
    const tinygltf::Accessor &a = m.accessors[static_cast<size_t>(prim.indices)];
    check_accessor_kind(prim.indices, "indices",
                        a.type == TINYGLTF_TYPE_SCALAR && !a.normalized &&
                            (a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                             a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ||
                             a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT));
    if (a.count % 3 != 0)
        fail(pp + "/indices", fmt("index count %zu is not a multiple of 3", a.count));
    if (a.count / 3 > GI_MAX_TRIANGLES)
        fail(pp + "/indices",
             fmt("%zu triangles exceed the limit of %u", a.count / 3, GI_MAX_TRIANGLES));
    Reader r = reader(prim.indices);
    out->resize(a.count);
    for (size_t e = 0; e < a.count; e++) {
        double x = r.get(e, 0);
        if (x >= static_cast<double>(nv))
            fail(pp + "/indices", fmt("index %.0f (element %zu of accessor %d) >= vertex count %zu",
                                      x, e, prim.indices, nv));
        (*out)[e] = static_cast<uint32_t>(x);
    }
}

/* Morph targets of one primitive (glTF 2.0 §3.7.2.2): POSITION and NORMAL
 * displacements, float VEC3, one per vertex; TANGENT is ignored (there are
 * no normal maps). Every primitive of a mesh must have as many targets. */
void Converter::read_targets(const std::string &pp, const tinygltf::Primitive &prim, size_t nv,
                             bool first_prim, MeshData *out)
{
    size_t first_vertex = out->vertices.size(); /* this primitive's vertices are appended after */
    if (first_prim) {
        out->morph_count = prim.targets.size();
        out->tpos.assign(out->morph_count, std::vector<float>());
        out->tnrm.assign(out->morph_count, std::vector<float>());
    } else if (prim.targets.size() != out->morph_count) {
        fail(pp + "/targets", fmt("has %zu morph targets but the mesh's first primitive has %zu",
                                  prim.targets.size(), out->morph_count));
    }
    if (prim.targets.size() > 255)
        fail(pp + "/targets",
             fmt("%zu morph targets exceed the limit of 255", prim.targets.size()));
    /* Displacements are stored per target for every vertex of the mesh: as
     * many as GI_MAX_VERTICES vertices at most, like the vertices. */
    if (prim.targets.size() && (first_vertex + nv) * prim.targets.size() > GI_MAX_VERTICES)
        fail(pp + "/targets", fmt("%zu morph targets x %zu vertices exceed the limit of %u",
                                  prim.targets.size(), first_vertex + nv, GI_MAX_VERTICES));
    for (size_t k = 0; k < prim.targets.size(); k++) {
        std::string pt = fmt("%s/targets/%zu", pp.c_str(), k);
        std::vector<float> *dst[2] = {&out->tpos[k], &out->tnrm[k]};
        const char *names[2] = {"POSITION", "NORMAL"};
        if (prim.targets[k].empty())
            fail(pt, "morph target has no attribute");
        for (const auto &attr : prim.targets[k])
            if (attr.first != "POSITION" && attr.first != "NORMAL" && attr.first != "TANGENT")
                fail(pt + "/" + attr.first, "morph target attribute " + shown(attr.first) +
                                                " is not supported (POSITION, NORMAL, TANGENT)");
        for (int j = 0; j < 2; j++) {
            dst[j]->resize((first_vertex + nv) * 3, 0.0f);
            auto it = prim.targets[k].find(names[j]);
            if (it == prim.targets[k].end())
                continue;
            int acc = it->second;
            if (acc < 0 || static_cast<size_t>(acc) >= m.accessors.size())
                fail(pt + "/" + names[j],
                     out_of_range("accessor", acc, m.accessors.size(), "accessors"));
            const tinygltf::Accessor &a = m.accessors[static_cast<size_t>(acc)];
            check_accessor_kind(acc, j == 0 ? "morph target POSITION" : "morph target NORMAL",
                                a.type == TINYGLTF_TYPE_VEC3 &&
                                    a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT);
            if (a.count != nv)
                fail(pt + "/" + names[j],
                     fmt("accessor %d has %zu elements but POSITION has %zu", acc, a.count, nv));
            if (j == 1)
                out->morph_normals = true;
            Reader r = reader(acc);
            for (size_t e = 0; e < nv; e++)
                for (int ax = 0; ax < 3; ax++) {
                    double x = r.get(e, static_cast<uint64_t>(ax));
                    if (!finite_float(x))
                        fail(fmt("/accessors/%d", acc),
                             fmt("morph target %s element %zu is not finite", names[j], e));
                    (*dst[j])[(first_vertex + e) * 3 + static_cast<size_t>(ax)] =
                        static_cast<float>(x);
                }
        }
    }
}

void Converter::convert_primitive(size_t mi, size_t k, MeshData *out)
{
    const tinygltf::Primitive &prim = m.meshes[mi].primitives[k];
    std::string pp = fmt("/meshes/%zu/primitives/%zu", mi, k);
    if (prim.mode != TINYGLTF_MODE_TRIANGLES)
        fail(pp + "/mode", fmt("mode %d (%s) is not supported; only triangles (4)", prim.mode,
                               mode_name(prim.mode)));
    int pos = attribute(prim, "POSITION"), nrm = attribute(prim, "NORMAL"),
        tex = attribute(prim, "TEXCOORD_0");
    if (prim.attributes.count("POSITION") == 0)
        fail(pp + "/attributes", "POSITION is missing");
    const char *names[3] = {"POSITION", "NORMAL", "TEXCOORD_0"};
    int accs[3] = {pos, nrm, tex};
    for (int j = 0; j < 3; j++)
        if (prim.attributes.count(names[j]) &&
            (accs[j] < 0 || static_cast<size_t>(accs[j]) >= m.accessors.size()))
            fail(pp + "/attributes/" + names[j],
                 out_of_range("accessor", accs[j], m.accessors.size(), "accessors"));
    int material = prim.material;
    if (material < -1 || material >= static_cast<int>(m.materials.size()))
        fail(pp + "/material", out_of_range("material", material, m.materials.size(), "materials"));
    if (material == -1) {
        if (default_material < 0) {
            gi_material g = {};
            g.albedo[0] = g.albedo[1] = g.albedo[2] = 0.8f;
            g.albedo_texture = -1;
            default_material = static_cast<int>(materials.size());
            materials.push_back(g);
            material_names.push_back("default");
        }
        material = default_material;
    }

    std::vector<gi_vertex> v;
    std::vector<uint32_t> idx;
    read_positions(pp, pos, &v);
    std::vector<bool> need(v.size(), true);
    if (nrm != -1) {
        read_normals(pp, nrm, &v);
        for (size_t i = 0; i < v.size(); i++)
            need[i] = v[i].normal[0] == 0.0f && v[i].normal[1] == 0.0f && v[i].normal[2] == 0.0f;
    }
    if (tex != -1)
        read_uvs(pp, tex, &v);
    read_indices(pp, prim, v.size(), &idx);
    size_t first_vertex = out->vertices.size();
    read_targets(pp, prim, v.size(), k == 0, out);
    if (nrm == -1)
        flat_normals(&v, &idx, first_vertex, out);
    else
        smooth_normals(&v, idx, need);
    if (nrm == -1 || !out->flat.empty()) {
        out->flat.resize(out->indices.size() / 3, 0);
        out->flat.resize((out->indices.size() + idx.size()) / 3, nrm == -1 ? 1 : 0);
    }

    if (out->vertices.size() + v.size() > GI_MAX_VERTICES)
        fail(pp, fmt("mesh exceeds the limit of %u vertices", GI_MAX_VERTICES));
    if ((out->indices.size() + idx.size()) / 3 > GI_MAX_TRIANGLES)
        fail(pp, fmt("mesh exceeds the limit of %u triangles", GI_MAX_TRIANGLES));
    uint32_t base = static_cast<uint32_t>(out->vertices.size());
    for (gi_vertex &x : v)
        x.material = static_cast<uint32_t>(material);
    out->vertices.insert(out->vertices.end(), v.begin(), v.end());
    for (uint32_t i : idx)
        out->indices.push_back(base + i);
}

/* One object per scene node with a mesh, in scene order, after checking
 * the totals against the limits (before any copy); then the meshes no node
 * uses, validated and dropped. */
void Converter::instantiate()
{
    mesh_done.assign(m.meshes.size(), false);
    meshes.assign(m.meshes.size(), MeshData());
    check_totals();
    for (int v : order) {
        const tinygltf::Node &nd = m.nodes[static_cast<size_t>(v)];
        if (nd.mesh >= 0)
            add_object(v);
        if (nd.camera >= 0)
            add_camera(v);
        if (node_light(static_cast<size_t>(v)) >= 0)
            add_light(v);
    }
    for (size_t mi = 0; mi < m.meshes.size(); mi++)
        if (!mesh_done[mi]) {
            mesh(static_cast<int>(mi));
            meshes[mi] = MeshData();
        }
}

void Converter::check_totals()
{
    uint64_t objs = 0, verts = 0, tris = 0;
    for (int v : order) {
        const tinygltf::Node &nd = m.nodes[static_cast<size_t>(v)];
        if (nd.mesh < 0)
            continue;
        std::string p = fmt("/nodes/%d", v);
        if (++objs > GI_MAX_OBJECTS)
            fail(p, fmt("more than %d objects (nodes with a mesh) in the scene", GI_MAX_OBJECTS));
        const MeshData &md = mesh(nd.mesh);
        verts += md.vertices.size();
        tris += md.indices.size() / 3;
        /* Triangles first: flat normals give every triangle its own three
         * vertices, so the vertex limit (three per triangle) follows it. */
        if (tris > GI_MAX_TRIANGLES)
            fail(p, fmt("scene exceeds the limit of %u triangles", GI_MAX_TRIANGLES));
        if (verts > GI_MAX_VERTICES)
            fail(p, fmt("scene exceeds the limit of %u vertices", GI_MAX_VERTICES));
    }
    vertices.reserve(verts);
    indices.reserve(tris * 3);
}

void Converter::add_camera(int node)
{
    const tinygltf::Node &nd = m.nodes[static_cast<size_t>(node)];
    const tinygltf::Camera &cam = m.cameras[static_cast<size_t>(nd.camera)];
    gi_camera g = {};
    g.node = node;
    g.yfov = static_cast<float>(cam.perspective.yfov);
    g.aspect = static_cast<float>(cam.perspective.aspectRatio);
    g.znear = static_cast<float>(cam.perspective.znear);
    g.zfar = static_cast<float>(cam.perspective.zfar);
    cameras.push_back(g);
    camera_names.push_back(!cam.name.empty() ? cam.name : nd.name);
}

void Converter::add_light(int node)
{
    const tinygltf::Light &l = m.lights[static_cast<size_t>(node_light(static_cast<size_t>(node)))];
    gi_light g = {};
    g.node = node;
    g.type = l.type == "point"  ? GI_LIGHT_POINT
             : l.type == "spot" ? GI_LIGHT_SPOT
                                : GI_LIGHT_DIRECTIONAL;
    for (int k = 0; k < 3; k++)
        g.intensity[k] = static_cast<float>(
            (l.color.empty() ? 1.0 : l.color[static_cast<size_t>(k)]) * l.intensity);
    g.range = static_cast<float>(l.range);
    if (g.type == GI_LIGHT_SPOT) {
        g.inner_cone = static_cast<float>(l.spot.innerConeAngle);
        g.outer_cone = static_cast<float>(l.spot.outerConeAngle);
    }
    lights.push_back(g);
    light_names.push_back(!l.name.empty() ? l.name : m.nodes[static_cast<size_t>(node)].name);
}

void Converter::add_object(int node)
{
    const tinygltf::Node &nd = m.nodes[static_cast<size_t>(node)];
    const MeshData &md = mesh(nd.mesh); /* totals checked by check_totals */
    gi_object o = {};
    o.node = node;
    o.first_vertex = static_cast<uint32_t>(vertices.size());
    o.vertex_count = static_cast<uint32_t>(md.vertices.size());
    o.first_triangle = static_cast<uint32_t>(indices.size() / 3);
    o.triangle_count = static_cast<uint32_t>(md.indices.size() / 3);
    uint32_t id = static_cast<uint32_t>(objects.size());
    for (int k = 0; k < 3; k++) {
        o.local_bounds[k] = INFINITY;
        o.local_bounds[k + 3] = -INFINITY;
    }
    for (gi_vertex v : md.vertices) {
        v.object = id;
        for (int k = 0; k < 3; k++) {
            o.local_bounds[k] = std::min(o.local_bounds[k], v.position[k]);
            o.local_bounds[k + 3] = std::max(o.local_bounds[k + 3], v.position[k]);
        }
        vertices.push_back(v);
    }
    for (uint32_t i : md.indices)
        indices.push_back(o.first_vertex + i);
    ObjectMorph om;
    o.morph_count = static_cast<uint32_t>(md.morph_count);
    std::string pw = fmt("/nodes/%d/weights", node);
    if (!nd.weights.empty() && nd.weights.size() != md.morph_count)
        fail(pw, fmt("has %zu weights but mesh %d has %zu morph targets", nd.weights.size(),
                     nd.mesh, md.morph_count));
    om.weights = md.weights;
    for (size_t k = 0; k < nd.weights.size(); k++) {
        if (!finite_float(nd.weights[k]))
            fail(fmt("%s/%zu", pw.c_str(), k), "weight is not finite");
        om.weights[k] = static_cast<float>(nd.weights[k]);
    }
    for (size_t k = 0; k < md.morph_count; k++) {
        om.pos.insert(om.pos.end(), md.tpos[k].begin(), md.tpos[k].end());
        if (md.morph_normals)
            om.nrm.insert(om.nrm.end(), md.tnrm[k].begin(), md.tnrm[k].end());
    }
    om.flat = md.flat;
    objects.push_back(o);
    object_morphs.push_back(std::move(om));
    const std::string &mesh_name = m.meshes[static_cast<size_t>(nd.mesh)].name;
    object_names.push_back(!nd.name.empty()     ? nd.name
                           : !mesh_name.empty() ? mesh_name
                                                : fmt("node%d", node));
}

/* ---- animation ---- */

void Converter::convert_animations()
{
    for (size_t a = 0; a < m.animations.size(); a++)
        for (size_t k = 0; k < m.animations[a].channels.size(); k++)
            convert_channel(a, k);
    for (gi_object &o : objects) {
        for (int v = o.node; v >= 0 && !o.animated; v = parents[static_cast<size_t>(v)])
            for (const Track &t : nodes[static_cast<size_t>(v)].anim)
                if (!t.times.empty())
                    o.animated = 1;
    }
    for (size_t i = 0; i < objects.size(); i++)
        if (objects[i].morph_count)
            morph_bounds(&objects[i], object_morphs[i],
                         nodes[static_cast<size_t>(objects[i].node)].weights);
}

/* Local bounds of a morphing object over every weight it takes: a LINEAR
 * or STEP track stays within its keys' range (held outside them), so per
 * target k the weight lies in [lo_k, hi_k] and per vertex and axis the box
 * of base + sum_k w_k d_k is base + sum_k min/max(lo_k d_k, hi_k d_k). */
void Converter::morph_bounds(gi_object *o, const ObjectMorph &om, const Track &tr) const
{
    size_t n = o->morph_count, nv = o->vertex_count;
    std::vector<float> lo(om.weights), hi(om.weights);
    if (!tr.times.empty()) {
        lo.assign(n, INFINITY);
        hi.assign(n, -INFINITY);
        for (size_t e = 0; e < tr.times.size(); e++)
            for (size_t k = 0; k < n; k++) {
                lo[k] = std::min(lo[k], tr.values[e * n + k]);
                hi[k] = std::max(hi[k], tr.values[e * n + k]);
            }
    }
    for (int k = 0; k < 3; k++) {
        o->local_bounds[k] = INFINITY;
        o->local_bounds[k + 3] = -INFINITY;
    }
    for (size_t i = 0; i < nv; i++)
        for (int ax = 0; ax < 3; ax++) {
            double a = vertices[o->first_vertex + i].position[ax], b = a;
            for (size_t k = 0; k < n; k++) {
                double d = om.pos[(k * nv + i) * 3 + static_cast<size_t>(ax)];
                a += std::min(lo[k] * d, hi[k] * d);
                b += std::max(lo[k] * d, hi[k] * d);
            }
            o->local_bounds[ax] = std::min(o->local_bounds[ax], static_cast<float>(a));
            o->local_bounds[ax + 3] = std::max(o->local_bounds[ax + 3], static_cast<float>(b));
        }
}

void Converter::convert_channel(size_t a, size_t k)
{
    const tinygltf::Animation &an = m.animations[a];
    const tinygltf::AnimationChannel &ch = an.channels[k];
    std::string pc = fmt("/animations/%zu/channels/%zu", a, k);
    if (ch.sampler < 0 || static_cast<size_t>(ch.sampler) >= an.samplers.size())
        fail(pc + "/sampler", out_of_range("sampler", ch.sampler, an.samplers.size(), "samplers"));
    if (ch.target_node == -1)
        return; /* no target: defined by an extension we do not have */
    if (ch.target_node < 0 || static_cast<size_t>(ch.target_node) >= m.nodes.size())
        fail(pc + "/target/node", out_of_range("node", ch.target_node, m.nodes.size(), "nodes"));
    int path = ch.target_path == "translation" ? 0
               : ch.target_path == "rotation"  ? 1
               : ch.target_path == "scale"     ? 2
                                               : -1;
    size_t width = path == 1 ? 4 : 3;
    if (ch.target_path == "weights") {
        int mesh_index = m.nodes[static_cast<size_t>(ch.target_node)].mesh;
        if (mesh_index < 0)
            fail(pc + "/target/node",
                 fmt("node %d animates morph weights but has no mesh", ch.target_node));
        width = mesh(mesh_index).morph_count;
        if (width == 0)
            fail(pc + "/target/node",
                 fmt("node %d animates morph weights but mesh %d has no morph targets",
                     ch.target_node, mesh_index));
        path = 3;
    }
    if (path < 0)
        fail(pc + "/target/path", "path " + shown(ch.target_path) + " is not supported");
    const tinygltf::AnimationSampler &s = an.samplers[static_cast<size_t>(ch.sampler)];
    std::string ps = fmt("/animations/%zu/samplers/%d", a, ch.sampler);
    if (s.interpolation == "CUBICSPLINE")
        fail(ps + "/interpolation",
             "CUBICSPLINE interpolation is not supported (use LINEAR or STEP)");
    if (s.interpolation != "LINEAR" && s.interpolation != "STEP")
        fail(ps + "/interpolation",
             "interpolation " + shown(s.interpolation) + " is not supported");
    if (s.input < 0 || static_cast<size_t>(s.input) >= m.accessors.size())
        fail(ps + "/input", out_of_range("accessor", s.input, m.accessors.size(), "accessors"));
    if (s.output < 0 || static_cast<size_t>(s.output) >= m.accessors.size())
        fail(ps + "/output", out_of_range("accessor", s.output, m.accessors.size(), "accessors"));
    const tinygltf::Accessor &in = m.accessors[static_cast<size_t>(s.input)];
    const tinygltf::Accessor &out = m.accessors[static_cast<size_t>(s.output)];
    check_accessor_kind(s.input, "animation input",
                        in.type == TINYGLTF_TYPE_SCALAR &&
                            in.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT);
    bool float_out = out.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT;
    bool norm_out = out.normalized && out.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
    bool ok = path == 1   ? out.type == TINYGLTF_TYPE_VEC4 && (float_out || norm_out)
              : path == 3 ? out.type == TINYGLTF_TYPE_SCALAR && (float_out || norm_out)
                          : out.type == TINYGLTF_TYPE_VEC3 && float_out;
    check_accessor_kind(s.output,
                        path == 1   ? "rotation output"
                        : path == 3 ? "weights output"
                                    : "translation/scale output",
                        ok);
    if (path == 3) { /* one scalar per target per key (§3.11) */
        if (out.count != in.count * width)
            fail(ps + "/output",
                 fmt("weights output has %zu values but %zu keys x %zu morph targets = %zu",
                     out.count, in.count, width, in.count * width));
    } else if (out.count != in.count) {
        fail(ps + "/output", fmt("output has %zu keys but input has %zu", out.count, in.count));
    }
    NodeInfo &ni = nodes[static_cast<size_t>(ch.target_node)];
    Track &t = path == 3 ? ni.weights : ni.anim[path];
    if (!t.times.empty())
        fail(pc, fmt("node %d %s is already animated by another channel", ch.target_node,
                     ch.target_path.c_str()));
    Reader ri = reader(s.input), ro = reader(s.output);
    std::string pi = fmt("/accessors/%d", s.input), po = fmt("/accessors/%d", s.output);
    t.step = s.interpolation == "STEP";
    for (size_t e = 0; e < in.count; e++) {
        float time = static_cast<float>(ri.get(e, 0));
        if (!std::isfinite(time) || time < 0.0f)
            fail(pi, fmt("animation time %zu is negative or not finite", e));
        if (e > 0 && !(time > t.times.back()))
            fail(pi, fmt("animation times not strictly increasing at element %zu (%g after %g)", e,
                         static_cast<double>(time), static_cast<double>(t.times.back())));
        t.times.push_back(time);
        double l2 = 0.0;
        for (size_t j = 0; j < width; j++) {
            /* weights: scalar accessor, element e * width + j */
            double x = path == 3 ? ro.get(e * width + j, 0) : ro.get(e, j);
            if (!finite_float(x))
                fail(po, fmt("animation value %zu is not finite", e));
            t.values.push_back(static_cast<float>(x));
            l2 += x * x;
        }
        if (path == 1) {
            double l = std::sqrt(l2);
            if (!(l > 1e-6))
                fail(po, fmt("rotation key %zu is not a unit quaternion (length 0)", e));
            for (size_t j = t.values.size() - 4; j < t.values.size(); j++)
                t.values[j] = static_cast<float>(t.values[j] / l);
        }
    }
    animation_length = std::max(animation_length, t.times.back());
}

/* ---- environment ---- */

void Converter::read_environment()
{
    if (scene_index < 0)
        return;
    const Value *gb = member(m.scenes[static_cast<size_t>(scene_index)].extras, "gibench");
    std::string pg = fmt("/scenes/%d/extras/gibench", scene_index);
    if (!gb)
        return;
    if (!gb->IsObject())
        fail(pg, "must be an object");
    const Value *env = member(*gb, "environment");
    if (!env)
        return;
    std::string pe = pg + "/environment";
    if (!env->IsObject())
        fail(pe, "must be an object");
    const Value *uri = member(*env, "uri");
    if (!uri || !uri->IsString())
        fail(pe + "/uri", "must be a string");
    env_uri = uri->Get<std::string>();
    if (is_data_uri(env_uri))
        fail(pe + "/uri", "must name a file (data: URIs are not supported here)");
    env_path = resolve_uri(c, pe + "/uri", env_uri);
    double v = 1.0;
    if (const Value *in = member(*env, "intensity")) {
        if (!number(in, &v) || v < 0.0 || !finite_float(v))
            fail(pe + "/intensity", "must be a number >= 0");
        env_intensity = static_cast<float>(v);
    }
    if (const Value *rot = member(*env, "rotation_deg")) {
        if (!number(rot, &v) || std::fabs(v) > 1e6)
            fail(pe + "/rotation_deg", "must be a number of degrees");
        env_rotation = static_cast<float>(v);
    }
    has_env = true;
}

/* ---- output ---- */

template <class T> T *copy_array(const std::vector<T> &v)
{
    if (v.empty())
        return nullptr;
    T *p = static_cast<T *>(malloc(v.size() * sizeof(T)));
    if (!p)
        throw std::bad_alloc();
    memcpy(p, v.data(), v.size() * sizeof(T));
    return p;
}

char *copy_string(const std::string &s)
{
    char *p = static_cast<char *>(malloc(s.size() + 1));
    if (!p)
        throw std::bad_alloc();
    memcpy(p, s.c_str(), s.size() + 1);
    return p;
}

void fill_track(gi_track *dst, const Track &src)
{
    dst->count = static_cast<uint32_t>(src.times.size());
    dst->step = src.step ? 1 : 0;
    dst->times = copy_array(src.times);
    dst->values = copy_array(src.values);
}

/* The output's arrays, each filled by one of these from build() (a throw
 * leaves what is already there to gi_scene_free). */
void Converter::copy_geometry(gi_scene *s) const
{
    s->vertices = copy_array(vertices);
    s->vertex_count = static_cast<uint32_t>(vertices.size());
    s->indices = copy_array(indices);
    s->triangle_count = static_cast<uint32_t>(indices.size() / 3);
}

void Converter::copy_materials(gi_scene *s) const
{
    s->materials = static_cast<gi_material *>(calloc(materials.size() + 1, sizeof(gi_material)));
    if (!s->materials)
        throw std::bad_alloc();
    s->material_count = static_cast<uint32_t>(materials.size());
    for (size_t i = 0; i < materials.size(); i++) {
        s->materials[i] = materials[i];
        s->materials[i].name = nullptr;
        s->materials[i].name = copy_string(material_names[i]);
    }
}

void Converter::copy_textures(gi_scene *s) const
{
    s->textures = static_cast<gi_texture *>(calloc(textures.size() + 1, sizeof(gi_texture)));
    if (!s->textures)
        throw std::bad_alloc();
    s->texture_count = static_cast<uint32_t>(textures.size());
    for (size_t i = 0; i < textures.size(); i++) {
        s->textures[i].width = textures[i].width;
        s->textures[i].height = textures[i].height;
        s->textures[i].name = copy_string(textures[i].name);
        s->textures[i].rgba = copy_array(textures[i].rgba);
    }
}

void Converter::copy_nodes(gi_scene *s) const
{
    s->nodes = static_cast<gi_node *>(calloc(nodes.size() + 1, sizeof(gi_node)));
    if (!s->nodes)
        throw std::bad_alloc();
    s->node_count = static_cast<uint32_t>(nodes.size());
    for (size_t i = 0; i < nodes.size(); i++) {
        gi_node &g = s->nodes[i];
        g.parent = parents[i];
        memcpy(g.translation, nodes[i].t, sizeof g.translation);
        memcpy(g.rotation, nodes[i].r, sizeof g.rotation);
        memcpy(g.scale, nodes[i].s, sizeof g.scale);
        g.name = copy_string(m.nodes[i].name);
        fill_track(&g.anim_t, nodes[i].anim[0]);
        fill_track(&g.anim_r, nodes[i].anim[1]);
        fill_track(&g.anim_s, nodes[i].anim[2]);
    }
}

void Converter::copy_objects(gi_scene *s) const
{
    s->objects = static_cast<gi_object *>(calloc(objects.size() + 1, sizeof(gi_object)));
    if (!s->objects)
        throw std::bad_alloc();
    s->object_count = static_cast<uint32_t>(objects.size());
    for (size_t i = 0; i < objects.size(); i++) {
        s->objects[i] = objects[i];
        s->objects[i].name = nullptr;
        s->objects[i].name = copy_string(object_names[i]);
        s->objects[i].morph_positions = nullptr;
        s->objects[i].morph_normals = nullptr;
        s->objects[i].morph_weights = nullptr;
        s->objects[i].morph_track = gi_track();
        s->objects[i].flat_triangles = copy_array(object_morphs[i].flat);
        if (objects[i].morph_count) {
            const ObjectMorph &om = object_morphs[i];
            s->objects[i].morph_positions = copy_array(om.pos);
            s->objects[i].morph_normals = copy_array(om.nrm);
            s->objects[i].morph_weights = copy_array(om.weights);
            fill_track(&s->objects[i].morph_track,
                       nodes[static_cast<size_t>(objects[i].node)].weights);
        }
    }
}

void Converter::copy_lights(gi_scene *s) const
{
    s->lights = static_cast<gi_light *>(calloc(lights.size() + 1, sizeof(gi_light)));
    if (!s->lights)
        throw std::bad_alloc();
    s->light_count = static_cast<uint32_t>(lights.size());
    for (size_t i = 0; i < lights.size(); i++) {
        s->lights[i] = lights[i];
        s->lights[i].name = nullptr;
        s->lights[i].name = copy_string(light_names[i]);
    }
}

void Converter::copy_cameras(gi_scene *s) const
{
    s->cameras = static_cast<gi_camera *>(calloc(cameras.size() + 1, sizeof(gi_camera)));
    if (!s->cameras)
        throw std::bad_alloc();
    s->camera_count = static_cast<uint32_t>(cameras.size());
    for (size_t i = 0; i < cameras.size(); i++) {
        s->cameras[i] = cameras[i];
        s->cameras[i].name = nullptr;
        s->cameras[i].name = copy_string(camera_names[i]);
    }
}

/* The emissive triangles (after copy_geometry), the animation's length
 * and the environment. */
void Converter::copy_emitters_and_environment(gi_scene *s) const
{
    std::vector<uint32_t> emitters;
    for (uint32_t t = 0; t < s->triangle_count; t++) {
        const float *e = materials[vertices[indices[t * 3]].material].emission;
        if (e[0] > 0.0f || e[1] > 0.0f || e[2] > 0.0f)
            emitters.push_back(t);
    }
    s->emitters = copy_array(emitters);
    s->emitter_count = static_cast<uint32_t>(emitters.size());
    s->animation_length = animation_length;
    if (has_env) {
        s->has_environment = 1;
        s->environment.uri = copy_string(env_uri);
        s->environment.path = copy_string(env_path);
        s->environment.intensity = env_intensity;
        s->environment.rotation_deg = env_rotation;
    }
}

/* Moves everything into malloc'd C arrays (gi_scene_free's ownership). */
gi_scene *Converter::build() const
{
    gi_scene *s = static_cast<gi_scene *>(calloc(1, sizeof(gi_scene)));
    if (!s)
        throw std::bad_alloc();
    try {
        copy_geometry(s);
        copy_materials(s);
        copy_textures(s);
        copy_nodes(s);
        copy_objects(s);
        copy_lights(s);
        copy_cameras(s);
        copy_emitters_and_environment(s);
    } catch (...) {
        gi_scene_free(s);
        throw;
    }
    return s;
}

gi_scene *Converter::run(char env_pointer[GI_GLTF_POINTER_MAX])
{
    check_buffer_views();
    check_accessors();
    check_images();
    check_textures();
    convert_materials();
    check_cameras();
    check_lights();
    check_nodes();
    choose_scene();
    instantiate();
    if (materials.size() > GI_MAX_MATERIALS)
        fail("/materials",
             fmt("%zu materials exceed the limit of %d", materials.size(), GI_MAX_MATERIALS));
    if (indices.empty())
        fail(scene_index >= 0 ? fmt("/scenes/%d", scene_index) : std::string("/"),
             "the scene has no triangles");
    convert_animations();
    read_environment();
    if (has_env)
        snprintf(env_pointer, GI_GLTF_POINTER_MAX, "/scenes/%d/extras/gibench/environment/uri",
                 scene_index);
    return build();
}

/* ---- the whole load ---- */

gi_scene *parse(const gi_gltf_source *src, Context &c, char env_pointer[GI_GLTF_POINTER_MAX])
{
    const unsigned char *bytes = static_cast<const unsigned char *>(src->data);
    if (src->size > GI_MAX_FILE_BYTES)
        fail("/", fmt("%zu bytes exceed the 1 GiB file limit", src->size));
    const char *text = reinterpret_cast<const char *>(bytes);
    size_t text_size = src->size;
    uint32_t glb_length = 0;
    if (src->binary) {
        Glb glb = check_glb(bytes, src->size);
        text = glb.json;
        text_size = glb.json_size;
        glb_length = glb.length;
    }
    check_before_tinygltf(c, text, text_size);

    tinygltf::TinyGLTF loader;
    tinygltf::FsCallbacks fs = {fs_file_exists, fs_expand_path, fs_read_whole_file,
                                fs_write_whole_file, &c};
    loader.SetFsCallbacks(fs);
    loader.SetImageLoader(load_image_callback, &c);
    tinygltf::Model model;
    std::string err, warn;
    std::string base = c.has_base ? c.base : std::string();
    bool ok = src->binary
                  ? loader.LoadBinaryFromMemory(&model, &err, &warn, bytes, glb_length, base)
                  : loader.LoadASCIIFromString(&model, &err, &warn, text,
                                               static_cast<unsigned>(text_size), base);
    if (!c.refused.empty())
        fail(c.refused_pointer, c.refused);
    if (!ok) {
        std::string msg = one_line(err);
        if (msg.empty())
            msg = "tinygltf rejected the file" + (warn.empty() ? "" : ": " + one_line(warn));
        fail("", msg);
    }
    Converter conv(model, c);
    return conv.run(env_pointer);
}

void set_context(Context *c, const gi_gltf_source *src)
{
    c->name = src->name ? src->name : "(memory)";
    if (src->base_dir) {
        c->has_base = true;
        c->base = src->base_dir[0] ? src->base_dir : ".";
        while (c->base.size() > 1 && c->base.back() == '/')
            c->base.pop_back();
        c->prefix = c->base == "/" ? c->base : c->base + "/";
        if (char *real = realpath(c->base.c_str(), nullptr)) {
            c->real_prefix = std::string(real) == "/" ? std::string("/") : std::string(real) + "/";
            free(real);
        }
    }
}

} // namespace

extern "C" gi_scene *gi_gltf_parse(const gi_gltf_source *src, char env_pointer[GI_GLTF_POINTER_MAX],
                                   gi_error *err)
{
    const char *name = src->name ? src->name : "(memory)";
    env_pointer[0] = '\0';
    try {
        Context c;
        set_context(&c, src);
        return parse(src, c, env_pointer);
    } catch (const Failure &f) {
        if (f.pointer.empty())
            gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: %s", name, f.reason.c_str());
        else
            gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: %s: %s", name, f.pointer.c_str(),
                         f.reason.c_str());
    } catch (const std::bad_alloc &) {
        gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "%s: out of memory while loading", name);
    } catch (const std::exception &e) {
        gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: %s", name, one_line(e.what()).c_str());
    } catch (...) {
        gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: unexpected error while loading", name);
    }
    return nullptr;
}
