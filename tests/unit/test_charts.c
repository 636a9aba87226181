/* Charts (harness/report/charts.h): a log-log chart of three series is written as a
 * PNG of the requested size, read back and checked for what a reader needs:
 * each series in its own palette colour, a power law drawn as a straight
 * line (so both axes really are logarithmic), the reference curve dashed
 * and the others solid. Also: y ranges that do not magnify noise, error
 * bars drawn and counted in the ranges, ticks at given (swept) values,
 * points dropped on log axes, empty charts,
 * bad arguments and unwritable paths as errors, no temporary files left,
 * the caller's GL context current again afterwards, and the time a chart
 * takes. Registered with the label "charts", not "unit": it runs in the
 * release ctest only (VTK is not built for the ASan preset's checks). The
 * PNGs are removed on success; GI_KEEP_CHARTS=1 keeps them for a look. */
#define _POSIX_C_SOURCE 200809L /* mkdtemp, clock_gettime */
#include <dirent.h>
#include <epoxy/egl.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "charts.h"
#include "check.h"
#include "gi/gpu.h"
#include "gi/image.h"

static char dir[512];

static void make_dir(void)
{
    snprintf(dir, sizeof dir, "%s/tests/tmp_charts_XXXXXX", GI_BINARY_DIR);
    if (!mkdtemp(dir)) {
        perror("mkdtemp");
        exit(1);
    }
}

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Names in `dir` that look like our temporary files (".name.tmp-..."). */
static int count_temporaries(void)
{
    DIR *d = opendir(dir);
    int n = 0;
    struct dirent *e;
    while (d && (e = readdir(d)) != NULL)
        if (strstr(e->d_name, ".tmp-"))
            n++;
    if (d)
        closedir(d);
    return n;
}

/* Pixel (x, y) of an 8-bit image read back as [0, 1], scaled to 0..255. */
static void px(const gi_image *img, uint32_t x, uint32_t y, int rgb[3])
{
    const float *p = img->rgba + ((size_t)y * img->width + x) * 4;
    for (int c = 0; c < 3; c++)
        rgb[c] = (int)(p[c] * 255.0f + 0.5f);
}

static int near_colour(const int rgb[3], const int want[3], int tol)
{
    for (int c = 0; c < 3; c++)
        if (abs(rgb[c] - want[c]) > tol)
            return 0;
    return 1;
}

/* Columns in which colour `want` occurs, and the median row of its pixels
 * in each column (-1 where absent). Returns the number of such columns. */
static uint32_t colour_columns(const gi_image *img, const int want[3], int *median_row,
                               uint32_t *first, uint32_t *last)
{
    uint32_t cols = 0;
    int *rows = malloc(sizeof(int) * img->height);
    *first = img->width;
    *last = 0;
    for (uint32_t x = 0; x < img->width; x++) {
        int n = 0, rgb[3];
        for (uint32_t y = 0; y < img->height; y++) {
            px(img, x, y, rgb);
            if (near_colour(rgb, want, 24))
                rows[n++] = (int)y;
        }
        median_row[x] = n ? rows[n / 2] : -1;
        if (n) {
            cols++;
            if (x < *first)
                *first = x;
            *last = x;
        }
    }
    free(rows);
    return cols;
}

/* Least-squares line through (x, median_row[x]) over [a, b]; the largest
 * distance of a point from it, in pixels (rows). */
static double line_residual(const int *median_row, uint32_t a, uint32_t b, int *used)
{
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    int n = 0;
    for (uint32_t x = a; x <= b; x++)
        if (median_row[x] >= 0) {
            sx += x, sy += median_row[x], sxx += (double)x * x, sxy += (double)x * median_row[x];
            n++;
        }
    *used = n;
    if (n < 2)
        return 1e9;
    double slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
    double icpt = (sy - slope * sx) / n;
    double worst = 0;
    for (uint32_t x = a; x <= b; x++)
        if (median_row[x] >= 0) {
            double r = fabs(median_row[x] - (slope * x + icpt));
            if (r > worst)
                worst = r;
        }
    return worst;
}

/* The chart the report draws: error against time on log-log axes, two
 * methods and the path tracer's convergence as a dashed reference. */
