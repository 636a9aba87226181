/* The on-disk cache of precomputed data (cache.h): content hashes (XXH64),
 * the cache directory ($GIBENCH_CACHE, $XDG_CACHE_HOME/gibench or
 * ~/.cache/gibench, created on demand), whole-file reads and atomic writes
 * (a temporary file in the same directory, renamed into place, so a reader
 * never sees half an entry and an interrupted study leaves no torn files).
 */
#define _XOPEN_SOURCE 700
#define _DEFAULT_SOURCE /* mkstemps */

#include "gi/cache.h"

#include <assert.h>
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <xxhash.h>

uint64_t gi_hash64(const void *data, size_t size, uint64_t seed)
{
    return XXH64(data, size, seed);
}

/* Positions, normals and uvs of every vertex, then the indices relative to
 * the object's first vertex, then any morph targets with their weights: the same mesh hashes the
 * same wherever it sits in the scene, and any change to what a method precomputes from it changes
 * the hash. The object's transform and material are not part of it. */
uint64_t gi_scene_object_hash(const gi_scene *s, uint32_t object)
{
    assert(s && object < s->object_count);
    const gi_object *o = &s->objects[object];
    XXH64_state_t *st = XXH64_createState();
    if (!st)
        return 0;
    XXH64_reset(st, 0x676962656e6368ull); /* "gibench" */
    uint32_t counts[2] = {o->vertex_count, o->triangle_count};
    XXH64_update(st, counts, sizeof counts);
    for (uint32_t i = o->first_vertex; i < o->first_vertex + o->vertex_count; i++) {
        const gi_vertex *v = &s->vertices[i];
        XXH64_update(st, v->position, sizeof v->position);
        XXH64_update(st, v->normal, sizeof v->normal);
        XXH64_update(st, v->uv, sizeof v->uv);
        /* the one rule for sides (gi/scene.h): which faces exist in a map */
        unsigned char ds = (unsigned char)(s->materials[v->material].double_sided != 0);
        XXH64_update(st, &ds, 1);
    }
    for (size_t k = (size_t)o->first_triangle * 3;
         k < ((size_t)o->first_triangle + o->triangle_count) * 3; k++) {
        uint32_t rel = s->indices[k] - o->first_vertex;
        XXH64_update(st, &rel, sizeof rel);
    }
    if (o->flat_triangles) /* flat normals: recomputed under morphing */
        XXH64_update(st, o->flat_triangles, o->triangle_count);
    if (o->morph_count) { /* the morph targets and their weights shape it too */
        size_t n = (size_t)o->morph_count * o->vertex_count * 3;
        XXH64_update(st, &o->morph_count, sizeof o->morph_count);
        XXH64_update(st, o->morph_positions, n * sizeof(float));
        if (o->morph_normals)
            XXH64_update(st, o->morph_normals, n * sizeof(float));
        XXH64_update(st, o->morph_weights, o->morph_count * sizeof(float));
        if (o->morph_track.count) {
            XXH64_update(st, o->morph_track.times, o->morph_track.count * sizeof(float));
            XXH64_update(st, o->morph_track.values,
                         (size_t)o->morph_track.count * o->morph_count * sizeof(float));
            XXH64_update(st, &o->morph_track.step, sizeof o->morph_track.step);
        }
    }
    uint64_t h = XXH64_digest(st);
    XXH64_freeState(st);
    return h;
}

static char *join(const char *a, const char *b)
{
    size_t la = strlen(a), lb = strlen(b);
    int slash = la > 0 && a[la - 1] != '/';
    char *p = malloc(la + (size_t)slash + lb + 1);
    if (p) {
        memcpy(p, a, la);
        if (slash)
            p[la] = '/';
        memcpy(p + la + slash, b, lb + 1);
    }
    return p;
}

char *gi_cache_path(const char *dir, const char *name)
{
    assert(dir && name);
    return join(dir, name);
}

/* mkdir -p; 0 on success. */
static int make_dirs(char *path, gi_error *err)
{
    for (char *p = path + 1;; p++) {
        if (*p != '/' && *p != '\0')
            continue;
        char saved = *p;
        *p = '\0';
        int r = mkdir(path, 0755);
        int e = errno;
        struct stat st;
        if (r != 0 && !(e == EEXIST && stat(path, &st) == 0 && S_ISDIR(st.st_mode))) {
            gi_error_set(err, GI_ERR_IO, "cache directory %s: %s", path,
                         e == EEXIST ? "exists and is not a directory" : strerror(e));
            *p = saved;
            return -1;
        }
        *p = saved;
        if (saved == '\0')
            return 0;
    }
}

