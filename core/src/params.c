/* Typed, ranged method parameters (params.h): unknown names are errors. */
#include "gi/params.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

uint32_t gi_param_desc_count(const gi_param_desc *desc)
{
    uint32_t n = 0;
    while (desc && desc[n].name)
        n++;
    return n;
}

const char *gi_param_choice(const gi_param_desc *d, int index, char *buf, size_t size)
{
    const char *p = d->choices ? d->choices : "";
    for (int i = 0; i < index && p; i++) {
        p = strchr(p, '|');
        p = p ? p + 1 : NULL;
    }
    if (!p) {
        snprintf(buf, size, "?");
        return buf;
    }
    const char *end = strchr(p, '|');
    size_t n = end ? (size_t)(end - p) : strlen(p);
    snprintf(buf, size, "%.*s", (int)n, p);
    return buf;
}

static int choice_index(const gi_param_desc *d, const char *value)
{
    const char *p = d->choices ? d->choices : "";
    size_t vl = strlen(value);
    for (int i = 0; p; i++) {
        const char *end = strchr(p, '|');
        size_t n = end ? (size_t)(end - p) : strlen(p);
        if (n == vl && strncmp(p, value, n) == 0)
            return i;
        p = end ? end + 1 : NULL;
    }
    return -1;
}

static int parse_value(const gi_param_desc *d, const char *v, double *out)
{
    char *end = NULL;
    errno = 0;
    /* the value is exactly its text: strtoll and strtod would skip blanks */
    if (!*v || isspace((unsigned char)v[0]))
        return 0;
    switch (d->type) {
    case GI_PARAM_INT: {
        long long x = strtoll(v, &end, 10);
        if (errno || end == v || *end)
            return 0;
        *out = (double)x;
        return 1;
    }
    case GI_PARAM_FLOAT: {
        double x = strtod(v, &end);
        if (errno || end == v || *end || !isfinite(x))
            return 0;
        *out = x;
        return 1;
    }
    case GI_PARAM_BOOL:
        if (!strcmp(v, "true") || !strcmp(v, "1") || !strcmp(v, "on") || !strcmp(v, "yes"))
            *out = 1.0;
        else if (!strcmp(v, "false") || !strcmp(v, "0") || !strcmp(v, "off") || !strcmp(v, "no"))
            *out = 0.0;
        else
            return 0;
        return 1;
    case GI_PARAM_ENUM: {
        int i = choice_index(d, v);
        if (i < 0)
            return 0;
        *out = i;
        return 1;
    }
    }
    return 0;
}

static const char *type_name(gi_param_type t)
{
    switch (t) {
    case GI_PARAM_INT:
        return "an integer";
    case GI_PARAM_FLOAT:
        return "a number";
    case GI_PARAM_BOOL:
        return "true or false";
    case GI_PARAM_ENUM:
        return "one of";
    }
    return "?";
}

static void list_names(const gi_param_desc *desc, char *buf, size_t size)
{
    buf[0] = '\0';
    for (uint32_t i = 0; desc && desc[i].name; i++) {
        size_t used = strlen(buf);
        snprintf(buf + used, size - used, "%s%s", i ? ", " : "", desc[i].name);
    }
    if (!buf[0])
        snprintf(buf, size, "none");
}

gi_params *gi_params_parse(const char *method_id, const gi_param_desc *desc, const char *const *kv,
                           uint32_t n, gi_error *err)
{
    gi_params *p = calloc(1, sizeof *p);
    uint32_t count = gi_param_desc_count(desc);
    if (!p)
        goto oom;
    p->desc = desc;
    p->count = count;
    p->values = calloc(count ? count : 1, sizeof *p->values);
    p->given = calloc(count ? count : 1, sizeof *p->given);
    p->undeclared = calloc(GI_PARAM_NAME_MAX, 1);
    if (!p->values || !p->given || !p->undeclared)
        goto oom;
    for (uint32_t i = 0; i < count; i++)
        p->values[i] = desc[i].def;
    for (uint32_t k = 0; k < n; k++) {
        const char *eq = strchr(kv[k], '=');
        if (!eq || eq == kv[k]) {
            gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: parameter '%s' is not name=value",
                         method_id, kv[k]);
            goto fail;
        }
        size_t nl = (size_t)(eq - kv[k]);
        const char *value = eq + 1;
        uint32_t i = 0;
        while (i < count && !(strlen(desc[i].name) == nl && strncmp(desc[i].name, kv[k], nl) == 0))
            i++;
        if (i == count) {
            char names[512];
            list_names(desc, names, sizeof names);
            gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: unknown parameter '%.*s' (known: %s)",
                         method_id, (int)nl, kv[k], names);
            goto fail;
        }
        const gi_param_desc *d = &desc[i];
        double v;
        if (!parse_value(d, value, &v)) {
            if (d->type == GI_PARAM_ENUM)
                gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: %s='%s' is not one of %s",
                             method_id, d->name, value, d->choices);
            else
                gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: %s='%s' is not %s", method_id,
                             d->name, value, type_name(d->type));
            goto fail;
        }
        if ((d->type == GI_PARAM_INT || d->type == GI_PARAM_FLOAT) && (v < d->min || v > d->max)) {
            gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: %s=%s is outside [%g, %g]", method_id,
                         d->name, value, d->min, d->max);
            goto fail;
        }
        if (p->given[i]) {
            gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: parameter '%s' given twice", method_id,
                         d->name);
            goto fail;
        }
        p->values[i] = v;
        p->given[i] = 1;
    }
    return p;
