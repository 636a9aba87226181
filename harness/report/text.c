/* The report writers' growing text buffer (text.h). */
#include "text.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void gi_text_vput(gi_text *t, const char *fmt, va_list ap)
{
    va_list copy;
    va_copy(copy, ap);
    int n = vsnprintf(NULL, 0, fmt, copy);
    va_end(copy);
    if (n < 0) {
        t->failed = 1;
        return;
    }
    if (t->len + (size_t)n + 1 > t->cap) {
        size_t cap = t->cap ? t->cap : 4096;
        while (cap < t->len + (size_t)n + 1)
            cap *= 2;
        char *s = realloc(t->s, cap);
        if (!s) {
            t->failed = 1;
            return;
        }
        t->s = s;
        t->cap = cap;
    }
    vsnprintf(t->s + t->len, (size_t)n + 1, fmt, ap);
    t->len += (size_t)n;
}

void gi_text_put(gi_text *t, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    gi_text_vput(t, fmt, ap);
    va_end(ap);
}

/* The entity of c in HTML (with quote: '"' too), or NULL. */
static const char *entity(char c, int quote)
{
    return c == '<'            ? "&lt;"
           : c == '>'          ? "&gt;"
           : c == '&'          ? "&amp;"
           : quote && c == '"' ? "&quot;"
                               : NULL;
}

/* One character of a user's string: its entity, its backslash escape (a
 * character of `escaped`), or itself with line breaks as spaces. */
static void put_char(gi_text *t, char c, int quote, const char *escaped)
{
    const char *e = entity(c, quote);
    if (e)
        gi_text_put(t, "%s", e);
    else if (c && strchr(escaped, c))
        gi_text_put(t, "\\%c", c);
    else
        gi_text_put(t, "%c", c == '\n' || c == '\r' ? ' ' : c);
}

void gi_text_md(gi_text *t, const char *s)
{
    for (; *s; s++)
        put_char(t, *s, 0, "|`\\");
}

void gi_text_md_code(gi_text *t, const char *s)
{
    gi_text_put(t, "`");
    for (; *s; s++) {
        if (*s == '|')
            gi_text_put(t, "\\|");
        else
            gi_text_put(t, "%c", *s == '`' ? '\'' : *s == '\n' || *s == '\r' ? ' ' : *s);
    }
    gi_text_put(t, "`");
}

void gi_text_html(gi_text *t, const char *s)
{
    for (; *s; s++)
        put_char(t, *s, 1, "");
}
