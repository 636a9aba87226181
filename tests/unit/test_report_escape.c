/* Names from users in report.md and index.html (issue 32 item 12): a study
 * title, scene name (reference set, run id), method label, parameters and
 * failure reason holding a <script>, '|', backticks, a backslash and a line
 * break show as written in both files, add no markup, split no table cell
 * and break no line. Covers report.c's writers and the speed-against-
 * accuracy text of tradeoff.c that they embed. */
#define _POSIX_C_SOURCE 200809L
#include "check.h"
#include "report.h"
#include "text.h"
#include "tradeoff.h"

#include "gi/cache.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define NASTY "<!--<script>alert(1)</script>|a`b`\\c\nline2"
/* NASTY as report.md shows it (text.h) and as index.html does */
#define NASTY_MD "&lt;!--&lt;script&gt;alert(1)&lt;/script&gt;\\|a\\`b\\`\\\\c line2"
#define NASTY_HTML "&lt;!--&lt;script&gt;alert(1)&lt;/script&gt;|a`b`\\c line2"

static json_object *record(const char *run, const char *status)
{
    json_object *o = json_object_new_object();
    json_object_object_add(o, "run", json_object_new_string(run));
    json_object_object_add(o, "scene", json_object_new_string(NASTY ".gltf"));
    json_object_object_add(o, "method", json_object_new_string(NASTY));
    json_object_object_add(o, "params", json_object_new_string("k=" NASTY));
    json_object_object_add(o, "status", json_object_new_string(status));
    json_object_object_add(o, "reason", json_object_new_string(NASTY));
    json_object *c = json_object_new_array();
    for (int k = 0; k < 2; k++) {
        json_object *p = json_object_new_object(), *f = json_object_new_object();
        json_object_object_add(p, "frame", json_object_new_int(1 << k));
        json_object_object_add(p, "time_ms", json_object_new_double(10.0 * (k + 1)));
        json_object_object_add(f, "relmse", json_object_new_double(0.5 / (k + 1)));
        json_object_object_add(p, "full", f);
        json_object_object_add(p, "matched", json_object_get(f));
        json_object_array_add(c, p);
    }
    json_object_object_add(o, "curve", c);
    return o;
}

/* The cells of a markdown table row: its '|' that are not escaped, less one. */
static int md_cells(const char *line, size_t n)
{
    int bars = 0;
    for (size_t i = 0; i < n; i++) {
        if (line[i] == '\\')
            i++;
        else if (line[i] == '|')
            bars++;
    }
    return bars - 1;
}

/* Every row of every table in md has as many cells as its header. */
static void check_tables(const char *md)
{
    int want = -1, rows = 0;
    for (const char *l = md; *l;) {
        const char *e = strchr(l, '\n');
        size_t n = e ? (size_t)(e - l) : strlen(l);
        if (n && l[0] == '|') {
            int c = md_cells(l, n);
            if (want < 0)
                want = c;
            CHECK_MSG(c == want, "a row of %d cells in a table of %d: %.*s", c, want, (int)n, l);
            rows++;
        } else
            want = -1;
        l = e ? e + 1 : l + n;
    }
    CHECK(rows >= 8);
}

/* md without its code spans (`...`, a backslash-escaped backtick is none). */
static char *strip_code(const char *md)
{
    char *out = malloc(strlen(md) + 1), *o = out;
    int code = 0;
    for (const char *p = md; out && *p; p++) {
        if (!code && *p == '\\' && p[1]) {
            *o++ = *p++;
            *o++ = *p;
        } else if (*p == '`')
            code = !code;
        else if (!code)
            *o++ = *p;
    }
    if (out)
        *o = '\0';
    return out ? out : calloc(1, 1);
}

static void check_file(const char *path, const char *want, int html)
{
    size_t n = 0;
    char *s = gi_file_read_all(path, &n);
    CHECK_MSG(s != NULL, "%s not written", path);
    if (!s)
        return;
    /* report.md's code spans show their text as written, HTML not read */
    char *bare = strip_code(s);
    CHECK_MSG(strstr(html ? s : bare, "<script>alert") == NULL &&
                  strstr(html ? s : bare, "<!--") == NULL,
              "%s: raw HTML from a name:\n%s", path, s);
    free(bare);
    CHECK_MSG(strstr(s, "\nline2") == NULL, "%s: a name broke a line:\n%s", path, s);
    CHECK_MSG(strstr(s, "`b`") == NULL || html, "%s: a name's backticks open code:\n%s", path, s);
    /* the title, the runs table, the heading and rows of the trade-off text */
    int seen = 0;
    for (const char *p = s; (p = strstr(p, want)); p++)
        seen++;
    CHECK_MSG(seen >= 6, "%s: '%s' shown %d times:\n%s", path, want, seen, s);
    if (!html)
        check_tables(s);
    else /* the parameters, as a code span in the trade-off table */
        CHECK_MSG(
            strstr(s, "<code>k=&lt;!--&lt;script&gt;alert(1)&lt;/script&gt;|a'b'\\c line2</code>"),
            "%s: the parameters' code span:\n%s", path, s);
    free(s);
}

int main(void)
{
    const char *tmp = getenv("TMPDIR");
    char buf[1024];
    snprintf(buf, sizeof buf, "%s/gibench-report-escape-XXXXXX", tmp && *tmp ? tmp : "/tmp");
    char *d = mkdtemp(buf);
    CHECK(d != NULL);
    if (!d)
        return gi_test_finish();

    json_object *runs = json_object_new_array();
    json_object_array_add(runs, record(NASTY "-1", "ok"));
    json_object_array_add(runs, record(NASTY "-2", "failed"));
    tradeoff_run tr[1] = {{json_object_array_get_idx(runs, 0), 65, 1}};
    tradeoff_pt_curve full = {.bounces = 65, .n = 2, .t = {1, 4}, .e = {1, 0.25}};
    gi_text md = {0};
    json_object *charts = json_object_new_array();
    tradeoff_report(d, NASTY, &full, NULL, 0, tr, 1, NULL, charts, &md, NULL);
    CHECK(md.s != NULL && !md.failed);

    char *argv[] = {NASTY};
    json_object *meta = report_meta_new(NASTY, "study", 1, argv, "llvmpipe", NASTY);
    json_object_object_add(meta, "markdown", json_object_new_string(md.s ? md.s : ""));
    char why[512] = "";
    CHECK_MSG(report_write(d, runs, meta, why, sizeof why), "report_write: %s", why);

    char path[1200];
    snprintf(path, sizeof path, "%s/report.md", d);
    check_file(path, NASTY_MD, 0);
    snprintf(path, sizeof path, "%s/index.html", d);
    check_file(path, NASTY_HTML, 1);

    /* GI_TEST_KEEP=1 keeps the files to look at */
    const char *names[] = {"report.md",  "index.html", "runs.csv",
                           "frames.csv", "curves.csv", "runs.json"};
    int keep = getenv("GI_TEST_KEEP") != NULL;
    for (size_t k = 0; !keep && k < sizeof names / sizeof names[0]; k++) {
        snprintf(path, sizeof path, "%s/%s", d, names[k]);
        unlink(path);
    }
    if (keep || rmdir(d) != 0)
        fprintf(stderr, "note: %s left behind\n", d);
    free(md.s);
    json_object_put(charts);
    json_object_put(meta);
    json_object_put(runs);
    return gi_test_finish();
}
