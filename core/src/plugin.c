/* The plugin loader (plugin.h): dlopen, entry, descriptor checks. */
#define _POSIX_C_SOURCE 200809L
#include "gi/plugin.h"
#include "gi/kit.h"
#include "gi/log.h"

#include <dirent.h>
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

/* How long a plugin may take to load in the probe (constructors included). */
#define GI_PROBE_SECONDS 30

/* The size of gi_method in ABI 1.0: everything up to last_error. */
#define GI_METHOD_SIZE_1_0 (offsetof(gi_method, last_error) + sizeof(void *))

static char *dup_str(const char *s)
{
    size_t n = strlen(s) + 1;
    char *d = malloc(n);
    if (d)
        memcpy(d, s, n);
    return d;
}

static int valid_name(const char *s, int allow_upper)
{
    if (!s || !*s || strlen(s) > 31)
        return 0;
    for (const char *p = s; *p; p++)
        if (!((*p >= 'a' && *p <= 'z') || (*p >= '0' && *p <= '9') || *p == '_' ||
              (allow_upper && *p >= 'A' && *p <= 'Z')))
            return 0;
    return 1;
}

static gi_result validate_params(const gi_method *m, gi_error *err)
{
    for (uint32_t i = 0; m->params && m->params[i].name; i++) {
        const gi_param_desc *d = &m->params[i];
        if (!valid_name(d->name, 1))
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "parameter %u has an invalid name",
                                i);
        for (uint32_t k = 0; k < i; k++)
            if (strcmp(m->params[k].name, d->name) == 0)
                return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "parameter '%s' declared twice",
                                    d->name);
        if (d->type > GI_PARAM_ENUM)
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "parameter '%s' has an unknown type",
                                d->name);
        if (d->type == GI_PARAM_ENUM) {
            int n = 1;
            if (!d->choices || !*d->choices)
                return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                    "enum parameter '%s' has no choices", d->name);
            for (const char *p = d->choices; *p; p++)
                n += *p == '|';
            if (d->def < 0 || d->def >= n)
                return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                    "enum parameter '%s' default out of range", d->name);
        } else if ((d->type == GI_PARAM_INT || d->type == GI_PARAM_FLOAT) &&
                   !(d->min <= d->def && d->def <= d->max)) {
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                "parameter '%s' default %g outside [%g, %g]", d->name, d->def,
                                d->min, d->max);
        }
    }
    return GI_OK;
}

gi_result gi_method_create(const gi_method *m, const gi_host *host, const gi_params *params,
                           void **instance, gi_error *err)
{
    *instance = NULL;
    gi_result r = m->create(host, params, instance);
    if (r != GI_OK || !*instance) {
        if (r == GI_OK)
            r = GI_ERR_UNSUPPORTED; /* created nothing */
        if (*instance)
            m->destroy(*instance);
        *instance = NULL;
        gi_result bad = gi_params_check(params, m->id, err);
        return bad != GI_OK ? bad : gi_error_set(err, r, "create failed (%s)", gi_result_name(r));
    }
    r = gi_params_check(params, m->id, err);
    if (r != GI_OK) {
        m->destroy(*instance);
        *instance = NULL;
    }
    return r;
}

const gi_departure *gi_method_departure(const gi_method *m, const char *check)
{
    if (!m || !check || !GI_HAS_FIELD(m, gi_method, departures) || !m->departures)
        return NULL;
    for (const gi_departure *d = m->departures; d->check; d++)
        if (!strcmp(d->check, check))
            return d;
    return NULL;
}

int gi_departure_remedy_args(const gi_departure *d, char *buf, size_t size, const char **kv,
                             uint32_t max)
{
    if (!d || !d->remedy || strlen(d->remedy) >= size)
        return -1;
    snprintf(buf, size, "%s", d->remedy);
    uint32_t n = 0;
    char *save = NULL;
    for (char *tok = strtok_r(buf, " ", &save); tok; tok = strtok_r(NULL, " ", &save)) {
        if (n == max)
            return -1;
        kv[n++] = tok;
    }
    return (int)n;
}

/* Departures (ABI 1.2): each names a check the suite knows, gives a
 * one-line reason and a remedy its own parameter table accepts, once per
 * check; a declaration the suite could not act on is refused at load. */
