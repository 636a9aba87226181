/* Logging for the core and the harness.
 *
 * Messages go to stderr as "gibench: level: text". The level threshold is
 * process-wide (set once by the harness from -v / -q); that one global is the
 * only mutable state in the core besides what EGL itself keeps.
 */
#ifndef GI_LOG_H
#define GI_LOG_H

#include <stdarg.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef enum gi_log_level {
    GI_LOG_ERROR = 0,
    GI_LOG_WARN = 1,
    GI_LOG_INFO = 2,
    GI_LOG_DEBUG = 3,
} gi_log_level;

void gi_log_set_level(gi_log_level level);
gi_log_level gi_log_get_level(void);
void gi_log(gi_log_level level, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
void gi_logv(gi_log_level level, const char *fmt, va_list ap);

#ifdef __cplusplus
}
#endif
#endif