static void test_log_log_chart(void)
{
    enum { N = 12 };
    double t[N], e_a[N], e_b[N], t_pt[N], e_pt[N];
    for (int i = 0; i < N; i++) {
        t[i] = pow(10.0, i * 3.0 / (N - 1));     /* 1 .. 1000 ms */
        e_a[i] = 0.5 * pow(t[i], -0.5);          /* power law: straight on log-log */
        e_b[i] = 0.02 + 0.1 * exp(-t[i] / 50.0); /* plateaus: a biased method */
        t_pt[i] = t[i];
        e_pt[i] = 2.0 * pow(t[i], -0.5); /* Monte Carlo: 1/sqrt(time) */
    }
    gi_chart_series s[3] = {
        {"method A (unbiased)", t, e_a, N, GI_CHART_LINE_MARKERS, 0, NULL, NULL, NULL, NULL},
        {"method B (biased)", t, e_b, N, GI_CHART_MARKERS, 0, NULL, NULL, NULL, NULL},
        {"path tracer", t_pt, e_pt, N, GI_CHART_DASHED, 0, NULL, NULL, NULL, NULL},
    };
    gi_chart_desc d = {
        "Cornell box: RMSE against time", "time [ms]", "RMSE", 1, 1, 1000, 640, NULL, 0};
    char path[600];
    snprintf(path, sizeof path, "%s/error_time.png", dir);
    gi_error err = {{0}};
    double t0 = now();
    gi_result r = gi_chart_write_png(path, &d, s, 3, &err);
    double secs = now() - t0;
    CHECK_MSG(r == GI_OK, "%s", err.text);
    printf("log-log chart %ux%u, the process's first: %.3f s\n", d.width, d.height, secs);
    /* The brief: well under 3 s on llvmpipe; 10 s leaves room for a loaded machine. */
    CHECK_MSG(secs < 10.0, "%.2f s", secs);
    CHECK(count_temporaries() == 0);

    gi_image *img = gi_image_read(path, &err);
    CHECK_MSG(img != NULL, "%s", err.text);
    if (!img)
        return;
    CHECK(img->width == 1000 && img->height == 640);

    /* Not blank: luminance varies and a fair share of pixels is not white. */
    double sum = 0, sum2 = 0;
    size_t not_white = 0, count = (size_t)img->width * img->height;
    for (size_t i = 0; i < count; i++) {
        double l = (img->rgba[i * 4] + img->rgba[i * 4 + 1] + img->rgba[i * 4 + 2]) / 3.0;
        sum += l, sum2 += l * l;
        not_white += l < 0.9;
    }
    double var = sum2 / (double)count - (sum / (double)count) * (sum / (double)count);
    CHECK_MSG(var > 1e-3, "variance %g", var);
    CHECK_MSG(not_white > count / 100 && not_white < count / 2, "%zu of %zu not white", not_white,
              count);

    /* Palette colours of series 0, 1, 2 (Okabe-Ito blue, vermillion, bluish green). */
    static const int blue[3] = {0, 114, 178}, vermillion[3] = {213, 94, 0},
                     green[3] = {0, 158, 115};
    int *rows = malloc(sizeof(int) * img->width);
    uint32_t a0, a1, b0, b1, c0, c1;
    uint32_t cols_a = colour_columns(img, blue, rows, &a0, &a1);
    /* Series A spans most of the width (1 .. 1000 on the x axis). */
    CHECK_MSG(cols_a > img->width / 2 && a1 - a0 > img->width * 6 / 10,
              "blue in %u columns, %u..%u", cols_a, a0, a1);
    /* A power law on log-log axes is a straight line. Judge the middle of
     * the span (the legend's sample sits at the right); on linear axes the
     * same data bends by hundreds of pixels. */
    int used = 0;
    uint32_t m0 = a0 + (a1 - a0) / 5, m1 = a0 + (a1 - a0) * 3 / 5;
    double res = line_residual(rows, m0, m1, &used);
    CHECK_MSG(used > (int)(m1 - m0) / 2 && res < 4.0,
              "series A is not straight on log-log axes: %.1f px off a line over %d columns", res,
              used);

    /* Series B is drawn as markers only: its colour shows up in spots. */
    uint32_t cols_b = colour_columns(img, vermillion, rows, &b0, &b1);
    CHECK_MSG(cols_b > 20 && cols_b < (b1 - b0) * 7 / 10, "vermillion in %u columns over %u..%u",
              cols_b, b0, b1);

    /* The reference is dashed: gaps along it, where the solid series A has
     * its colour in (nearly) every column of its span. */
    uint32_t cols_c = colour_columns(img, green, rows, &c0, &c1);
    double cover_c = 0, cover_a = 0;
    int span_c = 0, span_a = 0;
    int *rows_a = malloc(sizeof(int) * img->width);
    colour_columns(img, blue, rows_a, &a0, &a1);
    for (uint32_t x = c0 + (c1 - c0) / 5; x <= c0 + (c1 - c0) * 3 / 5; x++)
        cover_c += rows[x] >= 0, span_c++;
    for (uint32_t x = m0; x <= m1; x++)
        cover_a += rows_a[x] >= 0, span_a++;
    cover_c /= span_c > 0 ? span_c : 1;
    cover_a /= span_a > 0 ? span_a : 1;
    CHECK_MSG(cols_c > 50, "green in %u columns", cols_c);
    CHECK_MSG(cover_a > 0.97, "solid series covers %.2f of its columns", cover_a);
    CHECK_MSG(cover_c < 0.9 && cover_c > 0.3, "dashed series covers %.2f of its columns", cover_c);
    free(rows_a);
    free(rows);
    gi_image_free(img);
}