static gi_result validate_departures(const gi_method *m, gi_error *err)
{
    if (!GI_HAS_FIELD(m, gi_method, departures) || !m->departures)
        return GI_OK;
    for (const gi_departure *d = m->departures; d->check; d++) {
        if (strcmp(d->check, "furnace") && strcmp(d->check, "held_out"))
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                "departure for unknown check '%s' (furnace, held_out)", d->check);
        if (gi_method_departure(m, d->check) != d)
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "departure '%s' declared twice",
                                d->check);
        if (!d->reason || !*d->reason || strchr(d->reason, '\n'))
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                "departure '%s' needs a one-line reason", d->check);
        char buf[512];
        const char *kv[16];
        int n = gi_departure_remedy_args(d, buf, sizeof buf, kv, 16);
        if (n <= 0)
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                "departure '%s' needs a remedy: up to 16 \"k=v\" parameters",
                                d->check);
        gi_error perr;
        gi_params *p = gi_params_parse(m->id, m->params, kv, (uint32_t)n, &perr);
        if (!p)
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "departure '%s' remedy: %s", d->check,
                                perr.text);
        gi_params_free(p);
    }
    return GI_OK;
}

const gi_debug_buffer_desc *gi_method_debug_buffers(const gi_method *m)
{
    if (!m || !GI_HAS_FIELD(m, gi_method, debug_buffers) || !m->debug_buffers ||
        !m->debug_buffers[0].name)
        return NULL;
    return m->debug_buffers;
}

const gi_debug_buffer_desc *gi_method_debug_buffer(const gi_method *m, const char *name)
{
    const gi_debug_buffer_desc *d = gi_method_debug_buffers(m);
    for (; d && name && d->name; d++)
        if (!strcmp(d->name, name))
            return d;
    return NULL;
}

/* Debug buffers (ABI 1.3): names a command line and a file name can carry,
 * each once, a one-line description, a known space, and the function that
 * makes them. */
static gi_result validate_debug_buffers(const gi_method *m, gi_error *err)
{
    const gi_debug_buffer_desc *d = gi_method_debug_buffers(m);
    if (!d)
        return GI_OK;
    if (!GI_HAS_FIELD(m, gi_method, debug_buffer) || !m->debug_buffer)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "declares debug buffers but lacks the function debug_buffer()");
    for (; d->name; d++) {
        if (!valid_name(d->name, 0))
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                "debug buffer name '%s' is not [a-z0-9_]{1,31}", d->name);
        if (gi_method_debug_buffer(m, d->name) != d)
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "debug buffer '%s' declared twice",
                                d->name);
        if (!d->description || !*d->description || strchr(d->description, '\n'))
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                "debug buffer '%s' needs a one-line description", d->name);
        if (d->space != GI_DEBUG_SCREEN && d->space != GI_DEBUG_OWN_SIZE)
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                "debug buffer '%s' has an unknown space %u", d->name, d->space);
    }
    return GI_OK;
}

