/* gibench conformance: the items of one method's check list (docs/conformance.md): the furnace,
 * every shipped scene, determinism, resize and second prepare, updates, parameter values, unknown
 * parameters and light types, in a fixed order that the child's --from
 * counts in; the parent groups them into the table's checks. */
#define _POSIX_C_SOURCE 200809L
#include "conf.h"

#include <dirent.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

/* Shipped scenes, sorted, full paths. */
static uint32_t list_scenes(char names[][512], uint32_t max)
{
    DIR *d = opendir(CONF_SCENES);
    uint32_t n = 0;
    if (!d)
        return 0;
    struct dirent *e;
    while ((e = readdir(d)) && n < max) {
        size_t len = strlen(e->d_name);
        if ((len > 5 && !strcmp(e->d_name + len - 5, ".gltf")) ||
            (len > 4 && !strcmp(e->d_name + len - 4, ".glb")))
            snprintf(names[n++], 512, "%s/%s", CONF_SCENES, e->d_name);
    }
    closedir(d);
    for (uint32_t i = 1; i < n; i++) /* insertion sort: a stable order for the item indices */
        for (uint32_t j = i; j > 0 && strcmp(names[j - 1], names[j]) > 0; j--) {
            char t[512];
            memcpy(t, names[j], 512);
            memcpy(names[j], names[j - 1], 512);
            memcpy(names[j - 1], t, 512);
        }
    return n;
}

static void add_item(conf_item *items, uint32_t *n, const char *group, const char *fmt, ...)
{
    if (*n >= CONF_MAX_ITEMS)
        return;
    conf_item *it = &items[(*n)++];
    snprintf(it->group, sizeof it->group, "%s", group);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(it->arg, sizeof it->arg, fmt, ap);
    va_end(ap);
}

/* Parameter values: ints and floats at min and max, booleans both ways,
 * enums at every choice. */
static void param_items(const gi_method *m, conf_item *items, uint32_t *n)
{
    for (const gi_param_desc *d = m->params; d && d->name; d++) {
        switch (d->type) {
        case GI_PARAM_INT:
            add_item(items, n, "params", "%s=%lld", d->name, (long long)d->min);
            add_item(items, n, "params", "%s=%lld", d->name, (long long)d->max);
            break;
        case GI_PARAM_FLOAT:
            add_item(items, n, "params", "%s=%.9g", d->name, d->min);
            add_item(items, n, "params", "%s=%.9g", d->name, d->max);
            break;
        case GI_PARAM_BOOL:
            add_item(items, n, "params", "%s=false", d->name);
            add_item(items, n, "params", "%s=true", d->name);
            break;
        case GI_PARAM_ENUM: {
            char c[64];
            int choices = 1;
            for (const char *p = d->choices ? d->choices : ""; *p; p++)
                choices += *p == '|';
            for (int k = 0; k < choices; k++)
                add_item(items, n, "params", "%s=%s", d->name, gi_param_choice(d, k, c, sizeof c));
            break;
        }
        }
    }
}

uint32_t conf_build_items(const gi_method *m, conf_item *items)
{
    uint32_t n = 0;
    static char scenes[64][512];
    add_item(items, &n, "furnace_0.5", "050");
    add_item(items, &n, "furnace_0.8", "080");
    uint32_t ns = list_scenes(scenes, 64);
    for (uint32_t i = 0; i < ns; i++)
        add_item(items, &n, "scenes", "%s", scenes[i]);
    add_item(items, &n, "determinism", "-");
    add_item(items, &n, "resize_prepare", "-");
    add_item(items, &n, "update_transforms", "-");
    add_item(items, &n, "update_vertices", "-");
    add_item(items, &n, "update_lights", "-");
    add_item(items, &n, "update_camera", "-");
    param_items(m, items, &n);
    add_item(items, &n, "unknown_params", "-");
    add_item(items, &n, "light_area", "area");
    add_item(items, &n, "light_point", "point");
    add_item(items, &n, "light_spot", "spot");
    add_item(items, &n, "light_directional", "directional");
    add_item(items, &n, "light_environment", "environment");
    return n;
}

/* The time limit of one item. A method that precomputes (caps
 * `precompute`) may take far longer at a parameter's extreme (csm's N=256
 * is 65 536 maps per object): the item checks that the value works, and
 * its limit only guards against a hang, so such items get five times the
 * limit. */
double conf_item_limit(const gi_method *m, const conf_item *it, double base)
{
    return (m->caps & GI_CAP_PRECOMPUTE) && !strcmp(it->group, "params") ? 5.0 * base : base;
}