static void test_points_kept(void)
{
    double x[] = {1, 0, -1, NAN, 2, INFINITY, 3};
    double y[] = {1, 1, 1, 1, -2, 1, 0.5};
    gi_chart_series s = {"s", x, y, 7, GI_CHART_LINE_MARKERS, 0, NULL, NULL, NULL, NULL};
    gi_chart_desc lin = {0}, logx = {0}, loglog = {0};
    logx.log_x = 1;
    loglog.log_x = loglog.log_y = 1;
    CHECK(gi_chart_points_kept(&lin, &s) == 5); /* NaN and Inf dropped */
    CHECK(gi_chart_points_kept(NULL, &s) == 5);
    CHECK(gi_chart_points_kept(&logx, &s) == 3);   /* also x = 0, x = -1 */
    CHECK(gi_chart_points_kept(&loglog, &s) == 2); /* also y = -2 */
    gi_chart_series empty = {"e", NULL, NULL, 0, GI_CHART_DASHED, 0, NULL, NULL, NULL, NULL};
    CHECK(gi_chart_points_kept(&loglog, &empty) == 0);

    /* Such a series still draws (with a warning), as do empty ones. */
    gi_chart_series both[3] = {
        s, empty, {NULL, x, y, 1, GI_CHART_MARKERS, 0, NULL, NULL, NULL, NULL}};
    char path[600];
    snprintf(path, sizeof path, "%s/dropped.png", dir);
    gi_error err = {{0}};
    CHECK_MSG(gi_chart_write_png(path, &loglog, both, 3, &err) == GI_OK, "%s", err.text);
    gi_image *img = gi_image_read(path, &err);
    CHECK(img && img->width == 900 && img->height == 600); /* the default size */
    gi_image_free(img);

    /* No series at all: empty axes, still a picture. */
    gi_chart_desc titled = {"nothing yet", "x", "y", 1, 1, 320, 200, NULL, 0};
    snprintf(path, sizeof path, "%s/empty.png", dir);
    CHECK_MSG(gi_chart_write_png(path, &titled, NULL, 0, &err) == GI_OK, "%s", err.text);
    img = gi_image_read(path, &err);
    CHECK(img && img->width == 320 && img->height == 200);
    gi_image_free(img);
}

/* Axis ranges the log-tick code treats apart: many decades (labels as
 * powers of ten), a single point, linear axes with negative values. */