gi_result gi_method_validate(const gi_method *m, gi_error *err)
{
    if (GI_ABI_VERSION_MAJOR(m->abi_version) != GI_ABI_MAJOR)
        return gi_error_set(
            err, GI_ERR_UNSUPPORTED, "built for plugin ABI %u.%u, this gibench speaks %u.%u",
            m->abi_version >> 16, m->abi_version & 0xFFFF, GI_ABI_MAJOR, GI_ABI_MINOR);
    if (m->struct_size < GI_METHOD_SIZE_1_0)
        return gi_error_set(err, GI_ERR_UNSUPPORTED,
                            "descriptor is %u bytes, ABI %u.0 needs at least %zu", m->struct_size,
                            GI_ABI_MAJOR, (size_t)GI_METHOD_SIZE_1_0);
    if (!valid_name(m->id, 0))
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "method id '%s' is not [a-z0-9_]{1,31}",
                            m->id ? m->id : "(null)");
    if (!m->title || !m->citation || !m->version)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "method '%s' lacks a title, citation or version", m->id);
    struct {
        const char *name;
        int present;
        size_t end;
    } fns[] = {
        {"create", m->create != NULL, offsetof(gi_method, create) + sizeof(void *)},
        {"prepare", m->prepare != NULL, offsetof(gi_method, prepare) + sizeof(void *)},
        {"update", m->update != NULL, offsetof(gi_method, update) + sizeof(void *)},
        {"render", m->render != NULL, offsetof(gi_method, render) + sizeof(void *)},
        {"destroy", m->destroy != NULL, offsetof(gi_method, destroy) + sizeof(void *)},
        {"last_error", m->last_error != NULL, offsetof(gi_method, last_error) + sizeof(void *)},
    };
    for (size_t i = 0; i < sizeof fns / sizeof fns[0]; i++)
        if (fns[i].end > m->struct_size || !fns[i].present)
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                "method '%s' lacks the required function %s()", m->id, fns[i].name);
    if (m->struct_size < offsetof(gi_method, layout) + sizeof m->layout)
        return gi_error_set(
            err, GI_ERR_UNSUPPORTED,
            "method '%s' has no data layout (built for ABI 1.0); rebuild it against this gibench "
            "(ABI %u.%u)",
            m->id, GI_ABI_MAJOR, GI_ABI_MINOR);
    gi_error lerr;
    if (gi_abi_layout_check(&m->layout, &lerr) != GI_OK)
        return gi_error_set(err, GI_ERR_UNSUPPORTED, "method '%s' %s", m->id, lerr.text);
    gi_error perr;
    if (validate_params(m, &perr) != GI_OK)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "method '%s': %s", m->id, perr.text);
    if (validate_departures(m, &perr) != GI_OK)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "method '%s': %s", m->id, perr.text);
    if (validate_debug_buffers(m, &perr) != GI_OK)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "method '%s': %s", m->id, perr.text);
    return GI_OK;
}

static int push_error(gi_plugins *reg, const char *text)
{
    char **e = realloc(reg->errors, (reg->error_count + 1) * sizeof *e);
    if (!e)
        return 0;
    reg->errors = e;
    reg->errors[reg->error_count] = dup_str(text);
    if (reg->errors[reg->error_count])
        reg->error_count++;
    return 1;
}

/* dlopen, entry and validation, with the descriptor returned (no registry);
 * the library handle into *handle when it is not NULL. */
static gi_result open_and_check(const char *path, const gi_method **out, void **handle,
                                gi_error *err)
{
    /* Never dlclose: see plugin.h. A refused library stays mapped too; it is
     * rare and closing it would run its destructors. */
    void *lib = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        const char *why = dlerror();
        return gi_error_set(err, GI_ERR_IO, "%s: cannot load: %s", path,
                            why ? why : "unknown reason");
    }
    gi_method_entry_fn entry;
    void *sym = dlsym(lib, "gi_method_entry");
    memcpy(&entry, &sym, sizeof entry);
    if (!sym)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "%s: no gi_method_entry symbol (not a gibench plugin)", path);
    const gi_method *m = entry(GI_ABI_VERSION);
    if (!m)
        return gi_error_set(
            err, GI_ERR_UNSUPPORTED,
            "%s: gi_method_entry returned NULL for host ABI %u.%u (built for another ABI major)",
            path, GI_ABI_MAJOR, GI_ABI_MINOR);
    gi_error verr;
    if (gi_method_validate(m, &verr) != GI_OK)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: %s", path, verr.text);
    *out = m;
    if (handle)
        *handle = lib;
    return GI_OK;
}

/* Plugins are loaded in a forked child first (dlopen with its
 * constructors, gi_method_entry, validation, then dlclose with its
 * destructors: the library's whole life but create and destroy, which need
 * a GL context and run in each render's own process), so that a plugin that
 * crashes, exits or hangs while loading or unloading is refused with one
 * line instead of taking the command down (a destructor that crashes would
 * otherwise kill every gibench process at exit, after its work, with its
 * output unflushed); the parent then maps only the plugins the child found
 * valid. Before dlclose the child reports "<index> -1" (unloading), so that
 * a death there is named as such. One child checks a whole batch in order and reports a line
 * "<index> <code> <message>" per plugin through a pipe; when it dies, the
 * first plugin it did not report is the culprit, and a new child goes on
 * with the next. The child leaves with _exit (no atexit handlers, no stdio
 * flush, no destructors). One child per batch, not per plugin: a fork of
 * gibench, and the first dlopen in it (copy-on-write faults all over the
 * loader's data), are the cost, not the plugins after it. */