static const char *non_empty_env(const char *name)
{
    const char *v = getenv(name);
    return v && v[0] ? v : NULL;
}

char *gi_cache_dir(gi_error *err)
{
    const char *v;
    char *dir;
    if ((v = non_empty_env("GIBENCH_CACHE")))
        dir = strdup(v);
    else if ((v = non_empty_env("XDG_CACHE_HOME")) && v[0] == '/') /* XDG: relative = unset */
        dir = join(v, "gibench");
    else if ((v = non_empty_env("HOME")))
        dir = join(v, ".cache/gibench");
    else {
        gi_error_set(err, GI_ERR_IO, "no cache directory: set GIBENCH_CACHE or HOME");
        return NULL;
    }
    if (!dir) {
        gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "out of memory");
        return NULL;
    }
    if (make_dirs(dir, err) != 0) {
        free(dir);
        return NULL;
    }
    return dir;
}

void *gi_file_read_all(const char *path, size_t *size)
{
    assert(path && size);
    *size = 0;
    int fd = open(path, O_RDONLY | O_CLOEXEC | O_NONBLOCK);
    if (fd < 0)
        return NULL;
    struct stat st;
    char *data = NULL;
    if (fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && (unsigned long long)st.st_size < SIZE_MAX) {
        size_t n = (size_t)st.st_size, done = 0;
        data = malloc(n + 1); /* NUL-terminated for text readers; *size excludes it */
        while (data && done < n) {
            ssize_t r = read(fd, data + done, n - done);
            if (r < 0 && errno == EINTR)
                continue;
            if (r <= 0) {
                free(data);
                data = NULL;
            } else {
                done += (size_t)r;
            }
        }
        if (data) {
            data[n] = '\0';
            *size = n;
        }
    }
    close(fd);
    return data;
}

static int write_all(int fd, const void *data, size_t size)
{
    const char *p = data;
    while (size > 0) {
        ssize_t r = write(fd, p, size);
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0)
            return -1;
        p += r;
        size -= (size_t)r;
    }
    return 0;
}

/* Makes the rename itself durable; failure here is not an error. */
static void sync_directory_of(const char *path)
{
    char *dir = strdup(path);
    if (!dir)
        return;
    char *slash = strrchr(dir, '/');
    if (slash)
        *(slash == dir ? slash + 1 : slash) = '\0';
    int fd = open(slash ? dir : ".", O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd >= 0) {
        fsync(fd);
        close(fd);
    }
    free(dir);
}

gi_result gi_atomic_begin(gi_atomic_file *f, const char *path, gi_error *err)
{
    assert(f && path);
    if (strlen(path) >= sizeof f->path)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%.200s...: path too long", path);
    snprintf(f->path, sizeof f->path, "%s", path);
    const char *slash = strrchr(path, '/');
    const char *base = slash ? slash + 1 : path;
    const char *dot = strrchr(base, '.');
    size_t dir_len = (size_t)(base - path),
           stem_len = dot && dot != base ? (size_t)(dot - base) : strlen(base);
    const char *ext = dot && dot != base ? dot : "";
    snprintf(f->tmp, sizeof f->tmp, "%.*s.%.*s.tmp-%ld-XXXXXX%s", (int)dir_len, path, (int)stem_len,
             base, (long)getpid(), ext);
    int fd = mkstemps(f->tmp, (int)strlen(ext));
    if (fd < 0)
        return gi_error_set(err, GI_ERR_IO, "%s: cannot create a temporary file: %s", path,
                            strerror(errno));
    close(fd);
    return GI_OK;
}

gi_result gi_atomic_commit(gi_atomic_file *f, int ok, gi_error *err)
{
    if (ok) {
        /* mkstemps made it 0600; results are meant to be shared like any new file. */
        mode_t mask = umask(0);
        umask(mask);
        if (chmod(f->tmp, 0666 & ~mask) == 0 && rename(f->tmp, f->path) == 0) {
            sync_directory_of(f->path);
            return GI_OK;
        }
        int e = errno;
        unlink(f->tmp);
        return gi_error_set(err, GI_ERR_IO, "%s: cannot move the temporary file into place: %s",
                            f->path, strerror(e));
    }
    unlink(f->tmp);
    return GI_OK;
}

