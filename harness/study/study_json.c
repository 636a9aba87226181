/* The study file as strict JSON (gibench study, docs/studies.md "gibench study"):
 * the reader that refuses trailing commas, comments and keys given twice,
 * and the typed reads of its values whose messages name the value's JSON
 * path. */
#define _POSIX_C_SOURCE 200809L
#include "study_internal.h"

#include "gi/cache.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int study_fail_json(const char *file, const char *path, const char *what)
{
    return cli_fail(EXIT_USAGE, "%s: %s: %s", file, path, what);
}

/* o[key] as an integer in [min, max] (absent or null: def); `prefix` is the
 * JSON path of o for messages. */
int study_get_uint(json_object *o, const char *prefix, const char *key, uint32_t min, uint32_t max,
                   uint32_t def, uint32_t *out, const char *file)
{
    json_object *v;
    *out = def;
    if (!json_object_object_get_ex(o, key, &v) || json_object_is_type(v, json_type_null))
        return EXIT_OK;
    if (!json_object_is_type(v, json_type_int) || json_object_get_int64(v) < min ||
        json_object_get_int64(v) > max) {
        char msg[128];
        snprintf(msg, sizeof msg, "must be an integer in [%u, %u]", min, max);
        char path[160];
        snprintf(path, sizeof path, "%s/%s", prefix, key);
        return study_fail_json(file, path, msg);
    }
    *out = (uint32_t)json_object_get_int64(v);
    return EXIT_OK;
}

/* o[key] as a number in [min, max] (absent or null: def). */
int study_get_number(json_object *o, const char *prefix, const char *key, double min, double max,
                     double def, double *out, const char *file)
{
    json_object *v;
    *out = def;
    if (!json_object_object_get_ex(o, key, &v) || json_object_is_type(v, json_type_null))
        return EXIT_OK;
    double d = json_object_get_double(v);
    if ((!json_object_is_type(v, json_type_int) && !json_object_is_type(v, json_type_double)) ||
        !(d >= min) || !(d <= max)) {
        char msg[128], path[160];
        snprintf(msg, sizeof msg, "must be a number in [%g, %g]", min, max);
        snprintf(path, sizeof path, "%s/%s", prefix, key);
        return study_fail_json(file, path, msg);
    }
    *out = d;
    return EXIT_OK;
}

/* o[key] as a string (absent: def; null too when null_ok). */
int study_get_string(json_object *o, const char *prefix, const char *key, int null_ok,
                     const char *def, const char **out, const char *file)
{
    json_object *v;
    *out = def;
    if (!json_object_object_get_ex(o, key, &v) ||
        (null_ok && json_object_is_type(v, json_type_null)))
        return EXIT_OK;
    if (!json_object_is_type(v, json_type_string)) {
        char path[160];
        snprintf(path, sizeof path, "%s/%s", prefix, key);
        return study_fail_json(file, path,
                               null_ok ? "must be a string or null" : "must be a string");
    }
    *out = json_object_get_string(v);
    return EXIT_OK;
}

/* json-c keeps the last of two equal keys in an object and drops the
 * first without a word; a study file that gives "params" (or "spp", ...)
 * twice is refused instead, naming the key's JSON path and its line. The
 * text has already parsed as strict JSON, so a small scanner suffices:
 * strings, the brackets and commas around them. Keys compare as written
 * (escapes are not decoded). Returns EXIT_OK or EXIT_USAGE after printing. */
typedef struct key_frame {
    int is_object, want_key;
    size_t index;    /* arrays: the element being read */
    const char *key; /* objects: the key being read */
    size_t key_len;
    const char **keys; /* objects: keys seen (into the text) */
    size_t *lens, count, cap;
} key_frame;