typedef struct probe_result {
    gi_result code; /* GI_OK: load it in the parent */
    gi_error err;   /* the refusal, "path: reason" */
    int unloading;  /* the child reported it loaded and was unloading it */
} probe_result;

/* Writes all of line[0..len) to fd; a failed write ends the child. */
static void write_line(int fd, const char *line, int len)
{
    for (int done = 0; done < len;) {
        ssize_t w = write(fd, line + done, (size_t)(len - done));
        if (w < 0 && errno == EINTR)
            continue;
        if (w <= 0)
            _exit(3);
        done += (int)w;
    }
}

static void probe_child(char *const *paths, size_t from, size_t n, int fd)
{
    /* a crash here must end the child, whatever handlers the host set */
    signal(SIGSEGV, SIG_DFL);
    signal(SIGBUS, SIG_DFL);
    signal(SIGILL, SIG_DFL);
    signal(SIGFPE, SIG_DFL);
    signal(SIGABRT, SIG_DFL);
    signal(SIGPIPE, SIG_DFL);
    for (size_t i = from; i < n; i++) {
        gi_error cerr = {{0}};
        const gi_method *m = NULL;
        void *lib = NULL;
        gi_result r = open_and_check(paths[i], &m, &lib, &cerr);
        if (r == GI_OK) {
            char mark[48];
            write_line(fd, mark, snprintf(mark, sizeof mark, "%zu -1\n", i));
            dlclose(lib); /* its destructors run here */
        }
        for (char *c = cerr.text; *c; c++)
            if (*c == '\n' || *c == '\r')
                *c = ' ';
        char line[sizeof cerr.text + 48];
        int len =
            snprintf(line, sizeof line, "%zu %d %s\n", i, (int)r, r == GI_OK ? "" : cerr.text);
        if (len < 0 || (size_t)len >= sizeof line) {
            len = (int)sizeof line - 1;
            line[len - 1] = '\n';
        }
        write_line(fd, line, len);
    }
    _exit(0);
}

static long elapsed_ms(const struct timespec *since)
{
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    return (now.tv_sec - since->tv_sec) * 1000L + (now.tv_nsec - since->tv_nsec) / 1000000L;
}

/* Runs one child from `from`; fills out[] for what it reported, and for the
 * plugin it died on. Returns the index to go on from (n when done). */
