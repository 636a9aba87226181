/* The report writers' growing text buffer (text.h). */
#include "text.h"

#include <stdio.h>
#include <stdlib.h>

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

void gi_text_md(gi_text *t, const char *s)
{
    for (; *s; s++) {
        if (*s == '<')
            gi_text_put(t, "&lt;");
        else if (*s == '>')
            gi_text_put(t, "&gt;");
        else if (*s == '&')
            gi_text_put(t, "&amp;");
        else if (*s == '|' || *s == '`' || *s == '\\')
            gi_text_put(t, "\\%c", *s);
        else
            gi_text_put(t, "%c", *s == '\n' || *s == '\r' ? ' ' : *s);
    }
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
    for (; *s; s++) {
        if (*s == '<')
            gi_text_put(t, "&lt;");
        else if (*s == '>')
            gi_text_put(t, "&gt;");
        else if (*s == '&')
            gi_text_put(t, "&amp;");
        else if (*s == '"')
            gi_text_put(t, "&quot;");
        else
            gi_text_put(t, "%c", *s == '\n' || *s == '\r' ? ' ' : *s);
    }
}
