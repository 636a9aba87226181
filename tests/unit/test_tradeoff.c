/* Speed against accuracy (harness/report/tradeoff.h): the path tracer's time at an
 * error, repeats pooled into a spread, the time charged to a run with an
 * error floor, Pareto fronts as staircases, and the equal-error and
 * equal-time tables, on synthetic runs whose answers are known. */
#include "check.h"
#include "tradeoff.h"

#include <stdlib.h>
#include <string.h>

/* A run record as the runner makes it, with a convergence curve. */
static json_object *record(const char *method, const char *params, const double *t, const double *e,
                           const double *em, int n, double prep_ms)
{
    json_object *o = json_object_new_object();
    json_object_object_add(o, "status", json_object_new_string("ok"));
    json_object_object_add(o, "method", json_object_new_string(method));
    json_object_object_add(o, "params", json_object_new_string(params));
    json_object_object_add(o, "prepare_ms", json_object_new_double(prep_ms));
    json_object *c = json_object_new_array();
    for (int k = 0; k < n; k++) {
        json_object *p = json_object_new_object(), *f = json_object_new_object(),
                    *m = json_object_new_object();
        json_object_object_add(p, "frame", json_object_new_int(1 << k));
        json_object_object_add(p, "time_ms", json_object_new_double(t[k] * 1000.0));
        json_object_object_add(f, "relmse", json_object_new_double(e[k]));
        json_object_object_add(m, "relmse", json_object_new_double(em[k]));
        json_object_object_add(p, "full", f);
        json_object_object_add(p, "matched", m);
        json_object_array_add(c, p);
    }
    json_object_object_add(o, "curve", c);
    return o;
}

static double field(json_object *o, const char *key)
{
    json_object *v;
    return json_object_object_get_ex(o, key, &v) ? json_object_get_double(v) : NAN;
}

/* The chart stand-in keeps what it was asked to draw. */
static struct {
    int calls;
    char last_path[512];
    uint32_t front_count[2];
    double front_x[2][16], front_y[2][16];
    uint32_t thin, reference, pt_not_reference, pt_colour_twice;
} seen;

static gi_result fake_chart(const char *path, const gi_chart_desc *desc, const gi_chart_series *s,
                            uint32_t n, gi_error *err)
{
    (void)desc, (void)err;
    seen.calls++;
    snprintf(seen.last_path, sizeof seen.last_path, "%s", path);
    /* the path tracer's curves: in the reference looks (never a method's
     * colour, issue 33), each bounce limit a look of its own */
    int used[64] = {0};
    for (uint32_t i = 0; i < n; i++)
        if (s[i].label && !strncmp(s[i].label, "path tracer", 11)) {
            seen.pt_not_reference += s[i].style != GI_CHART_REFERENCE;
            if (s[i].color >= 0 && s[i].color < 64)
                seen.pt_colour_twice += used[s[i].color]++ > 0;
        }
    if (seen.calls > 1)
        return GI_OK; /* the matched chart: counted only */
    for (uint32_t i = 0; i < n; i++) {
        if (s[i].style == GI_CHART_THIN)
            seen.thin++;
        if (s[i].style == GI_CHART_REFERENCE)
            seen.reference++;
        int m = s[i].label && !strncmp(s[i].label, "fast", 4)   ? 0
                : s[i].label && !strncmp(s[i].label, "prog", 4) ? 1
                                                                : -1;
        if (m >= 0 && s[i].style == GI_CHART_LINE_MARKERS) {
            seen.front_count[m] = s[i].count;
            for (uint32_t k = 0; k < s[i].count && k < 16; k++) {
                seen.front_x[m][k] = s[i].x[k];
                seen.front_y[m][k] = s[i].y[k];
            }
        }
    }
    return GI_OK;
}