static size_t probe_from(char *const *paths, size_t from, size_t n, probe_result *out)
{
    int fds[2];
    pid_t pid = -1;
    if (pipe(fds) == 0) {
        fflush(NULL); /* nothing buffered is written twice */
        pid = fork();
        if (pid == 0) {
            close(fds[0]);
            probe_child(paths, from, n, fds[1]);
        }
        close(fds[1]);
        if (pid < 0)
            close(fds[0]);
    }
    if (pid < 0) {
        gi_error_set(&out[from].err, GI_ERR_IO, "%s: cannot probe the plugin: %s", paths[from],
                     strerror(errno));
        out[from].code = GI_ERR_IO;
        return from + 1;
    }
    size_t next = from; /* the first plugin not reported yet */
    char buf[2 * sizeof(gi_error) + 64];
    size_t got = 0;
    int hung = 0;
    struct timespec since;
    clock_gettime(CLOCK_MONOTONIC, &since);
    for (;;) {
        long left_ms = GI_PROBE_SECONDS * 1000L - elapsed_ms(&since);
        if (left_ms <= 0) {
            hung = 1;
            break;
        }
        struct pollfd pfd = {.fd = fds[0], .events = POLLIN};
        int pr = poll(&pfd, 1, (int)left_ms);
        if (pr < 0 && errno == EINTR)
            continue;
        if (pr == 0) {
            hung = 1;
            break;
        }
        if (pr < 0)
            break;
        ssize_t r = read(fds[0], buf + got, sizeof buf - 1 - got);
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0)
            break; /* EOF: the child is gone */
        got += (size_t)r;
        buf[got] = '\0';
        char *nl;
        while ((nl = memchr(buf, '\n', got)) != NULL) {
            *nl = '\0';
            char *rest = NULL;
            unsigned long long idx = strtoull(buf, &rest, 10);
            long code = rest && *rest == ' ' ? strtol(rest + 1, &rest, 10) : -2;
            if (idx == next && idx < n && code == -1)
                out[idx].unloading = 1;
            if (idx == next && idx < n && code >= 0) {
                out[idx].code = code <= GI_ERR_IO ? (gi_result)code : GI_ERR_INVALID_ARGUMENT;
                if (out[idx].code != GI_OK)
                    snprintf(out[idx].err.text, sizeof out[idx].err.text, "%s",
                             *rest == ' ' ? rest + 1 : rest);
                next++;
                clock_gettime(CLOCK_MONOTONIC, &since); /* the time limit is per plugin */
            }
            size_t used = (size_t)(nl - buf) + 1;
            memmove(buf, nl + 1, got - used);
            got -= used;
        }
        if (got == sizeof buf - 1)
            got = 0; /* a line too long to be ours: dropped */
    }
    close(fds[0]);
    if (hung)
        kill(pid, SIGKILL);
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR)
        ;
    if (next >= n)
        return n;
    probe_result *bad = &out[next];
    bad->code = GI_ERR_UNSUPPORTED;
    if (hung)
        gi_error_set(&bad->err, bad->code, "%s: still %s after %d s (killed)", paths[next],
                     bad->unloading ? "unloading" : "loading", GI_PROBE_SECONDS);
    else if (WIFSIGNALED(status))
        gi_error_set(&bad->err, bad->code, "%s: crashed while %s (signal %d)", paths[next],
                     bad->unloading ? "unloading" : "loading", WTERMSIG(status));
    else
        gi_error_set(&bad->err, bad->code, "%s: exited while %s (status %d)", paths[next],
                     bad->unloading ? "unloading" : "loading",
                     WIFEXITED(status) ? WEXITSTATUS(status) : -1);
    return next + 1;
}

static void probe_all(char *const *paths, size_t n, probe_result *out)
{
    for (size_t i = 0; i < n;)
        i = probe_from(paths, i, n, out);
}

/* Maps a plugin the probe found valid and registers it. */
static gi_result add_probed(gi_plugins *reg, const char *path, gi_error *err)
{
    const gi_method *m = NULL;
    gi_result r = open_and_check(path, &m, NULL, err);
    if (r != GI_OK)
        return r;
    if (!reg)
        return GI_OK;
    for (uint32_t i = 0; i < reg->count; i++)
        if (strcmp(reg->items[i].method->id, m->id) == 0)
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                "%s: duplicate method id '%s' (already loaded from %s)", path,
                                m->id, reg->items[i].path);
    gi_plugin *items = realloc(reg->items, (reg->count + 1) * sizeof *items);
    if (!items)
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "out of memory");
    reg->items = items;
    reg->items[reg->count].method = m;
    reg->items[reg->count].path = dup_str(path);
    reg->count++;
    return GI_OK;
}

gi_result gi_plugins_add(gi_plugins *reg, const char *path, gi_error *err)
{
    probe_result pr = {GI_OK, {{0}}, 0};
    char *paths[1] = {(char *)path};
    probe_all(paths, 1, &pr);
    if (pr.code != GI_OK) {
        gi_error_set(err, pr.code, "%s", pr.err.text);
        return pr.code;
    }
    return add_probed(reg, path, err);
}

