/* index.html of a report (report.h): the runs, their stage timings, the
 * speed-against-accuracy tables and the charts, with the image viewer's
 * script and style (assets/, embedded at build time) inline. */
#include "report_internal.h"

#include "gi/shader.h"

#include <ctype.h>
#include <string.h>

#define html_escape gi_text_html /* text.h */

/* The page's script and style, embedded at build time (harness/report/CMakeLists.txt). */
extern const gi_shader_source gi_report_assets[];

static const char *asset(const char *name)
{
    for (const gi_shader_source *a = gi_report_assets; a->name; a++)
        if (!strcmp(a->name, name))
            return a->text;
    return "";
}

static void html_num(text *t, double v)
{
    if (v == v)
        put(t, "<td data-v=\"%.9g\">%.4g</td>", v, v);
    else
        put(t, "<td data-v=\"\">–</td>");
}

/* The entity at s (at most n bytes) that gi_text_md writes; its length, or 0. */
static size_t md_entity(const char *s, size_t n)
{
    static const char *const known[] = {"&lt;", "&gt;", "&amp;", "&quot;"};
    for (size_t k = 0; k < sizeof known / sizeof known[0]; k++) {
        size_t len = strlen(known[k]);
        if (len <= n && !strncmp(s, known[k], len))
            return len;
    }
    return 0;
}

/* Inline markdown as gi_text_md and gi_text_md_code write it (text.h):
 * `code` spans, backslash escapes and the entities of HTML's specials
 * (kept as they are: the page shows the character), the rest escaped. In a
 * code span only "\|" is an escape (a table's, as GitHub reads it). */
static void md_inline(text *t, const char *s, size_t n)
{
    int code = 0;
    char buf[2];
    buf[1] = '\0';
    for (size_t i = 0; i < n; i++) {
        size_t ent;
        if (s[i] == '`') {
            put(t, code ? "</code>" : "<code>");
            code = !code;
            continue;
        }
        if (s[i] == '\\' && i + 1 < n &&
            (s[i + 1] == '|' || (!code && ispunct((unsigned char)s[i + 1]))))
            i++;
        else if (!code && (ent = md_entity(s + i, n - i))) {
            put(t, "%.*s", (int)ent, s + i);
            i += ent - 1;
            continue;
        }
        buf[0] = s[i];
        html_escape(t, buf);
    }
    if (code)
        put(t, "</code>");
}

/* The next cell separator of a table row in [c, stop): a '|' not escaped. */
static const char *md_cell_end(const char *c, const char *stop)
{
    for (; c < stop; c++) {
        if (*c == '\\' && c + 1 < stop)
            c++;
        else if (*c == '|')
            return c;
    }
    return stop;
}

/* The speed-against-accuracy text of tradeoff.c (markdown: headings,
 * paragraphs and pipe tables) as HTML, tables sortable and scrolling in
 * their box. */