static void test_ranges(void)
{
    enum { N = 30 };
    double x[N], y[N], lx[N], ly[N];
    for (int i = 0; i < N; i++) {
        x[i] = pow(10.0, -1.0 + 6.0 * i / (N - 1)); /* 0.1 .. 1e5 */
        y[i] = 1e-1 * pow(x[i] / 0.1, -1.0);        /* 0.1 .. 1e-7 */
        lx[i] = -5.0 + i;
        ly[i] = 0.01 * lx[i] * lx[i] - 2.0;
    }
    double one_x = 3.0, one_y = 0.25;
    struct {
        const char *name;
        gi_chart_desc d;
        gi_chart_series s;
    } cases[] = {
        {"wide.png",
         {"seven decades", "samples per pixel", "relMSE", 1, 1, 700, 500, NULL, 0},
         {"1/spp", x, y, N, GI_CHART_LINE_MARKERS, 0, NULL, NULL, NULL, NULL}},
        {"single.png",
         {"one point", "x", "y", 1, 1, 400, 300, NULL, 0},
         {"only", &one_x, &one_y, 1, GI_CHART_LINE_MARKERS, 0, NULL, NULL, NULL, NULL}},
        {"linear.png",
         {"linear axes", "frame", "signed error", 0, 0, 600, 400, NULL, 0},
         {"parabola", lx, ly, N, GI_CHART_LINE_MARKERS, 0, NULL, NULL, NULL, NULL}},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        char path[600];
        snprintf(path, sizeof path, "%s/%s", dir, cases[k].name);
        gi_error err = {{0}};
        CHECK_MSG(gi_chart_write_png(path, &cases[k].d, &cases[k].s, 1, &err) == GI_OK, "%s: %s",
                  cases[k].name, err.text);
        gi_image *img = gi_image_read(path, &err);
        CHECK_MSG(img && img->width == cases[k].d.width && img->height == cases[k].d.height, "%s",
                  cases[k].name);
        static const int blue[3] = {0, 114, 178};
        size_t blue_px = 0;
        for (uint32_t yy = 0; img && yy < img->height; yy++)
            for (uint32_t xx = 0; xx < img->width; xx++) {
                int rgb[3];
                px(img, xx, yy, rgb);
                blue_px += near_colour(rgb, blue, 24);
            }
        CHECK_MSG(blue_px > 20, "%s: %zu pixels of the series colour", cases[k].name, blue_px);
        gi_image_free(img);
    }
}

/* A series' own colour index: colour and marker of that position, so that
 * a method's runs (thin, no legend entry) and its front share a look. */
static void test_colour_index(void)
{
    enum { N = 8 };
    double x[N], y[N], y2[N];
    for (int i = 0; i < N; i++) {
        x[i] = i;
        y[i] = i * 0.5;
        y2[i] = i * 0.25;
    }
    gi_chart_series s[2] = {
        {NULL, x, y2, N, GI_CHART_THIN, 2, NULL, NULL, NULL, NULL},
        {"front", x, y, N, GI_CHART_LINE_MARKERS, 2, NULL, NULL, NULL, NULL},
    };
    gi_chart_desc d = {"colour index", "x", "y", 0, 0, 500, 400, NULL, 0};
    char path[600];
    snprintf(path, sizeof path, "%s/colour_index.png", dir);
    gi_error err = {{0}};
    CHECK_MSG(gi_chart_write_png(path, &d, s, 2, &err) == GI_OK, "%s", err.text);
    gi_image *img = gi_image_read(path, &err);
    CHECK_MSG(img != NULL, "%s", err.text);
    static const int blue[3] = {0, 114, 178}, vermillion[3] = {213, 94, 0};
    size_t blue_px = 0, verm_px = 0;
    for (uint32_t yy = 0; img && yy < img->height; yy++)
        for (uint32_t xx = 0; xx < img->width; xx++) {
            int rgb[3];
            px(img, xx, yy, rgb);
            blue_px += near_colour(rgb, blue, 24);
            verm_px += near_colour(rgb, vermillion, 24);
        }
    /* both series in the second palette colour; the first (blue) unused */
    CHECK_MSG(verm_px > 20 && blue_px == 0, "%zu vermillion, %zu blue pixels", verm_px, blue_px);
    gi_image_free(img);
}

/* A reference curve (GI_CHART_REFERENCE, the path tracer's) is drawn in
 * a grey of its own: even first in the chart it takes no palette colour. */
