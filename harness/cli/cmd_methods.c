/* gibench methods: the installed method plugins and their parameters. */
#include "cli.h"

#include <stdio.h>
#include <string.h>

static json_object *param_json(const gi_param_desc *d)
{
    json_object *p = json_object_new_object();
    json_object_object_add(p, "name", json_object_new_string(d->name));
    json_object_object_add(p, "type", json_object_new_string(cli_param_type_name(d->type)));
    if (d->type == GI_PARAM_ENUM) {
        char buf[64];
        json_object_object_add(
            p, "default", json_object_new_string(gi_param_choice(d, (int)d->def, buf, sizeof buf)));
        json_object_object_add(p, "choices", json_object_new_string(d->choices));
    } else if (d->type == GI_PARAM_BOOL) {
        json_object_object_add(p, "default", json_object_new_boolean(d->def != 0.0));
    } else if (d->type == GI_PARAM_INT) {
        json_object_object_add(p, "default", json_object_new_int64((int64_t)d->def));
        json_object_object_add(p, "min", json_object_new_int64((int64_t)d->min));
        json_object_object_add(p, "max", json_object_new_int64((int64_t)d->max));
    } else {
        json_object_object_add(p, "default", json_object_new_double(d->def));
        json_object_object_add(p, "min", json_object_new_double(d->min));
        json_object_object_add(p, "max", json_object_new_double(d->max));
    }
    gi_param_quality q;
    if (gi_param_quality_of(d, &q) == 1) { /* a quality knob (params.h) */
        json_object *qo = json_object_new_object();
        json_object_object_add(qo, "more_is",
                               json_object_new_string(q.dir > 0   ? "up"
                                                      : q.dir < 0 ? "down"
                                                                  : "none"));
        if (q.reason)
            json_object_object_add(qo, "does_not_converge", json_object_new_string(q.reason));
        json_object_object_add(qo, "factor", json_object_new_double(q.factor));
        /* the values the held-out sweep runs: it stops where the range clamps a step
         * (conf_heldout_run.c), so a repeated value is not listed */
        json_object *steps = json_object_new_array();
        double prev = d->def;
        for (int k = 1; k <= 3; k++) {
            double v = gi_param_quality_step(d, d->def, k);
            if (v == prev)
                break;
            json_object_array_add(steps, json_object_new_double(v));
            prev = v;
        }
        json_object_object_add(qo, "steps", steps);
        json_object_object_add(p, "quality", qo);
    }
    json_object_object_add(p, "symbol", json_object_new_string(d->symbol ? d->symbol : ""));
    json_object_object_add(p, "help", json_object_new_string(d->help ? d->help : ""));
    return p;
}

static void print_param(const gi_param_desc *d)
{
    char range[96] = "";
    char def[64];
    switch (d->type) {
    case GI_PARAM_ENUM:
        gi_param_choice(d, (int)d->def, def, sizeof def);
        snprintf(range, sizeof range, "{%s}", d->choices);
        break;
    case GI_PARAM_BOOL:
        snprintf(def, sizeof def, "%s", d->def != 0.0 ? "true" : "false");
        break;
    default:
        snprintf(def, sizeof def, "%g", d->def);
        snprintf(range, sizeof range, "[%g, %g]", d->min, d->max);
        break;
    }
    gi_param_quality q;
    char mark[64] = "";
    if (gi_param_quality_of(d, &q) == 1 && q.dir == 0)
        snprintf(mark, sizeof mark, " [does not converge: %.40s]", q.reason);
    else if (gi_param_quality_of(d, &q) == 1)
        snprintf(mark, sizeof mark, " [quality: %s is better, x%g a step]",
                 q.dir > 0 ? "more" : "less", q.factor);
    printf("    %-12s %-5s default %-8s %-18s %s%s%s%s%s\n", d->name, cli_param_type_name(d->type),
           def, range, d->help ? d->help : "", d->symbol ? " (" : "", d->symbol ? d->symbol : "",
           d->symbol ? ")" : "", mark);
}

/* The method's declared departures (gi_departure, ABI 1.2): the checks where the paper's
 * method, at its defaults, is known to fail, why, and the remedy the conformance suite checks. */
static json_object *departures_json(const gi_method *m)
{
    json_object *arr = json_object_new_array();
    static const char *const checks[] = {"furnace", "held_out"};
    for (size_t k = 0; k < sizeof checks / sizeof checks[0]; k++) {
        const gi_departure *d = gi_method_departure(m, checks[k]);
        if (!d)
            continue;
        json_object *o = json_object_new_object();
        json_object_object_add(o, "check", json_object_new_string(d->check));
        json_object_object_add(o, "reason", json_object_new_string(d->reason));
        json_object_object_add(o, "remedy", json_object_new_string(d->remedy));
        json_object_array_add(arr, o);
    }
    return arr;
}

