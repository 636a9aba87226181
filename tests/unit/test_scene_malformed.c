/* The malformed-input corpus: every file in tests/data/malformed must be
 * rejected (never crash; the asan build runs this too) with a one-line
 * "path: /json/pointer: reason" whose text contains the substring that
 * EXPECTED.txt gives for it; and every file there must have such a line. */
#define _POSIX_C_SOURCE 200809L

#include "check.h"

#include "gi/scene.h"

#include <dirent.h>
#include <stdlib.h>
#include <string.h>

#define DIR_MALFORMED GI_TEST_DATA "/malformed"

typedef struct expectation {
    char name[128];
    char text[400];
} expectation;

static int read_expected(expectation *out, int max)
{
    FILE *f = fopen(DIR_MALFORMED "/EXPECTED.txt", "r");
    CHECK_MSG(f != NULL, "cannot open EXPECTED.txt");
    if (!f)
        return 0;
    char line[600];
    int n = 0;
    while (n < max && fgets(line, sizeof line, f)) {
        line[strcspn(line, "\r\n")] = '\0';
        char *tab = strchr(line, '\t');
        if (line[0] == '#' || !tab)
            continue;
        *tab = '\0';
        if (strlen(line) >= sizeof out[n].name || strlen(tab + 1) >= sizeof out[n].text) {
            CHECK_MSG(0, "EXPECTED.txt line too long: %s", line);
            continue;
        }
        strcpy(out[n].name, line);
        strcpy(out[n].text, tab + 1);
        n++;
    }
    fclose(f);
    return n;
}

static void check_file(const expectation *e)
{
    char path[512];
    snprintf(path, sizeof path, "%s/%s", DIR_MALFORMED, e->name);
    gi_error err;
    memset(&err, 'x', sizeof err); /* the loader must not rely on a cleared buffer */
    gi_scene *s = gi_scene_load(path, &err);
    CHECK_MSG(s == NULL, "%s: loaded although malformed", e->name);
    gi_scene_free(s);
    CHECK_MSG(memchr(err.text, '\0', sizeof err.text) != NULL, "%s: message not terminated", e->name);
    err.text[sizeof err.text - 1] = '\0';
    CHECK_MSG(strstr(err.text, e->text) != NULL, "%s:\n   got  \"%s\"\n   want \"...%s...\"", e->name,
              err.text, e->text);
    size_t pl = strlen(path);
    CHECK_MSG(strncmp(err.text, path, pl) == 0 && strncmp(err.text + pl, ": ", 2) == 0,
              "%s: message does not start with the file name: \"%s\"", e->name, err.text);
    CHECK_MSG(strchr(err.text, '\n') == NULL, "%s: message is not one line", e->name);
}

static int has_suffix(const char *s, const char *suffix)
{
    size_t a = strlen(s), b = strlen(suffix);
    return a >= b && strcmp(s + a - b, suffix) == 0;
}

/* Every corpus file has an expectation (a new fuzz crash file needs one). */
static void check_listing(const expectation *e, int n)
{
    DIR *d = opendir(DIR_MALFORMED);
    CHECK(d != NULL);
    if (!d)
        return;
    int files = 0;
    for (struct dirent *de; (de = readdir(d));) {
        if (!has_suffix(de->d_name, ".gltf") && !has_suffix(de->d_name, ".glb"))
            continue;
        files++;
        int found = 0;
        for (int i = 0; i < n && !found; i++)
            found = strcmp(e[i].name, de->d_name) == 0;
        CHECK_MSG(found, "%s has no line in EXPECTED.txt", de->d_name);
    }
    closedir(d);
    CHECK_MSG(files == n, "%d files but %d expectations", files, n);
    CHECK_MSG(files >= 25, "only %d malformed files", files);
}

/* Failures that no file in the corpus can show. */
static void check_api_failures(void)
{
    gi_error err;
    gi_scene *s = gi_scene_load(GI_TEST_DATA "/malformed/does-not-exist.gltf", &err);
    CHECK(s == NULL && strstr(err.text, "does-not-exist.gltf: cannot open") != NULL);

    const char ext[] = "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"byteLength\":4,"
                       "\"uri\":\"quad.bin\"}]}";
    s = gi_scene_load_memory(ext, sizeof ext - 1, 0, NULL, "mem.gltf", &err);
    CHECK_MSG(s == NULL && strstr(err.text, "mem.gltf: /buffers/0/uri: external URI 'quad.bin' "
                                            "needs a base directory") != NULL,
              "%s", err.text);

    /* the size is checked before a byte is read */
    s = gi_scene_load_memory(ext, (size_t)GI_MAX_FILE_BYTES + 1, 0, NULL, "huge.gltf", &err);
    CHECK_MSG(s == NULL && strstr(err.text, "huge.gltf: /: 1073741825 bytes exceed the 1 GiB file "
                                            "limit") != NULL,
              "%s", err.text);

    s = gi_scene_load_memory("", 0, 0, NULL, NULL, &err);
    CHECK_MSG(s == NULL && strncmp(err.text, "(memory): ", 10) == 0, "%s", err.text);
    s = gi_scene_load_memory("glTF", 4, 1, NULL, "tiny.glb", &err);
    CHECK_MSG(s == NULL && strstr(err.text, "tiny.glb: GLB: 4 bytes is shorter") != NULL, "%s",
              err.text);
    s = gi_scene_load_memory(ext, sizeof ext - 1, 0, NULL, "noerr.gltf", NULL); /* err may be NULL */
    CHECK(s == NULL);
}

int main(void)
{
    static expectation e[512];
    int n = read_expected(e, 512);
    for (int i = 0; i < n; i++)
        check_file(&e[i]);
    check_listing(e, n);
    check_api_failures();
    printf("%d malformed files\n", n);
    return gi_test_finish();
}
