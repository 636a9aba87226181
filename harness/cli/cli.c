/* Helpers shared by the gibench subcommands. */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"

#include "gi/cache.h"
#include "gi/log.h"
#include "gi/timer.h"

#include <ctype.h>
#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

volatile sig_atomic_t cli_interrupted;

static void on_signal(int sig)
{
    (void)sig;
    cli_interrupted = 1;
}

void cli_install_signal_handlers(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
}

int cli_fail(int code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fputs("gibench: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
    return code;
}

int cli_parse_uint(const char *s, unsigned long min, unsigned long max, unsigned long *out)
{
    if (!s || !*s || *s == '-' || *s == '+')
        return 0;
    char *end;
    errno = 0;
    unsigned long v = strtoul(s, &end, 10);
    if (errno || *end || v < min || v > max)
        return 0;
    *out = v;
    return 1;
}

int cli_parse_float(const char *s, float *out)
{
    if (!s || !*s)
        return 0;
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    /* a float's range, not a double's: 1e39 would become inf */
    if (errno || *end || !isfinite(v) || fabs(v) > FLT_MAX || isspace((unsigned char)s[0]))
        return 0;
    *out = (float)v;
    return 1;
}

int cli_parse_exposure(const char *s, float *out)
{
    float v;
    if (!cli_parse_float(s, &v) || fabsf(v) > 64.0f)
        return 0;
    *out = v;
    return 1;
}

int cli_add_out(const char *cmd, const char **outs, int *count, int max, const char *path)
{
    const char *dot = strrchr(path, '.');
    if (*count == max)
        return cli_fail(EXIT_USAGE, "%s: at most %d --out files", cmd, max);
    if (!dot || (strcmp(dot, ".exr") && strcmp(dot, ".pfm") && strcmp(dot, ".png")))
        return cli_fail(EXIT_USAGE, "%s: --out '%s': use a .exr, .pfm or .png file name", cmd,
                        path);
    outs[(*count)++] = path;
    return 0;
}

int cli_frame_path(const char *pattern, uint32_t index, char *out, size_t size)
{
    size_t n = 0;
    int conversions = 0;
    for (const char *p = pattern; *p; p++) {
        char piece[32];
        const char *text = piece;
        if (*p != '%') {
            piece[0] = *p;
            piece[1] = '\0';
        } else if (p[1] == '%') {
            piece[0] = '%';
            piece[1] = '\0';
            p++;
        } else {
            int zero = p[1] == '0', width = 0;
            const char *q = p + 1 + zero;
            if (*q >= '1' && *q <= '9')
                width = *q++ - '0';
            if (*q != 'd' || ++conversions > 1)
                return 0;
            snprintf(piece, sizeof piece, zero ? "%0*u" : "%*u", width, index);
            p = q;
        }
        size_t len = strlen(text);
        if (n + len + 1 > size)
            return 0;
        memcpy(out + n, text, len + 1);
        n += len;
    }
    return conversions == 1 && n > 0;
}

int cli_parse_size(const char *s, uint32_t *w, uint32_t *h)
{
    const char *x = s ? strchr(s, 'x') : NULL;
    if (!x)
        return 0;
    char buf[32];
    size_t n = (size_t)(x - s);
    if (n == 0 || n >= sizeof buf)
        return 0;
    memcpy(buf, s, n);
    buf[n] = '\0';
    unsigned long a, b;
    if (!cli_parse_uint(buf, 1, GI_MAX_IMAGE_SIDE, &a) ||
        !cli_parse_uint(x + 1, 1, GI_MAX_IMAGE_SIDE, &b) || !gi_image_size_ok(a, b))
        return 0;
    *w = (uint32_t)a;
    *h = (uint32_t)b;
    return 1;
}

const char *cli_plugin_dir(void)
{
    const char *dir = getenv("GIBENCH_PLUGIN_DIR");
    return !dir ? GIBENCH_PLUGIN_DIR : *dir ? dir : NULL;
}

gi_plugins *cli_load_plugins(int quiet)
{
    /* A plugin's constructors run at dlopen, and what they print must not
     * land in our stdout (methods --json, diff --json): while the plugins
     * load, stdout is a copy of stderr. */
    fflush(stdout);
    int saved = dup(STDOUT_FILENO);
    if (saved >= 0)
        dup2(STDERR_FILENO, STDOUT_FILENO);
    gi_plugins *reg = gi_plugins_scan(cli_plugin_dir());
    if (saved >= 0) {
        fflush(stdout);
        dup2(saved, STDOUT_FILENO);
        close(saved);
    }
    if (reg && !quiet)
        for (uint32_t i = 0; i < reg->error_count; i++)
            fprintf(stderr, "gibench: warning: plugin refused: %s\n", reg->errors[i]);
    return reg;
}

void cli_caps_string(uint32_t caps, char *buf, size_t size)
{
    static const char *names[] = {"direct",       "indirect",     "glossy",      "mirror",
                                  "area-lights",  "point-lights", "directional", "environment",
                                  "rigid-motion", "deformation",  "progressive", "precompute",
                                  "visibility",   "textures"};
    buf[0] = '\0';
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        if (caps & (1u << i)) {
            size_t used = strlen(buf);
            snprintf(buf + used, size - used, "%s%s", used ? " " : "", names[i]);
        }
}

const char *cli_param_type_name(gi_param_type t)
{
    switch (t) {
    case GI_PARAM_INT:
        return "int";
    case GI_PARAM_FLOAT:
        return "float";
    case GI_PARAM_BOOL:
        return "bool";
    case GI_PARAM_ENUM:
        return "enum";
    }
    return "?";
}

/* ---- host services ---- */

static cli_host *self(const gi_host *h)
{
    return (cli_host *)h->user;
}

static void host_log(const gi_host *h, int level, const char *fmt, ...)
{
    char msg[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    gi_log((gi_log_level)(level < 0   ? 0
                          : level > 3 ? 3
                                      : level),
           "%s: %s", self(h)->method_id, msg);
}

void cli_format_duration(double seconds, char *out, size_t size)
{
    if (!isfinite(seconds) || seconds < 0) {
        snprintf(out, size, "?");
        return;
    }
    unsigned long s = (unsigned long)(seconds + 0.5);
    if (s >= 3600)
        snprintf(out, size, "%lu:%02lu:%02lu", s / 3600, s / 60 % 60, s % 60);
    else
        snprintf(out, size, "%lu:%02lu", s / 60, s % 60);
}

void cli_progress_start(cli_progress *p, const char *label)
{
    p->on = isatty(STDERR_FILENO) && gi_log_get_level() >= GI_LOG_WARN;
    p->open = 0;
    p->start = gi_now();
    snprintf(p->label, sizeof p->label, "%s", label);
}

void cli_progress_show(cli_progress *p, double fraction, uint64_t done, uint64_t total,
                       const char *note)
{
    if (!p->on)
        return;
    if (!(fraction >= 0))
        fraction = 0;
    if (fraction > 1)
        fraction = 1;
    double elapsed = gi_now() - p->start;
    char bar[21], el[32], eta[32] = "?", count[48] = "";
    int filled = (int)(fraction * 20.0);
    for (int i = 0; i < 20; i++)
        bar[i] = i < filled ? '#' : '.';
    bar[20] = '\0';
    cli_format_duration(elapsed, el, sizeof el);
    if (fraction > 0)
        cli_format_duration(elapsed * (1.0 - fraction) / fraction, eta, sizeof eta);
    if (total > 0)
        snprintf(count, sizeof count, "  %llu/%llu", (unsigned long long)done,
                 (unsigned long long)total);
    /* \033[K clears what a longer line left behind */
    fprintf(stderr, "\r%s [%s] %3d%%%s  %s elapsed, ETA %s%s%s\033[K", p->label, bar,
            (int)(fraction * 100.0), count, el, eta, note ? "  " : "", note ? note : "");
    fflush(stderr);
    p->open = 1;
}

void cli_progress_end(cli_progress *p)
{
    if (p->on && p->open)
        fputc('\n', stderr);
    p->open = 0;
}

/* A plugin's precomputation progress. The task names what is being done
 * (a plugin may name itself in it: no second prefix then); a new task
 * starts a new line and its own clock. */
static void host_progress(const gi_host *h, const char *task, float fraction)
{
    cli_host *c = self(h);
    if (!c->show_progress)
        return;
    size_t idl = strlen(c->method_id);
    int named = !strncmp(task, c->method_id, idl) && (task[idl] == ':' || task[idl] == ' ');
    char label[64];
    snprintf(label, sizeof label, "%s%s%s", named ? "" : c->method_id, named ? "" : ": ", task);
    if (!c->bar.open || strcmp(c->bar.label, label)) {
        cli_progress_end(&c->bar);
        cli_progress_start(&c->bar, label);
    }
    cli_progress_show(&c->bar, fraction, 0, 0, NULL);
    if (fraction >= 1.0f)
        cli_progress_end(&c->bar);
}

void cli_host_progress_end(cli_host *h)
{
    if (h->bar.open)
        cli_progress_show(&h->bar, 1.0, 0, 0, NULL);
    cli_progress_end(&h->bar);
}

static void host_stage_begin(const gi_host *h, const char *name)
{
    if (self(h)->timer)
        gi_timer_begin(self(h)->timer, name);
}

static void host_stage_end(const gi_host *h, const char *name)
{
    if (self(h)->timer)
        gi_timer_end(self(h)->timer, name);
}

static void host_stat(const gi_host *h, const char *name, double value)
{
    json_object_object_add(self(h)->stats, name, json_object_new_double(value));
}

static int host_cancelled(const gi_host *h)
{
    (void)h;
    return cli_interrupted != 0;
}

static void *host_proc(const char *name)
{
    (void)name;
    return NULL; /* plugins use libepoxy through gicore */
}

void cli_host_init(cli_host *h, const char *method_id, const char *cache_dir,
                   const gi_gpu_scene *gs, const char *renderer, int software)
{
    memset(h, 0, sizeof *h);
    h->method_id = method_id;
    h->stats = json_object_new_object();
    h->show_progress = isatty(STDERR_FILENO) && gi_log_get_level() >= GI_LOG_WARN;
    gi_host *g = &h->host;
    g->struct_size = sizeof *g;
    g->abi_version = GI_ABI_VERSION;
    g->user = h;
    g->log = host_log;
    g->progress = host_progress;
    g->stage_begin = host_stage_begin;
    g->stage_end = host_stage_end;
    g->stat = host_stat;
    g->cancelled = host_cancelled;
    g->cache_dir = cache_dir;
    g->gl_get_proc_address = host_proc;
    g->gpu_scene = gs;
    g->gl_renderer = renderer;
    g->gl_is_software = software;
}

void cli_host_free(cli_host *h)
{
    json_object_put(h->stats);
    h->stats = NULL;
}

int cli_write_json(const char *path, json_object *obj, char *why, size_t why_size)
{
    const char *text = json_object_to_json_string_ext(
        obj, JSON_C_TO_STRING_PRETTY | JSON_C_TO_STRING_SPACED | JSON_C_TO_STRING_NOSLASHESCAPE);
    gi_error err;
    size_t n = strlen(text);
    char *with_nl = malloc(n + 2);
    if (!with_nl) {
        snprintf(why, why_size, "out of memory");
        return 0;
    }
    memcpy(with_nl, text, n);
    with_nl[n] = '\n';
    int ok = gi_file_write_atomic(path, with_nl, n + 1, &err) == GI_OK;
    free(with_nl);
    if (!ok)
        snprintf(why, why_size, "%s", err.text);
    return ok;
}

int cli_save_json(const char *path, json_object *obj)
{
    char why[GI_ERROR_MAX];
    int ok = cli_write_json(path, obj, why, sizeof why);
    json_object_put(obj);
    return ok ? EXIT_OK : cli_fail(EXIT_RUN, "%s", why);
}

json_object *cli_timer_json(const gi_timer *t)
{
    json_object *o = json_object_new_object();
    gi_stage_stats st[GI_TIMER_MAX_STAGES + 1];
    uint32_t n = gi_timer_stats(t, st, GI_TIMER_MAX_STAGES + 1);
    for (uint32_t i = 0; i < n; i++) {
        json_object *s = json_object_new_object();
        json_object_object_add(s, "median_ms", json_object_new_double(st[i].median_ms));
        json_object_object_add(s, "min_ms", json_object_new_double(st[i].min_ms));
        json_object_object_add(s, "max_ms", json_object_new_double(st[i].max_ms));
        json_object_object_add(s, "mean_ms", json_object_new_double(st[i].mean_ms));
        json_object_object_add(s, "samples", json_object_new_int((int32_t)st[i].samples));
        /* every timed frame's value, in order (per-frame time of animations) */
        uint32_t n_ms = 0;
        const double *ms = gi_timer_samples(t, st[i].name, &n_ms);
        json_object *arr = json_object_new_array();
        for (uint32_t k = 0; ms && k < n_ms; k++)
            json_object_array_add(arr, json_object_new_double(ms[k]));
        json_object_object_add(s, "samples_ms", arr);
        json_object_object_add(o, st[i].name, s);
    }
    return o;
}

uint64_t cli_scene_content_hash(const gi_scene *s, const char *path)
{
    size_t n = 0;
    char *bytes = gi_file_read_all(path, &n);
    uint64_t hash = gi_hash64(bytes ? bytes : "", n, 0x5CE7E);
    free(bytes);
    for (uint32_t k = 0; k < s->object_count; k++) {
        uint64_t oh = gi_scene_object_hash(s, k);
        hash = gi_hash64(&oh, sizeof oh, hash);
    }
    for (uint32_t t = 0; t < s->texture_count; t++) {
        const gi_texture *tx = &s->textures[t];
        if (tx->rgba)
            hash = gi_hash64(tx->rgba, (size_t)tx->width * tx->height * 4 * sizeof(float), hash);
    }
    if (s->has_environment && s->environment.path) {
        bytes = gi_file_read_all(s->environment.path, &n);
        hash = gi_hash64(bytes ? bytes : "", n, hash);
        free(bytes);
    }
    return hash;
}

int cli_caps_cover(const gi_method *m, const gi_scene *s, int animated, char *why, size_t size)
{
    uint32_t c = m->caps;
    int point = 0, directional = 0, mirror = 0, glossy = 0, textured = 0;
    for (uint32_t i = 0; i < s->light_count; i++) {
        point |= s->lights[i].type != GI_LIGHT_DIRECTIONAL;
        directional |= s->lights[i].type == GI_LIGHT_DIRECTIONAL;
    }
    for (uint32_t i = 0; i < s->material_count; i++) {
        const gi_material *mat = &s->materials[i];
        int spec = mat->ks[0] + mat->ks[1] + mat->ks[2] > 0.0f;
        mirror |= spec && (mat->mirror || mat->exponent >= GI_MIRROR_EXPONENT);
        glossy |= spec && !(mat->mirror || mat->exponent >= GI_MIRROR_EXPONENT);
        textured |= mat->albedo_texture >= 0;
    }
    const char *missing[9];
    int n = 0;
    if (s->emitter_count && !(c & GI_CAP_AREA_LIGHTS))
        missing[n++] = "area lights";
    if (point && !(c & GI_CAP_POINT_LIGHTS))
        missing[n++] = "point or spot lights";
    if (directional && !(c & GI_CAP_DIRECTIONAL))
        missing[n++] = "directional lights";
    if (s->envmap && !(c & GI_CAP_ENVIRONMENT))
        missing[n++] = "environment light";
    if (mirror && !(c & GI_CAP_MIRROR))
        missing[n++] = "mirrors";
    if (glossy && !(c & GI_CAP_GLOSSY))
        missing[n++] = "glossy materials";
    if (textured && !(c & GI_CAP_TEXTURES))
        missing[n++] = "textures";
    if (animated && !(c & GI_CAP_RIGID_MOTION))
        missing[n++] = "moving objects";
    if (gi_scene_deforms(s) && !(c & GI_CAP_DEFORMATION))
        missing[n++] =
            "deforming meshes"; /* even for a still frame: the CPU copy holds the rest pose */
    if (n == 0)
        return 1;
    int used = snprintf(why, size, "%s does not handle %s", m->id, missing[0]);
    for (int i = 1; i < n && used >= 0 && (size_t)used < size; i++)
        used += snprintf(why + used, size - (size_t)used, "%s%s", i == n - 1 ? " or " : ", ",
                         missing[i]);
    return 0;
}

int cli_mkdirs(const char *path)
{
    char buf[4096];
    snprintf(buf, sizeof buf, "%s", path);
    for (char *p = buf + 1; *p; p++)
        if (*p == '/') {
            *p = '\0';
            if (mkdir(buf, 0755) != 0 && errno != EEXIST)
                return 0;
            *p = '/';
        }
    return mkdir(buf, 0755) == 0 || errno == EEXIST;
}

/* "$TMPDIR/<stem>-XXXXXX" (/tmp when TMPDIR is unset or empty) into out;
 * 0 with errno ENAMETOOLONG when it does not fit. */
static int temp_template(const char *stem, char *out, size_t size)
{
    const char *dir = getenv("TMPDIR");
    if (!dir || !dir[0])
        dir = "/tmp";
    int n = snprintf(out, size, "%s/%s-XXXXXX", dir, stem);
    if (n < 0 || (size_t)n >= size) {
        errno = ENAMETOOLONG;
        return 0;
    }
    return 1;
}

int cli_temp_dir(const char *stem, char *out, size_t size)
{
    if (!temp_template(stem, out, size))
        return 0;
    if (mkdtemp(out))
        return 1;
    int e = errno; /* glibc leaves its last guess in out: name the template */
    temp_template(stem, out, size);
    errno = e;
    return 0;
}

int cli_temp_file(const char *stem, char *out, size_t size)
{
    if (!temp_template(stem, out, size))
        return -1;
    int fd = mkstemp(out);
    if (fd < 0) {
        int e = errno; /* as cli_temp_dir: name the template, not glibc's guess */
        temp_template(stem, out, size);
        errno = e;
    }
    return fd;
}

json_object *cli_read_json(const char *path)
{
    size_t n;
    char *text = gi_file_read_all(path, &n);
    if (!text)
        return NULL;
    json_tokener *tok = json_tokener_new();
    json_object *o = json_tokener_parse_ex(tok, text, (int)n);
    if (json_tokener_get_error(tok) != json_tokener_success) {
        json_object_put(o);
        o = NULL;
    }
    json_tokener_free(tok);
    free(text);
    return o;
}