static void test_reference_look(void)
{
    double x[4] = {0, 1, 2, 3}, y[4] = {3, 2, 1, 0};
    size_t grey_px[2] = {0, 0}, blue_px = 0;
    /* without and with the curve: antialiased axis text has greys too */
    for (uint32_t with = 0; with < 2; with++) {
        gi_chart_series s[1] = {
            {"path tracer", x, y, 4 * with, GI_CHART_REFERENCE, 0, NULL, NULL, NULL, NULL}};
        gi_chart_desc d = {"reference look", "x", "y", 0, 0, 500, 400, NULL, 0};
        char path[600];
        snprintf(path, sizeof path, "%s/reference_look_%u.png", dir, with);
        gi_error err = {{0}};
        CHECK_MSG(gi_chart_write_png(path, &d, s, 1, &err) == GI_OK, "%s", err.text);
        gi_image *img = gi_image_read(path, &err);
        CHECK_MSG(img != NULL, "%s", err.text);
        static const int blue[3] = {0, 114, 178}, grey[3] = {90, 90, 90};
        for (uint32_t yy = 0; img && yy < img->height; yy++)
            for (uint32_t xx = 0; xx < img->width; xx++) {
                int rgb[3];
                px(img, xx, yy, rgb);
                blue_px += near_colour(rgb, blue, 24);
                grey_px[with] += near_colour(rgb, grey, 6);
            }
        gi_image_free(img);
    }
    CHECK_MSG(grey_px[1] > grey_px[0] + 100 && blue_px == 0,
              "%zu grey pixels with the curve, %zu without; %zu blue", grey_px[1], grey_px[0],
              blue_px);
}

/* Axis ranges (charts.h): a short span is widened so that noise does not
 * fill the y axis; a wide one is only padded; error bars count. */
static void test_noise_ranges(void)
{
    double x[3] = {1, 2, 3}, y[3] = {1.00, 1.01, 1.02}, wide[3] = {0, 5, 10};
    double lo[3] = {0.99, 1.0, 1.01}, hi[3] = {1.01, 50.0, 1.03};
    gi_chart_series s = {"s", x, y, 3, GI_CHART_LINE_MARKERS, 0, NULL, NULL, NULL, NULL};
    gi_chart_desc lin = {0}, logy = {0};
    logy.log_y = 1;
    double xr[2], yr[2];
    gi_chart_axis_ranges(&lin, &s, 1, xr, yr);
    /* 2 % apart: the axis spans at least 20 % of 1.02, the data a tenth of it */
    CHECK_MSG(yr[1] - yr[0] >= 0.2 * 1.02 && yr[0] < 1.0 && yr[1] > 1.02, "linear y range [%g, %g]",
              yr[0], yr[1]);
    CHECK_MSG((1.02 - 1.00) / (yr[1] - yr[0]) < 0.11, "the data fill %.0f %% of the axis",
              100.0 * 0.02 / (yr[1] - yr[0]));
    CHECK_MSG(xr[0] < 1.0 && xr[0] > 0.9 && xr[1] > 3.0 && xr[1] < 3.1,
              "x range [%g, %g] is only padded", xr[0], xr[1]);
    gi_chart_axis_ranges(&logy, &s, 1, xr, yr);
    CHECK_MSG(yr[1] / yr[0] >= 2.0 && yr[0] < 1.0 && yr[1] > 1.02, "log y range [%g, %g]", yr[0],
              yr[1]);
    s.y = wide;
    gi_chart_axis_ranges(&lin, &s, 1, xr, yr);
    CHECK_MSG(fabs(yr[0] + 0.4) < 1e-9 && fabs(yr[1] - 10.4) < 1e-9,
              "wide range [%g, %g]: 4 %% padding only", yr[0], yr[1]);
    s.y = y;
    s.y_lo = lo;
    s.y_hi = hi;
    gi_chart_axis_ranges(&lin, &s, 1, xr, yr);
    CHECK_MSG(yr[1] >= 50.0, "an error bar up to 50 is inside the y range [%g, %g]", yr[0], yr[1]);
}

/* Error bars are drawn: a point with a bar from 1 to 9 covers far more rows
 * of its colour than the same point without one (a second series fixes
 * both charts' ranges to the same [0, 10]). */
