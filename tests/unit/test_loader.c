/* The plugin loader refuses broken plugins with clear messages: wrong ABI,
 * missing function, duplicate id, bad id, NULL entry, short descriptor, bad
 * parameter table, a build against another data layout (older, newer, or
 * reordered), one that crashes while loading (entry or constructor); and
 * loads a good one. A folder without plugins is an empty
 * registry (no sort of an empty list: undefined behaviour under UBSan). */
#define _POSIX_C_SOURCE 200809L
#include "check.h"
#include "gi/kit.h"
#include "gi/plugin.h"

#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define FAKE_DIR GI_BINARY_DIR "/tests/fake_plugins"

static void expect_refused(const char *kind, const char *substring)
{
    char path[512];
    snprintf(path, sizeof path, "%s/gimethod_fake_%s.so", FAKE_DIR, kind);
    gi_error err = {{0}};
    gi_result r = gi_plugins_add(NULL, path, &err);
    CHECK_MSG(r != GI_OK && strstr(err.text, substring) && strstr(err.text, path), "%s: '%s'", kind,
              err.text);
}

static gi_result no_buffer(void *inst, const char *name, const gi_view *view, gi_image **out)
{
    (void)inst, (void)name, (void)view;
    *out = NULL;
    return GI_ERR_UNSUPPORTED;
}

