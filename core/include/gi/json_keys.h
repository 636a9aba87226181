/* Duplicate keys in JSON text (json_keys.c). JSON parsers keep one of two
 * equal keys of an object (json-c and tinygltf's nlohmann the last) and drop
 * the other without a word; files people write by hand (studies, saved
 * views, scenes) are refused instead, so this scans the text for them. */
#ifndef GI_JSON_KEYS_H
#define GI_JSON_KEYS_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Scans text[0..n) (already parsed as valid JSON) for an object that gives
 * a key twice, keys compared as parsers store them: unescaped
 * ("fr\u0061mes" is "frames") and cut at a NUL, as a C string. Returns 1
 * on the first such key, with its JSON pointer ("/a/0/b/KEY") in path, the
 * key in key (both with control characters as '?', to stay on one line)
 * and the line of its second occurrence in *line; 0 when every key is
 * unique; -1 when out of memory. */
int gi_json_duplicate_key(const char *text, size_t n, char *path, size_t path_size, char *key,
                          size_t key_size, size_t *line);

#ifdef __cplusplus
}
#endif

#endif