static void test_error_bars(void)
{
    double px_[1] = {5}, py_[1] = {5}, blo[1] = {1}, bhi[1] = {9};
    double fx[2] = {0, 10}, fy[2] = {0, 10};
    uint32_t extent[2];
    for (int with = 0; with < 2; with++) {
        gi_chart_series s[2] = {
            {"bars", px_, py_, 1, GI_CHART_MARKERS, 0, NULL, NULL, with ? blo : NULL,
             with ? bhi : NULL},
            {"frame", fx, fy, 2, GI_CHART_MARKERS, 2, NULL, NULL, NULL, NULL},
        };
        gi_chart_desc d = {"error bars", "x", "y", 0, 0, 500, 400, NULL, 0};
        char path[600];
        snprintf(path, sizeof path, "%s/bars_%d.png", dir, with);
        gi_error err = {{0}};
        CHECK_MSG(gi_chart_write_png(path, &d, s, 2, &err) == GI_OK, "%s", err.text);
        gi_image *img = gi_image_read(path, &err);
        CHECK_MSG(img != NULL, "%s", err.text);
        static const int blue[3] = {0, 114, 178};
        int top = -1, bottom = -1;
        /* the plot area only: the legend (right of x = 400) has a blue marker too */
        for (uint32_t yy = 0; img && yy < img->height; yy++)
            for (uint32_t xx = 0; xx < 400; xx++) {
                int rgb[3];
                px(img, xx, yy, rgb);
                if (near_colour(rgb, blue, 24)) {
                    if (top < 0)
                        top = (int)yy;
                    bottom = (int)yy;
                }
            }
        extent[with] = top < 0 ? 0 : (uint32_t)(bottom - top + 1);
        gi_image_free(img);
    }
    /* marker ~9 px; the bar spans 8 of the axis' 10.8 units of ~300 px */
    CHECK_MSG(extent[0] > 0 && extent[0] < 20 && extent[1] > 150,
              "blue rows: %u without, %u with the bar", extent[0], extent[1]);
}

/* Ticks at given values: accepted, change the picture, and a count without
 * an array is an error. */
static void test_custom_ticks(void)
{
    double x[3] = {32, 64, 128}, y[3] = {5.6, 9.0, 16.9}, ticks[3] = {32, 64, 128};
    gi_chart_series s = {"ratio", x, y, 3, GI_CHART_LINE_MARKERS, 0, NULL, NULL, NULL, NULL};
    gi_chart_desc d = {"atlas sweep", "atlas", "ratio", 1, 0, 400, 300, NULL, 0};
    char a[600], b[600];
    snprintf(a, sizeof a, "%s/ticks_auto.png", dir);
    snprintf(b, sizeof b, "%s/ticks_swept.png", dir);
    gi_error err = {{0}};
    CHECK_MSG(gi_chart_write_png(a, &d, &s, 1, &err) == GI_OK, "%s", err.text);
    d.x_ticks = ticks;
    d.x_tick_count = 3;
    CHECK_MSG(gi_chart_write_png(b, &d, &s, 1, &err) == GI_OK, "%s", err.text);
    gi_image *ia = gi_image_read(a, &err), *ib = gi_image_read(b, &err);
    size_t differ = 0;
    for (size_t i = 0; ia && ib && i < (size_t)ia->width * ia->height * 4; i++)
        differ += ia->rgba[i] != ib->rgba[i];
    CHECK_MSG(differ > 100, "ticks at 32, 64, 128 change %zu values of the picture", differ);
    gi_image_free(ia);
    gi_image_free(ib);
    d.x_ticks = NULL;
    CHECK(gi_chart_write_png(b, &d, &s, 1, &err) == GI_ERR_INVALID_ARGUMENT);
    CHECK_MSG(strstr(err.text, "ticks") != NULL, "%s", err.text);
}

