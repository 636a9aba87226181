/* Duplicate keys in JSON text (gi/json_keys.h): the scanner behind the
 * strict reader of studies and saved views (harness/cli/json_strict.c) and
 * the glTF loader's check (gltf_shim.cpp). */
#include "gi/json_keys.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void put_utf8(char *out, size_t *n, unsigned cp)
{
    if (cp < 0x80) {
        out[(*n)++] = (char)cp;
    } else if (cp < 0x800) {
        out[(*n)++] = (char)(0xC0 | cp >> 6);
        out[(*n)++] = (char)(0x80 | (cp & 0x3F));
    } else if (cp < 0x10000) {
        out[(*n)++] = (char)(0xE0 | cp >> 12);
        out[(*n)++] = (char)(0x80 | (cp >> 6 & 0x3F));
        out[(*n)++] = (char)(0x80 | (cp & 0x3F));
    } else {
        out[(*n)++] = (char)(0xF0 | cp >> 18);
        out[(*n)++] = (char)(0x80 | (cp >> 12 & 0x3F));
        out[(*n)++] = (char)(0x80 | (cp >> 6 & 0x3F));
        out[(*n)++] = (char)(0x80 | (cp & 0x3F));
    }
}

static unsigned hex4(const char *s)
{
    unsigned v = 0;
    for (int i = 0; i < 4; i++) {
        char c = s[i];
        v = v << 4 | (unsigned)(c <= '9' ? c - '0' : (c | 0x20) - 'a' + 10);
    }
    return v;
}

/* The key text s[0..n) (between its quotes, already valid JSON) unescaped
 * into a malloc'd C string, cut at the first NUL as json-c keeps it. A
 * UTF-8 sequence takes at most as many bytes as the escape it comes from. */
static char *unescape_key(const char *s, size_t n)
{
    char *out = malloc(n + 1);
    if (!out)
        return NULL;
    size_t o = 0;
    for (size_t i = 0; i < n; i++) {
        if (s[i] != '\\' || i + 1 >= n) {
            out[o++] = s[i];
            continue;
        }
        char e = s[++i];
        if (e == 'u' && i + 4 < n) {
            unsigned cp = hex4(s + i + 1);
            i += 4;
            if (cp >= 0xD800 && cp < 0xDC00 && i + 6 < n && s[i + 1] == '\\' && s[i + 2] == 'u') {
                unsigned lo = hex4(s + i + 3);
                if (lo >= 0xDC00 && lo < 0xE000) {
                    cp = 0x10000 + ((cp - 0xD800) << 10) + (lo - 0xDC00);
                    i += 6;
                }
            }
            put_utf8(out, &o, cp);
        } else {
            static const char from[] = "bfnrt", to[] = "\b\f\n\r\t";
            const char *k = strchr(from, e);
            out[o++] = e && k ? to[k - from] : e; /* \" \\ \/ stand for themselves */
        }
    }
    out[o] = '\0';
    return out;
}

typedef struct key_frame {
    int is_object, want_key;
    size_t index;    /* arrays: the element being read */
    const char *key; /* objects: the key being read (unescaped, in keys[]) */
    char **keys;     /* objects: the keys seen, unescaped */
    size_t count, cap;
} key_frame;

static void pop(key_frame *f)
{
    for (size_t q = 0; q < f->count; q++)
        free(f->keys[q]);
    free(f->keys);
}

/* "/a/0/b/KEY" of the key being read at depth `top`, control characters
 * shown as '?' so that the message stays one line. */
static void key_path(const key_frame *st, int top, const char *key, char *path, size_t size)
{
    size_t used = 0;
    path[0] = '\0';
    for (int d = 0; d <= top && used < size; d++) {
        int w = d == top          ? snprintf(path + used, size - used, "/%s", key)
                : st[d].is_object ? snprintf(path + used, size - used, "/%s", st[d].key)
                                  : snprintf(path + used, size - used, "/%zu", st[d].index);
        used += w > 0 ? (size_t)w : 0;
    }
    for (char *p = path; *p; p++)
        if ((unsigned char)*p < 0x20)
            *p = '?';
}

/* Records key k (unescaped, owned from here) in frame st[top]: 0 when
 * new, 1 when the frame has it already (path and key filled), -1 when out
 * of memory. */
static int add_key(key_frame *st, int top, char *k, char *path, size_t path_size, char *key,
                   size_t key_size)
{
    key_frame *f = &st[top];
    for (size_t q = 0; q < f->count; q++)
        if (!strcmp(f->keys[q], k)) {
            key_path(st, top, k, path, path_size);
            snprintf(key, key_size, "%s", k);
            for (char *p = key; *p; p++)
                if ((unsigned char)*p < 0x20)
                    *p = '?';
            free(k);
            return 1;
        }
    if (f->count == f->cap) {
        size_t cap = f->cap ? 2 * f->cap : 8;
        char **keys = realloc(f->keys, cap * sizeof *keys);
        if (!keys) {
            free(k);
            return -1;
        }
        f->keys = keys;
        f->cap = cap;
    }
    f->keys[f->count++] = k;
    f->key = k;
    f->want_key = 0;
    return 0;
}

/* The text is valid JSON already, so a small scanner of strings, brackets
 * and commas suffices. */
int gi_json_duplicate_key(const char *text, size_t n, char *path, size_t path_size, char *key,
                          size_t key_size, size_t *line_out)
{
    enum { MAX_DEPTH = 64 }; /* json-c stops at 32, the glTF loader at 64 */
    key_frame st[MAX_DEPTH];
    int top = -1, found = 0;
    size_t line = 1;
    for (size_t i = 0; i < n && !found; i++) {
        char c = text[i];
        if (c == '\n') {
            line++;
        } else if (c == '"') {
            size_t j = i + 1;
            while (j < n && text[j] != '"')
                j += text[j] == '\\' ? 2 : 1;
            if (j > n)
                j = n;
            if (top >= 0 && st[top].is_object && st[top].want_key) {
                char *k = unescape_key(text + i + 1, j - i - 1);
                found = k ? add_key(st, top, k, path, path_size, key, key_size) : -1;
                *line_out = line;
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
            pop(&st[top--]);
        } else if (c == ',' && top >= 0) {
            if (st[top].is_object)
                st[top].want_key = 1;
            else
                st[top].index++;
        }
    }
    for (; top >= 0; top--)
        pop(&st[top]);
    return found;
}
