/* TEMPORARY stand-ins for core helpers that are being written on main
 * (common.c). Lets the image/envmap/BRDF work build and test on its own;
 * removed as soon as main's versions are merged. */
#include <stdarg.h>
#include <stdio.h>

#include "gi/common.h"

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
