/* Logging to stderr with a process-wide level threshold. */
#include "gi/log.h"

#include <stdio.h>

static gi_log_level g_level = GI_LOG_WARN;

void gi_log_set_level(gi_log_level level)
{
    g_level = level;
}

gi_log_level gi_log_get_level(void)
{
    return g_level;
}

void gi_logv(gi_log_level level, const char *fmt, va_list ap)
{
    static const char *names[] = {"error", "warning", "info", "debug"};
    if (level > g_level)
        return;
    fprintf(stderr, "gibench: %s: ", names[level]);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
}

void gi_log(gi_log_level level, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    gi_logv(level, fmt, ap);
    va_end(ap);
}