gi_result gi_file_write_atomic(const char *path, const void *data, size_t size, gi_error *err)
{
    assert(path && (data || size == 0));
    gi_atomic_file f;
    gi_result r = gi_atomic_begin(&f, path, err);
    if (r != GI_OK)
        return r;
    const char *what = NULL;
    int fd = open(f.tmp, O_WRONLY | O_TRUNC | O_CLOEXEC);
    if (fd < 0)
        what = "open";
    else if (write_all(fd, data, size) != 0)
        what = "write";
    else if (fsync(fd) != 0)
        what = "fsync";
    int e = errno;
    if (fd >= 0 && close(fd) != 0 && !what) {
        what = "close";
        e = errno;
    }
    if (what) {
        gi_atomic_commit(&f, 0, NULL);
        return gi_error_set(err, GI_ERR_IO, "%s: %s failed: %s", path, what, strerror(e));
    }
    return gi_atomic_commit(&f, 1, err);
}

/* The cache entry's header (cache.h): magic, version, name length, name,
 * payload size, payload hash, all little-endian as the host writes them
 * (a cache directory is not shared between machines of other byte order:
 * such an entry fails its checks and is recomputed). */
static const char cache_magic[8] = {'G', 'I', 'C', 'A', 'C', 'H', 'E', '\n'};
#define CACHE_HEADER_VERSION 1u
#define CACHE_NAME_MAX 255u

static const char *entry_name(const char *path)
{
    const char *slash = strrchr(path, '/');
    return slash ? slash + 1 : path;
}

gi_result gi_cache_store(const char *path, const void *data, size_t size, gi_error *err)
{
    assert(path && (data || size == 0));
    const char *name = entry_name(path);
    uint32_t head[2] = {CACHE_HEADER_VERSION, (uint32_t)strlen(name)};
    if (head[1] > CACHE_NAME_MAX)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%.200s: cache entry name too long",
                            path);
    uint64_t tail[2] = {(uint64_t)size, gi_hash64(data, size, 0)};
    size_t header = sizeof cache_magic + sizeof head + head[1] + sizeof tail;
    unsigned char *buf = malloc(header + size);
    if (!buf)
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    unsigned char *q = buf;
    memcpy(q, cache_magic, sizeof cache_magic);
    q += sizeof cache_magic;
    memcpy(q, head, sizeof head);
    q += sizeof head;
    memcpy(q, name, head[1]);
    q += head[1];
    memcpy(q, tail, sizeof tail);
    q += sizeof tail;
    if (size)
        memcpy(q, data, size);
    gi_result r = gi_file_write_atomic(path, buf, header + size, err);
    free(buf);
    return r;
}

/* Checks the header of an entry of n bytes read from `path`: GI_OK with the
 * payload's offset and size, or why not. */
static gi_result check_entry(const char *path, const unsigned char *p, size_t n, size_t *at,
                             size_t *size, gi_error *err)
{
    const char *name = entry_name(path);
    uint32_t head[2];
    uint64_t tail[2];
    size_t fixed = sizeof cache_magic + sizeof head;
    if (n < fixed || memcmp(p, cache_magic, sizeof cache_magic) != 0)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "no gibench cache header (damaged, or written by an older gibench)");
    memcpy(head, p + sizeof cache_magic, sizeof head);
    if (head[0] != CACHE_HEADER_VERSION || head[1] > CACHE_NAME_MAX ||
        n < fixed + head[1] + sizeof tail)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "bad cache header (version %u)", head[0]);
    if (head[1] != strlen(name) || memcmp(p + fixed, name, head[1]) != 0) {
        /* the name it was made as, when it is printable (one line) */
        int shown = 1;
        for (uint32_t i = 0; i < head[1]; i++)
            shown &= p[fixed + i] >= 0x20 && p[fixed + i] < 0x7f;
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "made as %.*s, not %s: copied from another scene or other settings",
                            shown ? (int)head[1] : 9, shown ? (const char *)(p + fixed) : "another",
                            name);
    }
    memcpy(tail, p + fixed + head[1], sizeof tail);
    *at = fixed + head[1] + sizeof tail;
    if (tail[0] != n - *at)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "%zu bytes of data, the header says %llu (truncated or padded)",
                            n - *at, (unsigned long long)tail[0]);
    if (gi_hash64(p + *at, n - *at, 0) != tail[1])
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "checksum mismatch (damaged)");
    *size = n - *at;
    return GI_OK;
}

gi_result gi_cache_load(const char *path, void **data, size_t *size, gi_error *err)
{
    assert(path && data && size);
    *data = NULL;
    *size = 0;
    size_t n = 0, at = 0, payload = 0;
    errno = 0;
    unsigned char *p = gi_file_read_all(path, &n);
    if (!p)
        return errno == ENOENT ? GI_OK
                               : gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "cannot read it: %s",
                                              strerror(errno));
    gi_result r = check_entry(path, p, n, &at, &payload, err);
    if (r != GI_OK) {
        free(p);
        return r;
    }
    memmove(p, p + at, payload);
    *data = p;
    *size = payload;
    return GI_OK;
}
