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

/* Text from users (study titles, scene stems and so run ids and reference
 * set names, labels, parameters, failure reasons) in report.md and
 * index.html: every writer of either file puts such a string through one of
 * these, so that it shows as written and cannot add markup (a <script>, an
 * <img onerror=...>), end a table cell or a code span, or break a line. */

/* Markdown text: HTML's specials as entities (markdown passes raw HTML
 * through), '|', '`' and '\' backslash-escaped, line breaks as spaces. */
void gi_text_md(gi_text *t, const char *s);
/* A markdown code span `...` (HTML is not read in it): a backtick, which
 * would end it, becomes a quote, '|' is escaped (a table cell), line breaks
 * become spaces. */
void gi_text_md_code(gi_text *t, const char *s);
/* HTML text or a double-quoted attribute value: < > & " as entities, line
 * breaks as spaces (as in report.md). */
void gi_text_html(gi_text *t, const char *s);

#endif
