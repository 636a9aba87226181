/* The study file as strict JSON (gibench study, docs/studies.md "gibench
 * study"): the strict reader (harness/cli/json_strict.c) and the typed
 * reads of its values whose messages name the value's JSON path. */
#define _POSIX_C_SOURCE 200809L
#include "study_internal.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "gi/limits.h"

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

/* A study on standard input ("-", e.g. from a program that holds the study
 * in memory) is copied to a private temporary file first, so that it goes
 * through the same strict reader and limits as a study file; messages name
 * it "-". */
static json_object *read_stdin_json(char *why, size_t why_size)
{
    /* in $TMPDIR, as every other temporary file of the harness */
    char tmp[4096];
    int fd = cli_temp_file("gibench-study", tmp, sizeof tmp);
    if (fd < 0) {
        snprintf(why, why_size, "-: cannot make %s for the study on standard input: %s", tmp,
                 strerror(errno));
        return NULL;
    }
    FILE *f = fdopen(fd, "wb");
    char buf[65536];
    size_t n, total = 0;
    int ok = f != NULL;
    while (ok && (n = fread(buf, 1, sizeof buf, stdin)) > 0) {
        total += n;
        ok = total <= GI_MAX_JSON_BYTES && fwrite(buf, 1, n, f) == n;
    }
    ok = ok && !ferror(stdin);
    if (f ? fclose(f) != 0 : close(fd) != 0)
        ok = 0;
    json_object *o = NULL;
    if (!ok)
        snprintf(why, why_size, "-: cannot read the study on standard input (at most %llu bytes)",
                 (unsigned long long)GI_MAX_JSON_BYTES);
    else if (!(o = cli_read_json_strict(tmp, why, why_size))) {
        char text[1024];
        const char *rest = strncmp(why, tmp, strlen(tmp)) ? why : why + strlen(tmp);
        snprintf(text, sizeof text, "-%s", rest);
        snprintf(why, why_size, "%s", text);
    }
    unlink(tmp);
    return o;
}

/* The study file through the strict reader of every hand-written JSON file
 * (cli_read_json_strict: no trailing commas, comments, text after the
 * object, or key given twice, keys compared unescaped); NULL after
 * printing where it goes wrong. */
json_object *study_read_strict_json(const char *file)
{
    char why[1024];
    json_object *o = !strcmp(file, "-") ? read_stdin_json(why, sizeof why)
                                        : cli_read_json_strict(file, why, sizeof why);
    if (!o)
        cli_fail(EXIT_USAGE, "%s", why);
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
