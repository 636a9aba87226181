/* The strict JSON reader of every file a user writes by hand (studies,
 * saved views; cli.h cli_read_json_strict): no trailing comma, no comment,
 * nothing after the value, a bounded size, and no key given twice in one
 * object. json-c keeps the last of two equal keys and drops the first
 * without a word, so the reader scans the text once more for keys, and
 * compares them as json-c stores them: unescaped ("fr\u0061mes" is
 * "frames") and cut at a NUL, as a C string. */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"

#include "gi/cache.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static json_object *fail(char *why, size_t size, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

static json_object *fail(char *why, size_t size, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(why, size, fmt, ap);
    va_end(ap);
    return NULL;
}

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

/* Records key k (unescaped, owned from here) in frame f; 0 with `why`
 * set when f has it already. */
static int add_key(key_frame *st, int top, char *k, size_t line, const char *file, char *why,
                   size_t size)
{
    key_frame *f = &st[top];
    for (size_t q = 0; q < f->count; q++)
        if (!strcmp(f->keys[q], k)) {
            char path[512];
            key_path(st, top, k, path, sizeof path);
            snprintf(why, size, "%s: %s: key given twice (line %zu)", file, path, line);
            free(k);
            return 0;
        }
    if (f->count == f->cap) {
        size_t cap = f->cap ? 2 * f->cap : 8;
        char **keys = realloc(f->keys, cap * sizeof *keys);
        if (!keys) {
            snprintf(why, size, "%s: out of memory", file);
            free(k);
            return 0;
        }
        f->keys = keys;
        f->cap = cap;
    }
    f->keys[f->count++] = k;
    f->key = k;
    f->want_key = 0;
    return 1;
}

/* 1 when no object of the text (already parsed as strict JSON, so a small
 * scanner of strings, brackets and commas suffices) gives a key twice;
 * else 0 with "FILE: /json/path: key given twice (line N)" in why. */
static int keys_unique(const char *file, const char *text, size_t n, char *why, size_t size)
{
    enum { MAX_DEPTH = 64 }; /* json-c stops at 32 */
    key_frame st[MAX_DEPTH];
    int top = -1, ok = 1;
    size_t line = 1;
    for (size_t i = 0; i < n && ok; i++) {
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
                ok = k ? add_key(st, top, k, line, file, why, size)
                       : (snprintf(why, size, "%s: out of memory", file), 0);
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
    return ok;
}

json_object *cli_read_json_strict(const char *path, char *why, size_t why_size)
{
    struct stat sb;
    if (stat(path, &sb) != 0 || !S_ISREG(sb.st_mode))
        return fail(why, why_size, "%s: cannot read the file (not a regular file)", path);
    if ((unsigned long long)sb.st_size > GI_MAX_JSON_BYTES)
        return fail(why, why_size, "%s: %lld bytes exceed the limit of %llu for a JSON file", path,
                    (long long)sb.st_size, (unsigned long long)GI_MAX_JSON_BYTES);
    size_t n = 0;
    char *text = gi_file_read_all(path, &n);
    if (!text)
        return fail(why, why_size, "%s: cannot read the file", path);
    json_tokener *tok = json_tokener_new();
    json_object *o = NULL;
    if (!tok) {
        free(text);
        return fail(why, why_size, "%s: out of memory", path);
    }
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
        snprintf(why, why_size, "%s: line %zu: not valid JSON: %s", path, line,
                 json_tokener_error_desc(e));
        json_object_put(o);
        o = NULL;
    } else if (!keys_unique(path, text, n, why, why_size)) {
        json_object_put(o);
        o = NULL;
    }
    json_tokener_free(tok);
    free(text);
    return o;
}