static int check_duplicate_keys(const char *file, const char *text, size_t n)
{
    enum { MAX_DEPTH = 64 }; /* json-c stops at 32 */
    key_frame st[MAX_DEPTH];
    int top = -1, rc = EXIT_OK;
    size_t line = 1;
    for (size_t i = 0; i < n && rc == EXIT_OK; i++) {
        char c = text[i];
        if (c == '\n') {
            line++;
        } else if (c == '"') {
            size_t j = i + 1;
            while (j < n && text[j] != '"')
                j += text[j] == '\\' ? 2 : 1;
            if (j > n)
                j = n;
            key_frame *f = top >= 0 ? &st[top] : NULL;
            if (f && f->is_object && f->want_key) {
                const char *k = text + i + 1;
                size_t kl = j - i - 1;
                for (size_t q = 0; q < f->count; q++)
                    if (f->lens[q] == kl && !memcmp(f->keys[q], k, kl)) {
                        char path[512];
                        size_t used = 0;
                        for (int d = 0; d < top && used < sizeof path; d++) {
                            int w = st[d].is_object
                                        ? snprintf(path + used, sizeof path - used, "/%.*s",
                                                   (int)st[d].key_len, st[d].key)
                                        : snprintf(path + used, sizeof path - used, "/%zu",
                                                   st[d].index);
                            used += w > 0 ? (size_t)w : 0;
                        }
                        if (used < sizeof path)
                            snprintf(path + used, sizeof path - used, "/%.*s", (int)kl, k);
                        char what[64];
                        snprintf(what, sizeof what, "key given twice (line %zu)", line);
                        rc = study_fail_json(file, path, what);
                        break;
                    }
                if (rc == EXIT_OK && f->count == f->cap) {
                    size_t cap = f->cap ? 2 * f->cap : 8;
                    const char **keys = realloc(f->keys, cap * sizeof *keys);
                    if (keys)
                        f->keys = keys;
                    size_t *lens = keys ? realloc(f->lens, cap * sizeof *lens) : NULL;
                    if (lens)
                        f->lens = lens;
                    if (!keys || !lens)
                        rc = cli_fail(EXIT_RUN, "%s: out of memory", file);
                    else
                        f->cap = cap;
                }
                if (rc == EXIT_OK) {
                    f->keys[f->count] = k;
                    f->lens[f->count++] = kl;
                    f->key = k;
                    f->key_len = kl;
                    f->want_key = 0;
                }
            }
            for (size_t q = i + 1; q < j; q++)
                line += text[q] == '\n';
            i = j;
        } else if (c == '{' || c == '[') {
            if (top + 1 >= MAX_DEPTH)
                break; /* deeper than json-c reads: it refused the file already */
            key_frame *f = &st[++top];
            memset(f, 0, sizeof *f);
            f->is_object = c == '{';
            f->want_key = f->is_object;
        } else if ((c == '}' || c == ']') && top >= 0) {
            free(st[top].keys);
            free(st[top].lens);
            top--;
        } else if (c == ',' && top >= 0) {
            if (st[top].is_object)
                st[top].want_key = 1;
            else
                st[top].index++;
        }
    }
    for (; top >= 0; top--) {
        free(st[top].keys);
        free(st[top].lens);
    }
    return rc;
}

/* The study file as strict JSON (no trailing commas, no comments, nothing
 * after the top-level value); NULL after printing where it goes wrong. */
json_object *study_read_strict_json(const char *file)
{
    size_t n = 0;
    char *text = gi_file_read_all(file, &n);
    if (!text) {
        cli_fail(EXIT_USAGE, "%s: cannot read the study file", file);
        return NULL;
    }
    json_tokener *tok = json_tokener_new();
    json_object *o = NULL;
    if (tok) {
        json_tokener_set_flags(tok, JSON_TOKENER_STRICT);
        o = json_tokener_parse_ex(tok, text, (int)n);
        enum json_tokener_error e = json_tokener_get_error(tok);
        size_t end = json_tokener_get_parse_end(tok);
        if (e == json_tokener_continue)
            e = json_tokener_error_parse_eof;
        if (e != json_tokener_success || !o) {
            size_t line = 1;
            for (size_t i = 0; i < end && i < n; i++)
                line += text[i] == '\n';
            cli_fail(EXIT_USAGE, "%s: line %zu: not valid JSON: %s", file, line,
                     json_tokener_error_desc(e));
            json_object_put(o);
            o = NULL;
        }
        json_tokener_free(tok);
    }
    if (o && check_duplicate_keys(file, text, n) != EXIT_OK) {
        json_object_put(o);
        o = NULL;
    }
    free(text);
    return o;
}

/* Rejects keys of o that are not in `known` (NULL-terminated). */
int study_check_keys(json_object *o, const char *const *known, const char *prefix, const char *file)
{
    if (!json_object_is_type(o, json_type_object))
        return study_fail_json(file, *prefix ? prefix : "/", "must be an object {key: value}");
    json_object_object_foreach(o, key, val)
    {
        (void)val;
        int ok = 0;
        for (int i = 0; known[i]; i++)
            ok |= !strcmp(known[i], key);
        if (!ok) {
            char path[256];
            snprintf(path, sizeof path, "%s/%s", prefix, key);
            return study_fail_json(file, path, "unknown key");
        }
    }
    return EXIT_OK;
}