static void test_pt_time(void)
{
    /* relMSE = 1 / time: log-log interpolation is exact on it */
    tradeoff_pt_curve c = {.bounces = 65, .n = 3, .t = {1, 4, 16}, .e = {1, 0.25, 0.0625}};
    int ex = -1;
    CHECK_NEAR(tradeoff_pt_time_at(&c, 0.5, &ex), 2.0, 1e-12);
    CHECK(ex == 0);
    CHECK_NEAR(tradeoff_pt_time_at(&c, 2.0, &ex), 0.5,
               1e-12); /* beyond the first point: slope -1 */
    CHECK(ex == 1);
    CHECK_NEAR(tradeoff_pt_time_at(&c, 0.01, &ex), 100.0, 1e-9);
    CHECK(ex == 1);
    CHECK(isnan(tradeoff_pt_time_at(&c, 0.0, &ex)));
    tradeoff_pt_curve empty = {.bounces = 65, .n = 0, .t = {0}, .e = {0}};
    CHECK(isnan(tradeoff_pt_time_at(&empty, 0.5, &ex)));
}

static void test_report(void)
{
    /* "fast": an error floor (every frame the same error), two repeats;
     * a second setting of it that is slower and worse (dominated). "prog":
     * progressive, its error halving per doubling of time, 1 bounce. */
    double ta[3] = {0.01, 0.02, 0.04}, ea1[3] = {0.39, 0.39, 0.39}, ea2[3] = {0.41, 0.41, 0.41};
    double tb[3] = {0.02, 0.04, 0.08}, eb[3] = {0.5, 0.5, 0.5};
    double tp[3] = {1, 2, 4}, ep[3] = {0.2, 0.1, 0.05}, epm[3] = {0.1, 0.05, 0.025};
    tradeoff_run runs[4] = {
        {record("fast", "A", ta, ea1, ea1, 3, 100), 65, 1},
        {record("fast", "A", ta, ea2, ea2, 3, 300), 65, 1},
        {record("fast", "B", tb, eb, eb, 3, 0), 65, 2},
        {record("prog", "P", tp, ep, epm, 3, 0), 1, 3},
    };
    tradeoff_pt_curve full = {.bounces = 65, .n = 3, .t = {1, 4, 16}, .e = {1, 0.25, 0.0625}};
    tradeoff_pt_curve matched = {.bounces = 1, .n = 2, .t = {0.5, 2}, .e = {0.1, 0.025}};
    /* memory: "fast" A's repeats peaked at 100 and 300 MiB and keep 1 MiB of data */
    for (int r = 0; r < 2; r++) {
        json_object *st = json_object_new_object();
        json_object_object_add(st, "data_bytes", json_object_new_double(1048576.0));
        json_object_object_add(runs[r].record, "stats", st);
        json_object_object_add(runs[r].record, "peak_rss_mib",
                               json_object_new_double(r ? 300.0 : 100.0));
    }
    gi_text md = {0};
    json_object *charts = json_object_new_array();
    tradeoff_report("/nonexistent", "box", &full, &matched, 1, runs, 4, fake_chart, charts, &md,
                    NULL);
    CHECK(md.s != NULL);
    const char *s = md.s ? md.s : "";

    /* the floor is reached at frame 1: charged 0.01 s, not 0.04 s */
    CHECK_NEAR(field(runs[0].record, "time_to_final_error_s"), 0.01, 1e-12);
    CHECK_NEAR(field(runs[0].record, "speedup_vs_pt"), (1 / 0.39) / 0.01, 1e-6);
    /* the progressive run needs all its frames */
    CHECK_NEAR(field(runs[3].record, "time_to_final_error_s"), 4.0, 1e-12);
    /* matched: 0.025 on the 1-bounce curve is its last point, 2 s */
    CHECK_NEAR(field(runs[3].record, "speedup_vs_pt_matched"), 2.0 / 4.0, 1e-9);

    /* equal error: the front of "fast" is setting A's first frame with its
     * spread; B is dominated; "prog" has three points */
    CHECK_MSG(strstr(s, "| fast | `A` | 1 | 0.01 | 0.4 [0.39–0.41] |") != NULL, "%s", s);
    CHECK_MSG(strstr(s, "`B`") == NULL, "dominated setting listed:\n%s", s);
    CHECK_MSG(strstr(s, "| prog | `P` | 4 | 4 | 0.05 |") != NULL, "%s", s);
    /* precomputation: the median of 0.1 s and 0.3 s, amortised over 100 images */
    CHECK_MSG(strstr(s, "| 0.2 | 0.21 | 0.012 | 0.01002 | 200 | 1 |\n") != NULL, "%s", s);
    /* a method that measured no memory: dashes, not zeros */
    CHECK_MSG(strstr(s, "| 0 | 4 | 4 | 4 | – | – |\n") != NULL, "%s", s);
    /* equal time: the costs of the settings behind each row */
    CHECK_MSG(strstr(s, "| precompute (s) | peak RSS (MiB) | data (MiB) |") != NULL, "%s", s);
    CHECK_MSG(strstr(s, "| fast | 0.4 (×0.4) | 0.4 (×1.6) | 0.4 (×6.4) | 0.2 | 200 | 1 |\n") !=
                  NULL,
              "%s", s);

    /* equal time, at the path tracer's 1 s (error 1): fast 0.4, prog 0.2;
     * prog's matched row uses its own curve (0.5 s: no setting that fast) */
    CHECK_MSG(strstr(s, "| fast | 0.4 (×0.4) |") != NULL, "%s", s);
    CHECK_MSG(strstr(s, "| prog | 0.2 (×0.2) |") != NULL, "%s", s);
    CHECK_MSG(strstr(s, "| prog (matched) | – | 0.05 (×2) |") != NULL, "%s", s);
    CHECK_MSG(strstr(s, "| fast (matched)") == NULL, "a full-GI method got a matched row:\n%s", s);

    /* charts: full and matched; the fronts are staircases */
    CHECK(seen.calls == 2);
    CHECK(strstr(seen.last_path, "chart_box_error_vs_time_matched.png") != NULL);
    CHECK(seen.thin == 3);      /* every setting's own curve */
    CHECK(seen.reference == 1); /* the full-GI path tracer */
    CHECK_MSG(seen.pt_not_reference == 0, "%u path tracer curves drawn as a method's",
              seen.pt_not_reference);
    CHECK(seen.pt_colour_twice == 0);
    CHECK(seen.front_count[0] == 1);
    CHECK(seen.front_count[1] == 5);
    double want_x[5] = {1, 2, 2, 4, 4}, want_y[5] = {0.2, 0.2, 0.1, 0.1, 0.05};
    for (int k = 0; k < 5; k++) {
        CHECK_NEAR(seen.front_x[1][k], want_x[k], 1e-12);
        CHECK_NEAR(seen.front_y[1][k], want_y[k], 1e-12);
    }
    CHECK(json_object_array_length(charts) == 2);

    free(md.s);
    json_object_put(charts);
    for (int i = 0; i < 4; i++)
        json_object_put(runs[i].record);
}