static void md_to_html(text *t, const char *md)
{
    int in_table = 0, in_par = 0, row = 0;
    while (*md) {
        const char *end = strchr(md, '\n');
        size_t n = end ? (size_t)(end - md) : strlen(md);
        const char *next = end ? end + 1 : md + n;
        while (n && (md[n - 1] == ' ' || md[n - 1] == '\r'))
            n--;
        int is_row = n && md[0] == '|';
        if (!is_row && in_table) {
            put(t, "</tbody></table></div>\n");
            in_table = 0;
        }
        if ((is_row || !n || md[0] == '#') && in_par) {
            put(t, "</p>\n");
            in_par = 0;
        }
        if (is_row) {
            if (!in_table) {
                put(t, "<div class=\"scroll\"><table class=\"sortable\"><thead>");
                in_table = 1;
                row = 0;
            }
            if (row == 1 && strspn(md, "|-: ") == n) { /* the alignment row */
                row++;
                md = next;
                continue;
            }
            put(t, "<tr>");
            const char *c = md + 1, *stop = md + n;
            while (c < stop) {
                const char *bar = md_cell_end(c, stop);
                const char *a = c, *b = bar;
                while (a < b && *a == ' ')
                    a++;
                while (b > a && b[-1] == ' ')
                    b--;
                put(t, row == 0 ? "<th class=l>" : "<td%s>",
                    row && b > a && (*a < '0' || *a > '9') ? " class=l" : "");
                md_inline(t, a, (size_t)(b - a));
                put(t, row == 0 ? "</th>" : "</td>");
                c = bar + 1;
            }
            put(t, "</tr>");
            if (row == 0)
                put(t, "</thead><tbody>");
            put(t, "\n");
            row++;
        } else if (n && md[0] == '#') {
            size_t h = strspn(md, "#");
            const char *a = md + h;
            while (*a == ' ')
                a++;
            int level = h < 3 ? 3 : h > 5 ? 5 : (int)h; /* below the page's h2 sections */
            put(t, "<h%d>", level);
            md_inline(t, a, (size_t)(md + n - a));
            put(t, "</h%d>\n", level);
        } else if (n) {
            put(t, in_par ? "\n" : "<p>");
            in_par = 1;
            md_inline(t, md, n);
        }
        md = next;
    }
    if (in_table)
        put(t, "</tbody></table></div>\n");
    if (in_par)
        put(t, "</p>\n");
}

static void params_cell(text *t, json_object *o)
{
    const char *given = report_raw(o, "params"), *full = report_str(o, "params");
    put(t, "<td class=\"params\" data-v=\"");
    html_escape(t, given);
    put(t, "\"><details><summary title=\"");
    html_escape(t, full);
    put(t, "\"><code>");
    html_escape(t, *given ? given : "(defaults)");
    put(t, "</code></summary><code>");
    html_escape(t, full);
    put(t, "</code></details></td>");
}

/* The page's head (with the style), title, header list, navigation and note. */
static void html_header(text *t, json_object *meta)
{
    put(t, "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
           "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\"><title>");
    html_escape(t, report_str(meta, "title"));
    put(t, "</title>\n<style>\n%s</style>\n</head><body>\n<h1>", asset("viewer.css"));
    html_escape(t, report_str(meta, "title"));
    put(t, "</h1>\n<dl class=\"meta\">");
    const char *keys[] = {"command", "renderer", "reference", "machine", "date"};
    const char *names[] = {"command", "GL renderer", "reference", "machine", "date"};
    for (int k = 0; k < 5; k++) {
        put(t, "<dt>%s</dt><dd>%s", names[k], k == 0 ? "<code>" : "");
        html_escape(t, report_str(meta, keys[k]));
        put(t, "%s</dd>", k == 0 ? "</code>" : "");
    }
    put(t,
        "</dl>\n<nav><a href=\"#images\">images</a><a href=\"#runs\">runs</a><a "
        "href=\"#stages\">stage "
        "timings</a><a href=\"#tradeoff\">speed against accuracy</a>%s<a "
        "href=\"#charts\">charts</a></nav>\n",
        json_object_object_get_ex(meta, "animation_markdown", NULL) &&
                *report_str(meta, "animation_markdown")
            ? "<a href=\"#animation\">animation</a>"
            : "");
    put(t, "<p>Errors are against the full-GI reference (\"full\") and against the reference "
           "limited to the "
           "method's own bounce count (\"matched\"). Times are medians over the timed frames; on a "
           "software "
           "renderer only ratios within one study mean anything.</p>\n");
}

/* the image viewers, one per reference set */
static void html_images(text *t, json_object *sets)
{
    put(t, "<h2 id=\"images\">Images</h2>\n");
    for (size_t i = 0; i < json_object_array_length(sets); i++) {
        json_object *set = json_object_array_get_idx(sets, i);
        put(t, "<h3>");
        html_escape(t, report_raw(set, "name"));
        put(t, "</h3>\n<div class=\"gib-viewer\" data-set=\"%zu\"></div>\n", i);
    }
    put(t, "<noscript><p>The image viewer needs JavaScript; the images are in runs/ and "
           "references/.</p></noscript>\n");
}

