/* Result names and error-text helpers. */
#include "gi/common.h"

#include <stdarg.h>
#include <stdio.h>

const char *gi_result_name(gi_result r)
{
    switch (r) {
    case GI_OK:
        return "ok";
    case GI_ERR_INVALID_ARGUMENT:
        return "invalid argument";
    case GI_ERR_UNSUPPORTED:
        return "unsupported";
    case GI_ERR_GL:
        return "GL error";
    case GI_ERR_OUT_OF_MEMORY:
        return "out of memory";
    case GI_ERR_CANCELLED:
        return "cancelled";
    case GI_ERR_IO:
        return "I/O error";
    }
    return "unknown error";
}

gi_result gi_error_set(gi_error *err, gi_result code, const char *fmt, ...)
{
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err->text, sizeof err->text, fmt, ap);
        va_end(ap);
    }
    return code;
}