int main(void)
{
    expect_refused("wrong_abi", "built for plugin ABI 2.0, this gibench speaks 1.3");
    expect_refused("missing_fn", "lacks the required function render()");
    expect_refused("bad_id", "method id 'Bad Id!' is not [a-z0-9_]{1,31}");
    expect_refused("null_entry", "gi_method_entry returned NULL");
    expect_refused("small_struct", "descriptor is");
    expect_refused("bad_param", "parameter 'n' default 100 outside [0, 10]");
    /* Crashing while loading (in gi_method_entry, in a constructor) is
     * caught in a probe child: one line, and this process goes on. */
    expect_refused("entry_crash", "crashed while loading (signal 11)");
    expect_refused("ctor_crash", "crashed while loading (signal 11)");
    /* ... and in a destructor, which the probe runs by unloading it (else
     * every process that mapped it would crash at exit). */
    expect_refused("dtor_crash", "crashed while unloading (signal 11)");
    /* Built against other data layouts: refused with the struct named. */
    char msg[160];
    snprintf(msg, sizeof msg,
             "built against gi_view of %zu bytes, this gibench has %zu: rebuild the plugin",
             sizeof(gi_view) - 16, sizeof(gi_view));
    expect_refused("layout_old", msg);
    snprintf(msg, sizeof msg, "built against gi_scene of %zu bytes, this gibench has %zu",
             sizeof(gi_scene) + 8, sizeof(gi_scene));
    expect_refused("layout_new", msg);
    snprintf(msg, sizeof msg, "built against data layout revision %u, this gibench has %u",
             GI_LAYOUT_REVISION + 1u, GI_LAYOUT_REVISION);
    expect_refused("layout_revision", msg);

    gi_error err;
    CHECK(gi_plugins_add(NULL, FAKE_DIR "/does_not_exist.so", &err) == GI_ERR_IO);
    CHECK(strstr(err.text, "cannot load") != NULL);

    /* A directory scan: the good one loads, the duplicate of its id is refused
     * with both paths named, every broken one gives one error line. */
    gi_plugins *reg = gi_plugins_scan(FAKE_DIR);
    CHECK(reg != NULL);
    CHECK(gi_plugins_find(reg, "fake_good") != NULL);
    CHECK(reg->count == 1);
    int dup = 0;
    for (uint32_t i = 0; i < reg->error_count; i++)
        dup += strstr(reg->errors[i], "duplicate method id 'fake_good'") != NULL;
    CHECK(dup == 1);
    CHECK(reg->error_count == 13);
    const gi_method *m = gi_plugins_find(reg, "fake_good");
    CHECK(m && m->params && strcmp(m->params[1].choices, "a|b|c") == 0);
    gi_plugins_free(reg);

    /* A folder holding no plugin, and one that does not exist: empty registries. */
    char empty[] = "/tmp/gibench_no_plugins_XXXXXX";
    CHECK(mkdtemp(empty) != NULL);
    unsetenv("GIBENCH_PLUGIN_PATH");
    gi_plugins *none = gi_plugins_scan(empty);
    CHECK(none && none->count == 0 && none->error_count == 0);
    gi_plugins_free(none);
    none = gi_plugins_scan("/tmp/gibench_no_such_folder_for_plugins");
    CHECK(none && none->count == 0 && none->error_count == 0);
    gi_plugins_free(none);
    rmdir(empty);

    /* Validation of a descriptor without a library. */
    gi_method bad = *m;
    bad.abi_version = (GI_ABI_MAJOR + 1) << 16;
    CHECK(gi_method_validate(&bad, &err) == GI_ERR_UNSUPPORTED &&
          strstr(err.text, "plugin ABI 2.0"));
    bad = *m;
    bad.destroy = NULL;
    CHECK(gi_method_validate(&bad, &err) != GI_OK && strstr(err.text, "destroy()"));
    /* A 1.0 descriptor (ends at last_error) has no layout: refused. */
    bad = *m;
    bad.struct_size = (uint32_t)offsetof(gi_method, layout);
    CHECK(gi_method_validate(&bad, &err) == GI_ERR_UNSUPPORTED &&
          strstr(err.text, "has no data layout"));
    /* Declared departures (ABI 1.2): a valid one is found by its check; one
     * the conformance suite could not act on is refused with the reason. */
    static const gi_departure ok_dep[] = {{"furnace", "why", "n=8 mode=c"}, {NULL, NULL, NULL}};
    bad = *m;
    bad.departures = ok_dep;
    CHECK(gi_method_validate(&bad, &err) == GI_OK);
    CHECK(gi_method_departure(&bad, "furnace") == &ok_dep[0]);
    CHECK(gi_method_departure(&bad, "held_out") == NULL);
    char buf[64];
    const char *kv[4];
    CHECK(gi_departure_remedy_args(&ok_dep[0], buf, sizeof buf, kv, 4) == 2 &&
          strcmp(kv[0], "n=8") == 0 && strcmp(kv[1], "mode=c") == 0);
    CHECK(gi_departure_remedy_args(&ok_dep[0], buf, sizeof buf, kv, 1) == -1);
    /* a 1.1 descriptor ends before the field: none declared, whatever lies beyond */
    bad.struct_size = (uint32_t)offsetof(gi_method, departures);
    CHECK(gi_method_validate(&bad, &err) == GI_OK && gi_method_departure(&bad, "furnace") == NULL);
    static const struct {
        gi_departure d[3];
        const char *error;
    } refused[] = {
        {{{"nosuch", "why", "n=8"}, {NULL, NULL, NULL}}, "unknown check 'nosuch'"},
        {{{"furnace", "", "n=8"}, {NULL, NULL, NULL}}, "one-line reason"},
        {{{"furnace", "two\nlines", "n=8"}, {NULL, NULL, NULL}}, "one-line reason"},
        {{{"furnace", "why", ""}, {NULL, NULL, NULL}}, "needs a remedy"},
        {{{"furnace", "why", "nosuch=1"}, {NULL, NULL, NULL}}, "remedy"},
        {{{"furnace", "why", "n=999"}, {NULL, NULL, NULL}}, "remedy"},
        {{{"furnace", "a", "n=8"}, {"furnace", "b", "n=9"}, {NULL, NULL, NULL}}, "declared twice"},
    };
    for (size_t i = 0; i < sizeof refused / sizeof refused[0]; i++) {
        bad = *m;
        bad.departures = refused[i].d;
        CHECK(gi_method_validate(&bad, &err) == GI_ERR_INVALID_ARGUMENT &&
              strstr(err.text, refused[i].error));
    }
    /* Debug buffers (ABI 1.3): found by name; a plugin built for ABI 1.2
     * loads and has none, whatever its build put beyond its struct_size. */
    CHECK(gi_method_debug_buffers(m) == NULL && gi_method_debug_buffer(m, "x") == NULL);
    gi_plugins *old = gi_plugins_scan(GI_BINARY_DIR "/tests/fake_plugins_abi12");
    const gi_method *m12 = old ? gi_plugins_find(old, "fake_abi12") : NULL;
    CHECK_MSG(m12 && old->error_count == 0, "%s", old && old->error_count ? old->errors[0] : "");
    CHECK(m12 && m12->struct_size == offsetof(gi_method, debug_buffers));
    CHECK(m12 && gi_method_debug_buffers(m12) == NULL && !gi_method_debug_buffer(m12, "beyond"));
    gi_plugins_free(old);
    static const gi_debug_buffer_desc ok_buf[] = {
        {"vis", "one line", GI_DEBUG_SCREEN}, {"map", "m", GI_DEBUG_OWN_SIZE}, {NULL, NULL, 0}};
    bad = *m;
    bad.debug_buffers = ok_buf;
    bad.debug_buffer = no_buffer;
    CHECK(gi_method_validate(&bad, &err) == GI_OK);
    CHECK(gi_method_debug_buffer(&bad, "map") == &ok_buf[1] && !gi_method_debug_buffer(&bad, "x"));
    static const struct {
        gi_debug_buffer_desc d[3];
        const char *error;
    } bad_bufs[] = {
        {{{"Vis", "x", 0}, {NULL, NULL, 0}}, "is not [a-z0-9_]"},
        {{{"vis", "", 0}, {NULL, NULL, 0}}, "one-line description"},
        {{{"vis", "a\nb", 0}, {NULL, NULL, 0}}, "one-line description"},
        {{{"vis", "x", 7}, {NULL, NULL, 0}}, "unknown space"},
        {{{"vis", "x", 0}, {"vis", "y", 0}, {NULL, NULL, 0}}, "declared twice"},
    };
    for (size_t i = 0; i < sizeof bad_bufs / sizeof bad_bufs[0]; i++) {
        bad.debug_buffers = bad_bufs[i].d;
        CHECK_MSG(gi_method_validate(&bad, &err) == GI_ERR_INVALID_ARGUMENT &&
                      strstr(err.text, bad_bufs[i].error),
                  "%s", err.text);
    }
    bad.debug_buffers = ok_buf;
    bad.debug_buffer = NULL;
    CHECK(gi_method_validate(&bad, &err) == GI_ERR_INVALID_ARGUMENT &&
          strstr(err.text, "lacks the function debug_buffer()"));
    /* A plugin built against the current headers passes the check. */
    static const gi_abi_layout current = GI_ABI_LAYOUT;
    CHECK(gi_abi_layout_check(&current, &err) == GI_OK);
    return gi_test_finish();
}