oom:
    gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "out of memory");
fail:
    gi_params_free(p);
    return NULL;
}

void gi_params_free(gi_params *p)
{
    if (!p)
        return;
    free(p->values);
    free(p->given);
    free(p->undeclared);
    free(p);
}

/* The value of `name`, or 0 when the table does not declare it; the first
 * such name is kept for gi_params_check (p->undeclared points to memory of
 * the parameter set's own, so a const set can still record it). */
static double value_of(const gi_params *p, const char *name)
{
    for (uint32_t i = 0; i < p->count; i++)
        if (strcmp(p->desc[i].name, name) == 0)
            return p->values[i];
    if (p->undeclared && !p->undeclared[0])
        snprintf(p->undeclared, GI_PARAM_NAME_MAX, "%s", name && name[0] ? name : "(empty)");
    return 0.0;
}

int gi_params_int(const gi_params *p, const char *name)
{
    return (int)value_of(p, name);
}
float gi_params_float(const gi_params *p, const char *name)
{
    return (float)value_of(p, name);
}
int gi_params_bool(const gi_params *p, const char *name)
{
    return value_of(p, name) != 0.0;
}
int gi_params_enum(const gi_params *p, const char *name)
{
    return (int)value_of(p, name);
}

gi_result gi_params_check(const gi_params *p, const char *method_id, gi_error *err)
{
    if (!p || !p->undeclared || !p->undeclared[0])
        return GI_OK;
    return gi_error_set(
        err, GI_ERR_INVALID_ARGUMENT,
        "method '%s' read parameter '%s', which its parameter table does not declare (a bug in the "
        "plugin)",
        method_id, p->undeclared);
}

char *gi_params_to_string(const gi_params *p)
{
    size_t cap = 64 + (size_t)p->count * 96;
    char *s = malloc(cap);
    if (!s)
        return NULL;
    s[0] = '\0';
    for (uint32_t i = 0; i < p->count; i++) {
        const gi_param_desc *d = &p->desc[i];
        char val[64];
        switch (d->type) {
        case GI_PARAM_INT:
            snprintf(val, sizeof val, "%lld", (long long)p->values[i]);
            break;
        case GI_PARAM_FLOAT:
            snprintf(val, sizeof val, "%.9g", p->values[i]);
            break;
        case GI_PARAM_BOOL:
            snprintf(val, sizeof val, "%s", p->values[i] != 0.0 ? "true" : "false");
            break;
        case GI_PARAM_ENUM:
            gi_param_choice(d, (int)p->values[i], val, sizeof val);
            break;
        }
        size_t used = strlen(s);
        snprintf(s + used, cap - used, "%s%s=%s", i ? "," : "", d->name, val);
    }
    return s;
}

int gi_param_quality_of(const gi_param_desc *d, gi_param_quality *q)
{
    if (!d || (d->type != GI_PARAM_INT && d->type != GI_PARAM_FLOAT) || !d->choices)
        return 0;
    const char *s = d->choices;
    int dir = 0;
    if (!strncmp(s, "quality:none:", 13)) {
        if (!s[13])
            return -1; /* a knob that does not converge says why */
        if (q) {
            q->dir = 0;
            q->factor = 1.0;
            q->reason = s + 13;
        }
        return 1;
    }
    if (!strncmp(s, "quality:up:", 11))
        dir = 1;
    else if (!strncmp(s, "quality:down:", 13))
        dir = -1;
    else
        return -1;
    const char *f = s + (dir > 0 ? 11 : 13);
    char *end = NULL;
    double factor = strtod(f, &end);
    if (end == f || *end || !(factor > 1.0) || !isfinite(factor))
        return -1;
    if (q) {
        q->dir = dir;
        q->factor = factor;
        q->reason = NULL;
    }
    return 1;
}

double gi_param_quality_step(const gi_param_desc *d, double from, int steps)
{
    gi_param_quality q;
    if (gi_param_quality_of(d, &q) != 1 || q.dir == 0)
        return from;
    double v = from;
    for (int k = 0; k < steps; k++) {
        double next = q.dir > 0 ? v * q.factor : v / q.factor;
        if (d->type == GI_PARAM_INT) {
            /* an int step moves by at least one, so a small default still rises */
            next = q.dir > 0 ? fmax(round(next), v + 1.0) : fmin(round(next), v - 1.0);
        }
        v = fmin(fmax(next, d->min), d->max);
    }
    return v;
}
