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
#include "gi/json_keys.h"

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

/* 1 when no object of the text gives a key twice (gi/json_keys.h); else 0
 * with "FILE: /json/path: key given twice (line N)" in why. */
static int keys_unique(const char *file, const char *text, size_t n, char *why, size_t size)
{
    char path[512], key[256];
    size_t line = 0;
    int r = gi_json_duplicate_key(text, n, path, sizeof path, key, sizeof key, &line);
    if (r > 0)
        snprintf(why, size, "%s: %s: key given twice (line %zu)", file, path, line);
    else if (r < 0)
        snprintf(why, size, "%s: out of memory", file);
    return r == 0;
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
