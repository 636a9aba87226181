/* A growing text buffer for the report writers (report.c and its writers, tradeoff.c):
 * printf-style appends; on an allocation failure the append is dropped and
 * `failed` set, so the caller can refuse to write a partial file. */
#ifndef GIBENCH_TEXT_H
#define GIBENCH_TEXT_H

#include <stdarg.h>
#include <stddef.h>

typedef struct gi_text {
    char *s;
    size_t len, cap;
    int failed;
} gi_text;

void gi_text_put(gi_text *t, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
void gi_text_vput(gi_text *t, const char *fmt, va_list ap);

#endif
