/* Result codes and small shared definitions of the gibench core.
 *
 * Every fallible core or plugin function returns a gi_result. GI_OK is zero,
 * so `if (r != GI_OK)` and `if (r)` both test for failure. The message that
 * goes with a failure is reported where the function documents it: the
 * error buffer passed in, the instance's last_error(), or the host log.
 * Programmer mistakes (NULL where the contract forbids it) are asserts.
 */
#ifndef GI_COMMON_H
#define GI_COMMON_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef enum gi_result {
    GI_OK = 0,
    GI_ERR_INVALID_ARGUMENT = 1, /* bad input: file, parameter, size */
    GI_ERR_UNSUPPORTED = 2,      /* the method cannot do what was asked */
    GI_ERR_GL = 3,               /* OpenGL reported an error */
    GI_ERR_OUT_OF_MEMORY = 4,
    GI_ERR_CANCELLED = 5,
    GI_ERR_IO = 6, /* a file could not be read or written */
} gi_result;

/* Readable name of a result code ("invalid argument", ...). */
const char *gi_result_name(gi_result r);

/* Error text buffers used throughout the core: fixed size, always
 * NUL-terminated, first error wins unless documented otherwise. */
#define GI_ERROR_MAX 512
typedef struct gi_error {
    char text[GI_ERROR_MAX];
} gi_error;

/* printf-style set of an error text; returns `code` so callers can write
 * `return gi_error_set(err, GI_ERR_IO, "%s: %s", path, strerror(errno));`.
 * `err` may be NULL (the message is dropped). */
gi_result gi_error_set(gi_error *err, gi_result code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

#ifdef __cplusplus
}
#endif
#endif
