/* The on-disk cache of precomputed data, keyed by content hashes.
 *
 * The cache directory is $GIBENCH_CACHE, else $XDG_CACHE_HOME/gibench, else
 * ~/.cache/gibench. Methods name entries "<id>-<16 hex digits>.<ext>" where
 * the hex is gi_hash64 of everything the data depends on (mesh bytes,
 * parameters, format version). Writes are atomic (temporary + rename).
 */
#ifndef GI_CACHE_H
#define GI_CACHE_H

#include "gi/common.h"
#include "gi/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

/* 64-bit hash (XXH64) of a byte range, continuing from `seed`. */
uint64_t gi_hash64(const void *data, size_t size, uint64_t seed);
/* Hash of one object's mesh in local space (positions, normals, uvs, indices,
 * each vertex's material doubleSided: which faces exist under the rule for sides). */
uint64_t gi_scene_object_hash(const gi_scene *s, uint32_t object);
/* Resolves (and creates) the cache directory; returns a malloc'd path or
 * NULL + err. */
char *gi_cache_dir(gi_error *err);
/* dir/name; malloc'd. */
char *gi_cache_path(const char *dir, const char *name);
/* Reads a whole file (NULL if absent/unreadable); writes atomically. */
void *gi_file_read_all(const char *path, size_t *size);
gi_result gi_file_write_atomic(const char *path, const void *data, size_t size, gi_error *err);

/* Cache entries carry what they were made for. gi_cache_store writes
 * `data` to `path` atomically behind a header: the magic "GICACHE\n", the
 * header's version, the entry's own name (the last part of `path`, whose
 * hex digits are the hash of everything the data depends on: scene
 * content, method, the parameters that change the data, the data's format
 * version), the payload's size and its XXH64. gi_cache_load reads it back
 * and checks all of it against `path`: GI_OK with *data (malloc'd, yours
 * to free) and *size when the entry is whole and was made under this very
 * name; GI_OK with *data NULL when there is no file; else
 * GI_ERR_INVALID_ARGUMENT and one line saying why (made for another entry:
 * copied from another scene or other settings; truncated, padded or
 * damaged; no header: written by an older gibench), for the caller to
 * recompute with a warning. */
gi_result gi_cache_store(const char *path, const void *data, size_t size, gi_error *err);
gi_result gi_cache_load(const char *path, void **data, size_t *size, gi_error *err);

/* Atomic replacement for writers that open the file by name themselves
 * (OpenImageIO, VTK). gi_atomic_begin creates an empty temporary file beside
 * `path`, named ".<stem>.tmp-<pid>-XXXXXX<ext>" so that the real extension
 * (which picks the format) stays last; the caller writes f.tmp; then
 * gi_atomic_commit(&f, 1, err) gives it a new file's mode (0666 & ~umask)
 * and renames it over `path`, or gi_atomic_commit(&f, 0, err) removes it.
 * Every successful begin must be followed by exactly one commit. */
typedef struct gi_atomic_file {
    char path[4096];
    char tmp[4096 + 64];
} gi_atomic_file;
gi_result gi_atomic_begin(gi_atomic_file *f, const char *path, gi_error *err);
gi_result gi_atomic_commit(gi_atomic_file *f, int ok, gi_error *err);

#ifdef __cplusplus
}
#endif
#endif
