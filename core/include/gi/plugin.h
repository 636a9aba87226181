/* The plugin loader: finds, opens and checks method plugins.
 *
 * Search path: the directory given at creation (the build's plugin
 * directory), then each entry of $GIBENCH_PLUGIN_PATH (':'-separated).
 * A plugin is any file named gimethod_<id>.so there. Each is opened with
 * dlopen(RTLD_NOW | RTLD_LOCAL), its gi_method_entry called, and its
 * descriptor checked: entry present, non-NULL result, ABI major equal,
 * struct_size at least the 1.0 size, every required function inside
 * struct_size and non-NULL, a valid id, a valid parameter table, valid
 * declared departures (a known check, a one-line reason, a remedy that
 * parses against the parameter table), valid debug buffers (names [a-z0-9_]{1,31}, unique, a
 * one-line description, a known space, debug_buffer() present), no duplicate id (the first found
 * wins). All of this, and unloading it (dlclose: its destructors), is first tried in a child
 * process, so that a plugin that crashes or hangs there is refused. A refused plugin gives one line
 * "path: reason" in the registry's error list and is skipped. Libraries are never dlclose'd (shims
 * with C++/TLS destructors crash after unload); gi_plugins_free releases only the registry.
 */
#ifndef GI_PLUGIN_H
#define GI_PLUGIN_H

#include "gi/method.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct gi_plugin {
    const gi_method *method;
    char *path;
} gi_plugin;

typedef struct gi_plugins {
    gi_plugin *items;
    uint32_t count;
    char **errors; /* one "path: reason" line per refused plugin */
    uint32_t error_count;
} gi_plugins;

/* Scans `build_dir` (may be NULL) and $GIBENCH_PLUGIN_PATH. Never fails as
 * a whole: problems land in errors. */
gi_plugins *gi_plugins_scan(const char *build_dir);
/* Opens one plugin file and checks it; on refusal returns GI_ERR_* with
 * "path: reason" in err. Adds it to `reg` (which may be NULL to only check). */
gi_result gi_plugins_add(gi_plugins *reg, const char *path, gi_error *err);
const gi_method *gi_plugins_find(const gi_plugins *reg, const char *id);
void gi_plugins_free(gi_plugins *reg);
/* Checks a descriptor as the loader does (exposed for tests). */
gi_result gi_method_validate(const gi_method *m, gi_error *err);
/* The departure method m declares for `check` ("furnace", "held_out"), or
 * NULL when it declares none (or was built before ABI 1.2). */
const gi_departure *gi_method_departure(const gi_method *m, const char *check);
/* The debug buffers method m declares (ABI 1.3; terminated by name
 * NULL), or NULL when it declares none (or was built before ABI 1.3). */
const gi_debug_buffer_desc *gi_method_debug_buffers(const gi_method *m);
/* The debug buffer of m named `name`, or NULL. */
const gi_debug_buffer_desc *gi_method_debug_buffer(const gi_method *m, const char *name);
/* Splits d->remedy into at most `max` "k=v" strings kv[], pointing into
 * buf (size bytes); returns how many, or -1 when it does not fit. */
int gi_departure_remedy_args(const gi_departure *d, char *buf, size_t size, const char **kv,
                             uint32_t max);

/* m->create(host, params, instance), and then the parameter contract
 * (gi/params.h): an instance that read a parameter its table does not
 * declare is destroyed and refused with GI_ERR_INVALID_ARGUMENT naming the
 * parameter, in every build type. Any other failure is create()'s result,
 * with "create failed (<result>)" in err (the plugin's own message went to
 * host->log). On failure *instance is NULL. */
gi_result gi_method_create(const gi_method *m, const gi_host *host, const gi_params *params,
                           void **instance, gi_error *err);

#ifdef __cplusplus
}
#endif
#endif