static void print_departures(const gi_method *m)
{
    static const char *const checks[] = {"furnace", "held_out"};
    for (size_t k = 0; k < sizeof checks / sizeof checks[0]; k++) {
        const gi_departure *d = gi_method_departure(m, checks[k]);
        if (d)
            printf("  declared departure (%s): %s\n    remedy checked instead: %s\n", d->check,
                   d->reason, d->remedy);
    }
}

/* The method's debug buffers (gi_debug_buffer_desc, ABI 1.3): what
 * `render --buffer NAME` writes and gibench view shows. */
static json_object *buffers_json(const gi_method *m)
{
    json_object *arr = json_object_new_array();
    for (const gi_debug_buffer_desc *d = gi_method_debug_buffers(m); d && d->name; d++) {
        json_object *o = json_object_new_object();
        json_object_object_add(o, "name", json_object_new_string(d->name));
        json_object_object_add(o, "description", json_object_new_string(d->description));
        json_object_object_add(
            o, "space", json_object_new_string(d->space == GI_DEBUG_SCREEN ? "screen" : "own"));
        json_object_array_add(arr, o);
    }
    return arr;
}

static void print_buffers(const gi_method *m)
{
    const gi_debug_buffer_desc *d = gi_method_debug_buffers(m);
    if (d)
        printf("  debug buffers (render --buffer NAME):\n");
    for (; d && d->name; d++)
        printf("    %-12s %-6s %s\n", d->name, d->space == GI_DEBUG_SCREEN ? "screen" : "own",
               d->description);
}

json_object *cli_method_json(const gi_plugin *it)
{
    const gi_method *m = it->method;
    json_object *o = json_object_new_object();
    char caps[256];
    cli_caps_string(m->caps, caps, sizeof caps);
    json_object_object_add(o, "id", json_object_new_string(m->id));
    json_object_object_add(o, "title", json_object_new_string(m->title));
    json_object_object_add(o, "citation", json_object_new_string(m->citation));
    json_object_object_add(o, "version", json_object_new_string(m->version));
    json_object_object_add(o, "caps", json_object_new_string(caps));
    json_object_object_add(o, "max_bounces", json_object_new_int((int32_t)m->max_bounces));
    json_object_object_add(o, "path", json_object_new_string(it->path));
    json_object *ps = json_object_new_array();
    for (const gi_param_desc *d = m->params; d && d->name; d++)
        json_object_array_add(ps, param_json(d));
    json_object_object_add(o, "params", ps);
    json_object_object_add(o, "departures", departures_json(m));
    json_object_object_add(o, "buffers", buffers_json(m));
    return o;
}

int cmd_methods(int argc, char **argv)
{
    int json = 0;
    const char *only = NULL; /* methods ID: that method alone */
    for (int i = 0; i < argc; i++) {
        if (!strcmp(argv[i], "--json"))
            json = 1;
        else if (argv[i][0] != '-' && !only)
            only = argv[i];
        else
            return cli_fail(EXIT_USAGE, "methods: unknown argument '%s'", argv[i]);
    }
    gi_plugins *reg = cli_load_plugins(0);
    if (!reg)
        return cli_fail(EXIT_RUN, "out of memory");
    if (only && !gi_plugins_find(reg, only)) {
        gi_plugins_free(reg);
        return cli_fail(EXIT_USAGE, "methods: no method '%s' (gibench methods lists them)", only);
    }
    if (json) {
        json_object *arr = json_object_new_array();
        for (uint32_t i = 0; i < reg->count; i++)
            if (!only || !strcmp(reg->items[i].method->id, only))
                json_object_array_add(arr, cli_method_json(&reg->items[i]));
        puts(json_object_to_json_string_ext(arr, JSON_C_TO_STRING_PRETTY | JSON_C_TO_STRING_SPACED |
                                                     JSON_C_TO_STRING_NOSLASHESCAPE));
        json_object_put(arr);
    } else {
        if (reg->count == 0)
            printf("no method plugins found (build directory %s, GIBENCH_PLUGIN_PATH)\n",
                   cli_plugin_dir() ? cli_plugin_dir() : "none");
        for (uint32_t i = 0; i < reg->count; i++) {
            const gi_method *m = reg->items[i].method;
            if (only && strcmp(m->id, only))
                continue;
            char caps[256];
            cli_caps_string(m->caps, caps, sizeof caps);
            printf("%s  %s (v%s)\n  %s\n  caps: %s; indirect bounces: %u\n", m->id, m->title,
                   m->version, m->citation, caps, m->max_bounces);
            if (m->params && m->params[0].name) {
                printf("  parameters:\n");
                for (const gi_param_desc *d = m->params; d->name; d++)
                    print_param(d);
            }
            print_departures(m);
            print_buffers(m);
        }
    }
    gi_plugins_free(reg);
    return EXIT_OK;
}