static int cmp_str(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

typedef struct path_list {
    char **v;
    size_t n;
} path_list;

/* Appends the folder's plugin files to `list`, sorted by name. A folder
 * that anyone may write to is refused whole (anyone could place code that
 * every gibench process then runs); an entry that is not a regular file
 * (a FIFO, a device, a folder) is refused without being opened: dlopen of
 * a FIFO blocks until the probe's time limit. Both land in reg->errors. */
static void scan_dir(gi_plugins *reg, path_list *list, const char *dir)
{
    DIR *d = opendir(dir);
    if (!d)
        return;
    struct stat st;
    char why[4400]; /* a path and its reason */
    if (fstat(dirfd(d), &st) == 0 && (st.st_mode & S_IWOTH)) {
        snprintf(why, sizeof why,
                 "%s: folder is world-writable: its plugins are not loaded (chmod o-w %s)", dir,
                 dir);
        push_error(reg, why);
        closedir(d);
        return;
    }
    char **names = NULL;
    size_t n = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        size_t len = strlen(e->d_name);
        if (strncmp(e->d_name, "gimethod_", 9) != 0 || len < 12 ||
            strcmp(e->d_name + len - 3, ".so") != 0)
            continue;
        if (fstatat(dirfd(d), e->d_name, &st, 0) != 0 || !S_ISREG(st.st_mode)) {
            snprintf(why, sizeof why, "%s/%s: not a regular file (skipped unopened)", dir,
                     e->d_name);
            push_error(reg, why);
            continue;
        }
        char **grown = realloc(names, (n + 1) * sizeof *names);
        if (!grown)
            break;
        names = grown;
        names[n] = dup_str(e->d_name);
        if (names[n])
            n++;
    }
    closedir(d);
    /* Sorted, so that which duplicate wins does not depend on readdir order
     * (a folder without plugins has no list to sort: qsort wants a pointer). */
    if (n > 1)
        qsort(names, n, sizeof *names, cmp_str);
    for (size_t i = 0; i < n; i++) {
        size_t len = strlen(dir) + strlen(names[i]) + 2;
        char *path = malloc(len);
        char **grown = path ? realloc(list->v, (list->n + 1) * sizeof *list->v) : NULL;
        if (grown) {
            snprintf(path, len, "%s/%s", dir, names[i]);
            list->v = grown;
            list->v[list->n++] = path;
        } else {
            free(path);
        }
        free(names[i]);
    }
    free(names);
}

gi_plugins *gi_plugins_scan(const char *build_dir)
{
    gi_plugins *reg = calloc(1, sizeof *reg);
    if (!reg)
        return NULL;
    path_list list = {NULL, 0};
    if (build_dir)
        scan_dir(reg, &list, build_dir);
    const char *env = getenv("GIBENCH_PLUGIN_PATH");
    if (env) {
        char *copy = dup_str(env), *save = NULL;
        for (char *tok = copy ? strtok_r(copy, ":", &save) : NULL; tok;
             tok = strtok_r(NULL, ":", &save))
            if (*tok && (!build_dir || strcmp(tok, build_dir) != 0))
                scan_dir(reg, &list, tok);
        free(copy);
    }
    /* every plugin is tried in a child first; only those it found valid
     * are mapped here, in the order found */
    probe_result *probed = list.n ? calloc(list.n, sizeof *probed) : NULL;
    if (probed)
        probe_all(list.v, list.n, probed);
    for (size_t i = 0; i < list.n; i++) {
        gi_error err;
        if (!probed)
            push_error(reg, "out of memory while probing plugins");
        else if (probed[i].code != GI_OK)
            push_error(reg, probed[i].err.text);
        else if (add_probed(reg, list.v[i], &err) != GI_OK)
            push_error(reg, err.text);
        free(list.v[i]);
    }
    free(probed);
    free(list.v);
    return reg;
}

const gi_method *gi_plugins_find(const gi_plugins *reg, const char *id)
{
    for (uint32_t i = 0; i < reg->count; i++)
        if (strcmp(reg->items[i].method->id, id) == 0)
            return reg->items[i].method;
    return NULL;
}

void gi_plugins_free(gi_plugins *reg)
{
    if (!reg)
        return;
    for (uint32_t i = 0; i < reg->count; i++)
        free(reg->items[i].path);
    for (uint32_t i = 0; i < reg->error_count; i++)
        free(reg->errors[i]);
    free(reg->items);
    free(reg->errors);
    free(reg);
}

void gi_view_from_camera(const gi_camera_frame *cf, uint32_t width, uint32_t height, float t,
                         gi_view *v)
{
    memset(v, 0, sizeof *v);
    v->width = width;
    v->height = height;
    gi_mat4_invert(v->view, cf->world_from_camera);
    gi_mat4_perspective(v->proj, cf->yfov, (float)width / (float)height, cf->znear, cf->zfar);
    gi_mat4_mul(v->view_proj, v->proj, v->view);
    gi_mat4_invert(v->inv_view_proj, v->view_proj);
    v->eye = cf->eye;
    v->yfov = cf->yfov;
    v->znear = cf->znear;
    v->zfar = cf->zfar;
    v->time = t;
}