/* A table row's start: the run, its method and its parameters. */
static void run_cells(text *t, json_object *o)
{
    put(t, "<tr><td class=l><code>");
    html_escape(t, report_raw(o, "run"));
    put(t, "</code></td><td class=l>");
    html_escape(t, report_raw(o, "method"));
    put(t, "</td>");
    params_cell(t, o);
}

/* every run */
static void html_runs(text *t, json_object *runs)
{
    put(t,
        "<h2 id=\"runs\">Runs</h2>\n<p>Click a column header to sort. Parameters: those the study "
        "set; click "
        "for the full string (defaults included).</p>\n<div class=\"scroll\"><table "
        "class=\"sortable\"><thead><tr>"
        "<th class=l>run</th><th class=l>method</th><th class=l>params</th><th "
        "class=l>status</th><th>frames</th>"
        "<th>frame ms</th><th>prepare ms</th><th>relMSE full</th><th>relMSE "
        "matched</th><th>HDR-FLIP "
        "full</th><th>FLIP full</th>"
        "<th>SSIM full</th><th>mean lum. diff %%</th><th>speed-up vs PT</th><th>speed-up vs PT, "
        "matched</th>"
        "<th>leaked energy full</th><th>peak RSS MiB</th><th>data MiB</th></tr></thead><tbody>\n");
    size_t count = json_object_array_length(runs);
    for (size_t i = 0; i < count; i++) {
        json_object *o = json_object_array_get_idx(runs, i);
        run_cells(t, o);
        put(t, "<td class=\"l reason\">");
        html_escape(t, report_raw(o, "status"));
        if (strcmp(report_raw(o, "status"), "ok")) {
            put(t, ": ");
            html_escape(t, report_raw(o, "reason"));
        }
        put(t, "</td>");
        html_num(t, report_num(o, "frames", NULL, NULL));
        html_num(t, report_num(o, "frame_ms", "median", NULL));
        html_num(t, report_num(o, "prepare_ms", NULL, NULL));
        html_num(t, report_num(o, "metrics", "full", "relmse"));
        html_num(t, report_num(o, "metrics", "matched", "relmse"));
        html_num(t, report_num(o, "metrics", "full", "hdr_flip"));
        html_num(t, report_num(o, "metrics", "full", "flip"));
        html_num(t, report_num(o, "metrics", "full", "ssim"));
        html_num(t, report_num(o, "metrics", "full", "mean_lum_diff_pct"));
        html_num(t, report_num(o, "speedup_vs_pt", NULL, NULL));
        html_num(t, report_num(o, "speedup_vs_pt_matched", NULL, NULL));
        html_num(t, report_num(o, "metrics", "full", "leaked_energy"));
        html_num(t, report_num(o, "peak_rss_mib", NULL, NULL));
        html_num(t, report_num(o, "stats", "data_bytes", NULL) / (1024.0 * 1024.0));
        put(t, "</tr>\n");
    }
    put(t, "</tbody></table></div>\n");
}

