/* Method parameters: typed, ranged, named after the paper's symbols.
 *
 * A plugin declares a static gi_param_desc table. The host parses
 * "name=value" strings against it (gi_params_parse): an unknown name, a
 * value of the wrong type or outside [min, max], or an enum value not in
 * the list is an error whose message names the method, the parameter and
 * the allowed values. Parameters not given take their default. Plugins read
 * values by name, in create() (the only call that sees them). Asking for a
 * name the table does not declare is a bug in the plugin that fails in
 * every build type: the getter returns 0 and remembers the name, and
 * gi_method_create (gi/plugin.h), through which the host creates every
 * instance, then refuses the instance with that name.
 */
#ifndef GI_PARAMS_H
#define GI_PARAMS_H

#include "gi/common.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum gi_param_type {
    GI_PARAM_INT = 0,
    GI_PARAM_FLOAT = 1,
    GI_PARAM_BOOL = 2, /* true/false/1/0/on/off */
    GI_PARAM_ENUM = 3, /* one of `choices`, "a|b|c"; value is the index */
} gi_param_type;

typedef struct gi_param_desc {
    const char *name; /* [a-z0-9_]+, e.g. "N", "vpls", "filter" */
    gi_param_type type;
    double def;      /* default (enum: index into choices) */
    double min, max; /* inclusive range (int, float) */
    /* enum: the choices, "nearest|pcf|rr". int and float: NULL, or the
     * parameter's quality mark (GI_QUALITY_UP / GI_QUALITY_DOWN below). */
    const char *choices;
    const char *symbol; /* the paper's symbol or section, e.g. "N (Sec. 4.1)" */
    const char *help;   /* one line */
} gi_param_desc;

/* Quality marks (issue 28; docs/conformance.md "Converges"). A quality knob
 * is an int or float parameter along which the method should get closer to
 * the truth: sample counts, bins, atlas or grid resolution, direction
 * counts. Its mark, written in the `choices` slot of its row (unused by
 * numbers, so the table's layout and every unmarked row stay as they are),
 * says which way is "more" and the step: one step multiplies the value by
 * `factor` (UP, factor > 1) or divides it by `factor` (DOWN: smaller is
 * finer, e.g. a subdivision threshold), rounded for ints to at least one
 * more (or less) than before and clamped to [min, max].
 *     {"N", GI_PARAM_INT, 16, 2, 256, GI_QUALITY_UP(2), "N (Sec. 4.1)", "..."},
 * `gibench conformance --held-out` raises every marked knob three steps
 * from its default and requires that the error does not grow beyond its
 * noise; `gibench methods` shows the marks. A knob the method cannot
 * converge in is marked GI_QUALITY_NONE("the reason"): the suite reports it
 * n/a with that reason instead of sweeping it (never a silent pass). */
#define GI_QUALITY_UP(factor) "quality:up:" #factor
#define GI_QUALITY_DOWN(factor) "quality:down:" #factor
#define GI_QUALITY_NONE(reason) "quality:none:" reason

typedef struct gi_param_quality {
    int dir;            /* +1: larger is better; -1: smaller is better; 0: does not converge */
    double factor;      /* > 1: the ratio of one step (1 when dir is 0) */
    const char *reason; /* dir 0: why it does not converge; else NULL */
} gi_param_quality;

/* 1 and *q when d is a marked int/float parameter, 0 when it carries no
 * mark, -1 when its mark is malformed (not "quality:up|down:F" with F > 1,
 * nor "quality:none:" with a reason). */
int gi_param_quality_of(const gi_param_desc *d, gi_param_quality *q);
/* The value `steps` quality steps better than `from` (from itself when
 * steps is 0), clamped to the range; ints change by at least 1 a step.
 * from when d carries no valid mark. */
double gi_param_quality_step(const gi_param_desc *d, double from, int steps);

/* The longest parameter name kept by gi_params_check's message, with its NUL. */
#define GI_PARAM_NAME_MAX 64

typedef struct gi_params {
    const gi_param_desc *desc; /* the method's table */
    uint32_t count;
    double *values;   /* count values, desc order */
    uint32_t *given;  /* 1 where set explicitly */
    char *undeclared; /* the first name read that desc does not declare; "" when none */
} gi_params;

/* Fills defaults and applies each "name=value" in kv[0..n). `method_id`
 * names the method in messages. Returns NULL + err on the first bad entry. */
gi_params *gi_params_parse(const char *method_id, const gi_param_desc *desc, const char *const *kv,
                           uint32_t n, gi_error *err);
void gi_params_free(gi_params *p);
/* Number of entries in a NULL-terminated table. */
uint32_t gi_param_desc_count(const gi_param_desc *desc);

/* The value of parameter `name`; 0 (and the name kept in p->undeclared)
 * for a name the table does not declare. */
int gi_params_int(const gi_params *p, const char *name);
float gi_params_float(const gi_params *p, const char *name);
int gi_params_bool(const gi_params *p, const char *name);
/* Enum value as its index into choices. */
int gi_params_enum(const gi_params *p, const char *name);
/* GI_OK, or GI_ERR_INVALID_ARGUMENT naming the first parameter read that
 * the table does not declare ("method 'x' read parameter 'y', which its
 * parameter table does not declare"). */
gi_result gi_params_check(const gi_params *p, const char *method_id, gi_error *err);
/* Canonical "a=1,b=pcf" text of all values (for cache keys, runs.csv).
 * Returns a malloc'd string. */
char *gi_params_to_string(const gi_params *p);
/* Choice `index` of an enum's "a|b|c" list copied into buf. */
const char *gi_param_choice(const gi_param_desc *d, int index, char *buf, size_t size);

#ifdef __cplusplus
}
#endif
#endif
