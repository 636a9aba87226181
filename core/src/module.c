/* Optional modules (gi/module.h): found beside libgicore.so, opened on
 * first use, never closed. */
#define _GNU_SOURCE
#include "gi/module.h"

#include <dlfcn.h>
#include <pthread.h>
#include <stdio.h>
#include <string.h>

#define MAX_MODULES 8

static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
static pthread_once_t dir_once = PTHREAD_ONCE_INIT;
static char dir[4096];

static struct {
    char file[64];
    void *handle;
} opened[MAX_MODULES];
static unsigned opened_count;

static void find_dir(void)
{
    Dl_info info;
    /* Any object of this library names its file. */
    if (!dladdr((const void *)dir, &info) || !info.dli_fname)
        return;
    const char *slash = strrchr(info.dli_fname, '/');
    size_t n = slash ? (size_t)(slash - info.dli_fname) : 0;
    if (n >= sizeof dir)
        return;
    memcpy(dir, info.dli_fname, n);
    dir[n] = '\0';
}

const char *gi_module_dir(void)
{
    pthread_once(&dir_once, find_dir);
    return dir;
}

/* One line of dlerror(): its messages have no newline, but be sure. */
static void one_line(char *s)
{
    for (; *s; s++)
        if (*s == '\n' || *s == '\r')
            *s = ' ';
}

void *gi_module_symbol(const char *file, const char *symbol, const char *what, gi_error *err)
{
    const char *d = gi_module_dir();
    char path[4200];
    snprintf(path, sizeof path, "%s/%s", *d ? d : ".", file);
    pthread_mutex_lock(&lock);
    void *handle = NULL;
    for (unsigned i = 0; i < opened_count && i < MAX_MODULES; i++)
        if (!strcmp(opened[i].file, file))
            handle = opened[i].handle;
    if (!handle) {
        handle = dlopen(path, RTLD_NOW | RTLD_LOCAL);
        if (!handle) {
            char reason[1024];
            const char *e = dlerror();
            /* dlerror() begins with the path, which the message names already. */
            size_t pn = strlen(path);
            if (e && !strncmp(e, path, pn) && !strncmp(e + pn, ": ", 2))
                e += pn + 2;
            snprintf(reason, sizeof reason, "%s", e ? e : "unknown dlopen error");
            one_line(reason);
            pthread_mutex_unlock(&lock);
            gi_error_set(err, GI_ERR_UNSUPPORTED, "%s needs the module %s: %s", what, path, reason);
            return NULL;
        }
        if (opened_count < MAX_MODULES && strlen(file) < sizeof opened[0].file) {
            snprintf(opened[opened_count].file, sizeof opened[0].file, "%s", file);
            opened[opened_count++].handle = handle;
        }
    }
    dlerror();
    void *sym = dlsym(handle, symbol);
    pthread_mutex_unlock(&lock);
    if (!sym)
        gi_error_set(err, GI_ERR_UNSUPPORTED, "%s needs the module %s: it has no symbol %s", what,
                     path, symbol);
    return sym;
}