/* stage timings */
static void html_stages(text *t, json_object *runs)
{
    const char *stages[32];
    int ns = report_stage_names(runs, stages, 32);
    put(t, "<h2 id=\"stages\">Stage timings</h2>\n");
    if (ns == 0) {
        put(t, "<p>No run reported stage timings.</p>\n");
        return;
    }
    put(t, "<p>Milliseconds, median (min – max) over the timed frames.</p>\n<div "
           "class=\"scroll\"><table "
           "class=\"sortable\"><thead><tr><th class=l>run</th><th class=l>method</th><th "
           "class=l>params</th>");
    for (int k = 0; k < ns; k++) {
        put(t, "<th>");
        html_escape(t, stages[k]);
        put(t, "</th>");
    }
    put(t, "<th>frame</th></tr></thead><tbody>\n");
    size_t count = json_object_array_length(runs);
    for (size_t i = 0; i < count; i++) {
        json_object *o = json_object_array_get_idx(runs, i);
        if (strcmp(report_raw(o, "status"), "ok"))
            continue;
        run_cells(t, o);
        for (int k = 0; k <= ns; k++) {
            const char *k1 = k < ns ? "stages" : "frame_ms", *k2 = k < ns ? stages[k] : NULL;
            double med =
                k < ns ? report_num(o, k1, k2, "median") : report_num(o, k1, "median", NULL);
            double mn = k < ns ? report_num(o, k1, k2, "min") : report_num(o, k1, "min", NULL);
            double mx = k < ns ? report_num(o, k1, k2, "max") : report_num(o, k1, "max", NULL);
            if (med == med)
                put(t, "<td data-v=\"%.9g\">%.4g <small>(%.4g – %.4g)</small></td>", med, med, mn,
                    mx);
            else
                put(t, "<td data-v=\"\">–</td>");
        }
        put(t, "</tr>\n");
    }
    put(t, "</tbody></table></div>\n");
}

/* speed against accuracy (tradeoff.c's tables), and the animated runs' text */
static void html_tradeoff(text *t, json_object *meta)
{
    put(t, "<h2 id=\"tradeoff\">Speed against accuracy</h2>\n");
    json_object *extra;
    if (json_object_object_get_ex(meta, "markdown", &extra) && *json_object_get_string(extra))
        md_to_html(t, json_object_get_string(extra));
    else
        put(t, "<p>Not computed for this report.</p>\n");

    if (json_object_object_get_ex(meta, "animation_markdown", &extra) &&
        *json_object_get_string(extra)) {
        put(t, "<h2 id=\"animation\">Animated runs, frame by frame</h2>\n");
        md_to_html(t, json_object_get_string(extra));
    }
}

/* every chart of meta "charts" that exists */
static void html_charts(text *t, const char *dir, json_object *meta)
{
    put(t, "<h2 id=\"charts\">Charts</h2>\n");
    json_object *charts;
    int nc = 0;
    if (json_object_object_get_ex(meta, "charts", &charts))
        for (size_t i = 0; i < json_object_array_length(charts); i++) {
            const char *c = json_object_get_string(json_object_array_get_idx(charts, i));
            if (!report_exists_in(dir, c))
                continue;
            put(t, "<figure><img class=\"chart\" alt=\"");
            html_escape(t, c);
            put(t, "\" src=\"");
            html_escape(t, c);
            put(t, "\"><figcaption>");
            html_escape(t, c);
            put(t, "</figcaption></figure>\n");
            nc++;
        }
    if (!nc)
        put(t, "<p>No charts.</p>\n");
}

void report_write_html(text *t, const char *dir, json_object *runs, json_object *meta)
{
    html_header(t, meta);
    json_object *sets = report_viewer_sets(dir, runs, meta);
    html_images(t, sets);
    html_runs(t, runs);
    html_stages(t, runs);
    html_tradeoff(t, meta);
    html_charts(t, dir, meta);

    /* the viewer's data; json-c escapes '/', so no "</script>" can occur, */
    put(t, "<script type=\"application/json\" id=\"gib-data\">");
    json_object *data = json_object_new_object();
    json_object_object_add(data, "sets", sets);
    /* and '<' as \u003c (the same string to JSON.parse): a name holding
     * "<!--<script>" would otherwise keep the element open past its end */
    for (const char *j = json_object_to_json_string_ext(data, JSON_C_TO_STRING_PLAIN); *j; j++)
        if (*j == '<')
            put(t, "\\u003c");
        else
            put(t, "%c", *j);
    json_object_put(data);
    put(t, "</script>\n<script>\n%s</script>\n</body></html>\n", asset("viewer.js"));
}