static void test_errors(void)
{
    double x[] = {1, 2}, y[] = {1, 2};
    gi_chart_series s = {"s", x, y, 2, GI_CHART_LINE_MARKERS, 0, NULL, NULL, NULL, NULL};
    gi_chart_desc d = {0};
    gi_error err = {{0}};
    char path[600];

    /* A directory that does not exist: an I/O error naming the path. */
    snprintf(path, sizeof path, "%s/no/such/dir/c.png", dir);
    CHECK(gi_chart_write_png(path, &d, &s, 1, &err) == GI_ERR_IO);
    CHECK_MSG(strstr(err.text, path) != NULL, "%s", err.text);

    /* The destination is a directory: the rename fails, nothing is left. */
    snprintf(path, sizeof path, "%s/isdir.png", dir);
    mkdir(path, 0755);
    err.text[0] = '\0';
    CHECK(gi_chart_write_png(path, &d, &s, 1, &err) == GI_ERR_IO);
    CHECK_MSG(strstr(err.text, "isdir.png") != NULL, "%s", err.text);
    CHECK(count_temporaries() == 0);

    snprintf(path, sizeof path, "%s/c.svg", dir);
    CHECK(gi_chart_write_png(path, &d, &s, 1, &err) == GI_ERR_INVALID_ARGUMENT);
    CHECK(gi_chart_write_png("", &d, &s, 1, &err) == GI_ERR_INVALID_ARGUMENT);

    snprintf(path, sizeof path, "%s/c.png", dir);
    gi_chart_series bad_style = {"s", x, y, 2, 7, 0, NULL, NULL, NULL, NULL};
    CHECK(gi_chart_write_png(path, &d, &bad_style, 1, &err) == GI_ERR_INVALID_ARGUMENT);
    CHECK_MSG(strstr(err.text, "style") != NULL, "%s", err.text);
    gi_chart_series bad_colour = {"s", x, y, 2, GI_CHART_THIN, -1, NULL, NULL, NULL, NULL};
    CHECK(gi_chart_write_png(path, &d, &bad_colour, 1, &err) == GI_ERR_INVALID_ARGUMENT);
    CHECK_MSG(strstr(err.text, "colour") != NULL, "%s", err.text);
    gi_chart_series no_data = {"s", NULL, y, 2, GI_CHART_MARKERS, 0, NULL, NULL, NULL, NULL};
    CHECK(gi_chart_write_png(path, &d, &no_data, 1, &err) == GI_ERR_INVALID_ARGUMENT);
    CHECK(gi_chart_write_png(path, &d, NULL, 2, &err) == GI_ERR_INVALID_ARGUMENT);
    gi_chart_desc huge = {0};
    huge.width = 100000;
    CHECK(gi_chart_write_png(path, &huge, &s, 1, &err) == GI_ERR_INVALID_ARGUMENT);
    struct stat st;
    CHECK(stat(path, &st) != 0); /* nothing was written by the refused calls */
}

/* The harness may hold the core's GL context while it writes a report. */
static void test_context_restored(void)
{
    gi_error err = {{0}};
    gi_gpu *gpu = gi_gpu_create(NULL, &err);
    CHECK_MSG(gpu != NULL, "%s", err.text);
    if (!gpu)
        return;
    EGLContext before = eglGetCurrentContext();
    GLuint buf = 0;
    glGenBuffers(1, &buf); /* a GL object of the caller's, alive across the chart */
    glBindBuffer(GL_ARRAY_BUFFER, buf);
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    double x[] = {1, 10}, y[] = {1, 0.1};
    gi_chart_series s = {"s", x, y, 2, GI_CHART_LINE_MARKERS, 0, NULL, NULL, NULL, NULL};
    gi_chart_desc d = {"with the core's context", NULL, NULL, 1, 1, 400, 300, NULL, 0};
    char path[600];
    snprintf(path, sizeof path, "%s/ctx.png", dir);
    CHECK_MSG(gi_chart_write_png(path, &d, &s, 1, &err) == GI_OK, "%s", err.text);
    CHECK(eglGetCurrentContext() == before);
    CHECK(glIsBuffer(buf)); /* the caller's context, not the chart's */
    glDeleteBuffers(1, &buf);
    CHECK_MSG(gi_gl_check("after a chart", &err) == GI_OK, "%s", err.text);
    gi_gpu_destroy(gpu);
}

int main(void)
{
    make_dir();
    /* First, so that its time includes VTK's and EGL's start-up. */
    test_log_log_chart();
    gi_error err = {{0}};
    double t0 = now();
    gi_result avail = gi_chart_available(&err);
    CHECK_MSG(avail == GI_OK, "%s", err.text);
    printf("gi_chart_available: %.3f s\n", now() - t0);
    if (avail != GI_OK)
        return gi_test_finish();
    test_points_kept();
    test_ranges();
    test_colour_index();
    test_reference_look();
    test_noise_ranges();
    test_error_bars();
    test_custom_ticks();
    test_errors();
    test_context_restored();
    /* Kept for a look when something failed or GI_KEEP_CHARTS is set. */
    if (gi_test_failed == 0 && !getenv("GI_KEEP_CHARTS")) {
        char cmd[700];
        snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
        if (system(cmd) != 0)
            fprintf(stderr, "could not remove %s\n", dir);
    } else {
        printf("charts in %s\n", dir);
    }
    return gi_test_finish();
}