/* Runs of one setting timed under two GL renderers (two cluster nodes) are
 * not repeats of each other: the tables list the method once per renderer,
 * each with its own time, and no spread pools the two. With one renderer
 * the same runs are repeats (the median time, the spread of relMSE). */
static void test_renderers(void)
{
    double t1[2] = {0.01, 0.02}, t2[2] = {0.5, 1.0}, e1[2] = {0.3, 0.3}, e2[2] = {0.31, 0.31};
    for (int mixed = 0; mixed < 2; mixed++) {
        tradeoff_run runs[2] = {
            {record("fast", "A", t1, e1, e1, 2, 0), 65, 7},
            {record("fast", "A", t2, e2, e2, 2, 0), 65, 7},
        };
        json_object_object_add(runs[0].record, "renderer", json_object_new_string("NVIDIA H100"));
        json_object_object_add(runs[1].record, "renderer",
                               json_object_new_string(mixed ? "llvmpipe" : "NVIDIA H100"));
        tradeoff_pt_curve full = {.bounces = 65, .n = 3, .t = {1, 4, 16}, .e = {1, 0.25, 0.0625}};
        gi_text md = {0};
        json_object *charts = json_object_new_array();
        tradeoff_report("/nonexistent", "box", &full, NULL, 0, runs, 2, NULL, charts, &md, NULL);
        const char *s = md.s ? md.s : "";
        if (mixed) {
            CHECK_MSG(strstr(s, "| fast [NVIDIA H100] | `A` | 1 | 0.01 | 0.3 |") != NULL, "%s", s);
            CHECK_MSG(strstr(s, "| fast [llvmpipe] | `A` | 1 | 0.5 | 0.31 |") != NULL, "%s", s);
            CHECK_MSG(strstr(s, "[0.3–0.31]") == NULL, "two renderers pooled into one spread:\n%s",
                      s);
        } else {
            CHECK_MSG(strstr(s, "| fast | `A` | 1 | 0.255 | 0.305 [0.3–0.31] |") != NULL, "%s", s);
            CHECK_MSG(strstr(s, "[NVIDIA") == NULL, "%s", s);
        }
        free(md.s);
        json_object_put(charts);
        json_object_put(runs[0].record);
        json_object_put(runs[1].record);
    }
}

