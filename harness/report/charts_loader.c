/* The charts API (charts.h) for the processes that link neither VTK nor its
 * few hundred dependencies: each function opens the module libgi_charts.so
 * (harness/report/charts.cpp, gi/module.h) on first use and calls the function of
 * the same name there. A missing module is a one-line error
 * (GI_ERR_UNSUPPORTED), as when no OpenGL context can be made. */
#include "charts.h"

#include "gi/module.h"

#include <string.h>

#define CHARTS_MODULE "libgi_charts.so"

/* The module's function `name`, or NULL with the reason in err. */
static void *charts_symbol(const char *name, gi_error *err)
{
    return gi_module_symbol(CHARTS_MODULE, name, "drawing charts", err);
}

gi_result gi_chart_write_png(const char *path, const gi_chart_desc *desc,
                             const gi_chart_series *series, uint32_t n, gi_error *err)
{
    gi_result (*fn)(const char *, const gi_chart_desc *, const gi_chart_series *, uint32_t,
                    gi_error *);
    void *sym = charts_symbol("gi_chart_write_png", err);
    if (!sym)
        return GI_ERR_UNSUPPORTED;
    memcpy(&fn, &sym, sizeof fn);
    return fn(path, desc, series, n, err);
}

gi_result gi_chart_available(gi_error *err)
{
    gi_result (*fn)(gi_error *);
    void *sym = charts_symbol("gi_chart_available", err);
    if (!sym)
        return GI_ERR_UNSUPPORTED;
    memcpy(&fn, &sym, sizeof fn);
    return fn(err);
}

uint32_t gi_chart_points_kept(const gi_chart_desc *desc, const gi_chart_series *s)
{
    uint32_t (*fn)(const gi_chart_desc *, const gi_chart_series *);
    gi_error err;
    void *sym = charts_symbol("gi_chart_points_kept", &err);
    if (!sym)
        return 0;
    memcpy(&fn, &sym, sizeof fn);
    return fn(desc, s);
}

void gi_chart_axis_ranges(const gi_chart_desc *desc, const gi_chart_series *series, uint32_t n,
                          double x_range[2], double y_range[2])
{
    void (*fn)(const gi_chart_desc *, const gi_chart_series *, uint32_t, double[2], double[2]);
    gi_error err;
    void *sym = charts_symbol("gi_chart_axis_ranges", &err);
    if (!sym) { /* no module: nothing is drawn; report the empty axes' ranges */
        x_range[0] = y_range[0] = 0.0;
        x_range[1] = y_range[1] = 1.0;
        return;
    }
    memcpy(&fn, &sym, sizeof fn);
    fn(desc, series, n, x_range, y_range);
}
