/* Where a study's relative paths lead (docs/studies.md, "Paths in a study"):
 * every file a study names (its scenes, a "view:FILE" camera) is taken
 * relative to the study's base folder, which is the study file's own folder,
 * or its "base" key (a folder, relative to the study file's folder or
 * absolute). A study read from standard input ("-") has the current folder
 * as its base. Resolving from the study's folder, not from wherever the
 * command was started, lets a researcher copy a study next to her scenes
 * and run it from anywhere (issue 33). */
#define _POSIX_C_SOURCE 200809L
#include "study_internal.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* Collapses "." and "dir/.." components lexically, so that a study in
 * harness/studies/ with "base": "../.." names "scenes/x.gltf" when run from
 * the tree's root, as the records and cached runs of earlier studies do.
 * Leading ".." components (and "/.." at the root) are kept or dropped as a
 * shell would resolve them without symbolic links. */
static void normalise(char *path)
{
    int absolute = path[0] == '/';
    char *parts[1024];
    int n = 0;
    char *save = NULL;
    for (char *p = strtok_r(path, "/", &save); p && n < 1024; p = strtok_r(NULL, "/", &save)) {
        if (!strcmp(p, "."))
            continue;
        if (!strcmp(p, "..") && n > 0 && strcmp(parts[n - 1], "..")) {
            n--;
            continue;
        }
        if (!strcmp(p, "..") && absolute)
            continue; /* "/.." is "/" */
        parts[n++] = p;
    }
    char out[8200];
    size_t used = 0;
    out[0] = '\0';
    if (absolute)
        used += (size_t)snprintf(out, sizeof out, "/");
    for (int i = 0; i < n && used < sizeof out; i++)
        used += (size_t)snprintf(out + used, sizeof out - used, "%s%s", i ? "/" : "", parts[i]);
    if (!out[0])
        snprintf(out, sizeof out, ".");
    memmove(path, out, strlen(out) + 1);
}

/* The folder of `file` ("." for a name without one, "/" for a file at the root). */
static void folder_of(const char *file, char *out, size_t size)
{
    const char *slash = strrchr(file, '/');
    if (!slash)
        snprintf(out, size, ".");
    else if (slash == file)
        snprintf(out, size, "/");
    else
        snprintf(out, size, "%.*s", (int)(slash - file), file);
}

int study_set_base(study *st, json_object *root, const char *file)
{
    char from[4096];
    const char *at = st->located_as ? st->located_as : file;
    if (!strcmp(at, "-"))
        snprintf(from, sizeof from, ".");
    else
        folder_of(at, from, sizeof from);
    json_object *v;
    if (!json_object_object_get_ex(root, "base", &v)) {
        snprintf(st->base_dir, sizeof st->base_dir, "%s", from);
        normalise(st->base_dir);
        return EXIT_OK;
    }
    const char *b = json_object_get_string(v);
    if (!json_object_is_type(v, json_type_string) || !*b)
        return study_fail_json(
            file, "/base", "must be a folder (relative to the study file's folder, or absolute)");
    char joined[8200];
    if (b[0] == '/')
        snprintf(joined, sizeof joined, "%.4095s", b);
    else
        snprintf(joined, sizeof joined, "%s/%.4095s", from, b);
    normalise(joined);
    if (strlen(joined) >= sizeof st->base_dir)
        return study_fail_json(file, "/base", "the folder's path is too long");
    memcpy(st->base_dir, joined, strlen(joined) + 1);
    return EXIT_OK;
}

void study_resolve(const study *st, const char *name, char *out, size_t size)
{
    /* a name the study's base does not change is kept as written */
    if (name[0] == '/' || !strcmp(st->base_dir, ".")) {
        snprintf(out, size, "%s", name);
        return;
    }
    char joined[8200];
    snprintf(joined, sizeof joined, "%s/%.4095s", st->base_dir, name);
    normalise(joined);
    snprintf(out, size, "%s", joined);
}

int study_check_readable(const study *st, const char *file, const char *jpath, const char *name,
                         const char *resolved)
{
    if (access(resolved, R_OK) == 0)
        return EXIT_OK;
    if (name[0] == '/')
        return cli_fail(EXIT_USAGE, "%s: %s: %s: no such readable file", file, jpath, resolved);
    return cli_fail(EXIT_USAGE,
                    "%s: %s: %s: no such readable file (\"%s\" is relative to the study's base "
                    "folder %s)",
                    file, jpath, resolved, name, st->base_dir);
}