/* Issue 34: the speed-up carries the spread of the path tracer's repeated
 * curve points (here each point's fastest and slowest timing half and twice
 * its median) and of the method's repeats; a mixed-clock report says so. */
static void test_speedup_spread(void)
{
    double t1[1] = {0.1}, t2[1] = {0.2}, e[1] = {0.25};
    tradeoff_run runs[2] = {
        {record("m", "A", t1, e, e, 1, 0), 65, 7},
        {record("m", "A", t2, e, e, 1, 0), 65, 7},
    };
    json_object_object_add(runs[0].record, "invocation", json_object_new_string("inv-A"));
    json_object_object_add(runs[1].record, "invocation", json_object_new_string("inv-B"));
    tradeoff_pt_curve full = {.bounces = 65,
                              .n = 3,
                              .t = {1, 4, 16},
                              .e = {1, 0.25, 0.0625},
                              .t_lo = {0.5, 2, 8},
                              .t_hi = {2, 8, 32},
                              .samples = {3, 3, 3},
                              .invocation = "inv-A"};
    gi_text md = {0};
    json_object *charts = json_object_new_array();
    tradeoff_clock_note clocks = {1};
    tradeoff_report("/nonexistent", "box", &full, NULL, 0, runs, 2, NULL, charts, &md, &clocks);
    const char *s = md.s ? md.s : "";
    /* per run: the path tracer needs 4 s [2-8] for 0.25; run 0 took 0.1 s */
    CHECK_NEAR(field(runs[0].record, "speedup_vs_pt"), 40.0, 1e-9);
    CHECK_NEAR(field(runs[0].record, "speedup_vs_pt_min"), 20.0, 1e-9);
    CHECK_NEAR(field(runs[0].record, "speedup_vs_pt_max"), 80.0, 1e-9);
    /* the table: median time 0.15 s, so 26.7; low end 2 / 0.2, high end 8 / 0.1 */
    CHECK_MSG(strstr(s, "| 26.7 [10–80] |") != NULL, "no speed-up spread in:\n%s", s);
    CHECK_MSG(strstr(s, "4 s [2–8] → 0.25") != NULL, "no curve spread in:\n%s", s);
    CHECK_MSG(strstr(s, "**Clocks are mixed**") != NULL &&
                  strstr(s, "inv-A (the path tracer's curve, 1 runs); inv-B (1 runs)") != NULL,
              "no mixed-clock note in:\n%s", s);
    free(md.s);
    json_object_put(charts);
    json_object_put(runs[0].record);
    json_object_put(runs[1].record);
}

int main(void)
{
    test_pt_time();
    test_report();
    test_renderers();
    test_speedup_spread();
    return gi_test_finish();
}
