/* Charts (charts.h) drawn by VTK into a headless EGL context. The only C++
 * translation unit that touches VTK; no exception and no C++ type leaves it.
 *
 * Headless without X: Debian's VTK 9.1 is built for GLX only (no EGL, no
 * OSMesa render window; runtime selection by VTK_DEFAULT_OPENGL_WINDOW only
 * exists from VTK 9.4), and its X render window crashes without a display.
 * So the chart draws into a vtkGenericOpenGLRenderWindow on a GL context we
 * create through EGL. VTK 9.1 loads GL with GLEW built for GLX: glewInit()
 * fetches every entry point through glXGetProcAddress (libglvnd's dispatch
 * stubs, which route to whichever context is current, EGL ones included)
 * and then fails with GLEW_ERROR_NO_GLX_DISPLAY, because there is no GLX
 * display to ask for GLX extensions. egl_window below accepts exactly that
 * result; without it VTK logs an error on every frame and never marks its
 * context initialised. Pixels are identical to an Xvfb + GLX render on the
 * same llvmpipe (checked byte for byte on Debian 12).
 */
#define EGL_NO_X11 1  /* keep Xlib's macros (None, Status, Bool) out of VTK */
#include <vtk_glew.h> /* first: GLEW must precede every other GL header */

#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <vtkAxis.h>
#include <vtkBrush.h>
#include <vtkChartLegend.h>
#include <vtkChartXY.h>
#include <vtkContextScene.h>
#include <vtkContextView.h>
#include <vtkDoubleArray.h>
#include <vtkErrorCode.h>
#include <vtkGenericOpenGLRenderWindow.h>
#include <vtkImageData.h>
#include <vtkLogger.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkOutputWindow.h>
#include <vtkPNGWriter.h>
#include <vtkPen.h>
#include <vtkPlotLine.h>
#include <vtkPlotPoints.h>
#include <vtkPoints2D.h>
#include <vtkRenderer.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>
#include <vtkTable.h>
#include <vtkTextProperty.h>
#include <vtkUnsignedCharArray.h>
#include <vtkWindowToImageFilter.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <mutex>
#include <new>
#include <string>
#include <vector>

#include <sys/stat.h>
#include <unistd.h>

#include "charts.h"
#include "gi/cache.h"
#include "gi/log.h"

namespace
{

constexpr uint32_t default_width = 900, default_height = 600, max_side = 4096;

/* Okabe & Ito, "Color Universal Design" (2008): distinguishable under the
 * common colour-vision deficiencies. Yellow is last: it is faint on white. */
const unsigned char palette[][3] = {
    {0, 114, 178},   /* blue */
    {213, 94, 0},    /* vermillion */
    {0, 158, 115},   /* bluish green */
    {204, 121, 167}, /* reddish purple */
    {230, 159, 0},   /* orange */
    {86, 180, 233},  /* sky blue */
    {0, 0, 0},       /* black */
    {240, 228, 66},  /* yellow */
};
constexpr size_t palette_size = sizeof palette / sizeof palette[0];
/* Reference curves (GI_CHART_REFERENCE): greys, none in the palette (its
 * black excepted, they are grey), each with its own dash pattern, so that a
 * reference is never read as a method. */
const unsigned char reference_greys[][3] = {
    {90, 90, 90}, {125, 125, 125}, {155, 155, 155}, {180, 180, 180}};
const int reference_dashes[] = {vtkPen::DASH_LINE, vtkPen::DASH_DOT_LINE, vtkPen::DOT_LINE,
                                vtkPen::DASH_DOT_DOT_LINE};
constexpr size_t reference_looks = sizeof reference_greys / sizeof reference_greys[0];
/* Five shapes against eight colours: series k and k + 8 still differ. */
const int markers[] = {vtkPlotPoints::CIRCLE, vtkPlotPoints::SQUARE, vtkPlotPoints::DIAMOND,
                       vtkPlotPoints::CROSS, vtkPlotPoints::PLUS};
constexpr size_t marker_count = sizeof markers / sizeof markers[0];

/* VTK keeps process-wide state (the output window, GLEW's entry points). */
std::mutex chart_mutex;

/* Collapses VTK's "ERROR: In file, line N\nclass (0x..): text\n\n" to the text. */
std::string one_line(const char *text)
{
    std::string s = text ? text : "";
    if (s.rfind("ERROR: In ", 0) == 0 || s.rfind("Warning: In ", 0) == 0) {
        size_t nl = s.find('\n');
        s = nl == std::string::npos ? s : s.substr(nl + 1);
    }
    for (char &c : s)
        if (c == '\n' || c == '\r')
            c = ' ';
    while (!s.empty() && s.back() == ' ')
        s.pop_back();
    return s;
}

/* Catches what VTK reports while a chart is drawn: errors fail the call,
 * warnings go to the debug log instead of VTK's own stderr printing. */
class capture_output : public vtkOutputWindow
{
  public:
    static capture_output *New();
    /* No ";" after vtkTypeMacro: it ends in a function body (-Wpedantic). */
    vtkTypeMacro(capture_output, vtkOutputWindow)
    void DisplayText(const char *text) override
    {
        if (this->GetCurrentMessageType() == MESSAGE_TYPE_ERROR) {
            if (first_error.empty())
                first_error = one_line(text);
        } else {
            gi_log(GI_LOG_DEBUG, "VTK: %s", one_line(text).c_str());
        }
    }
    std::string first_error;
};
vtkStandardNewMacro(capture_output);

/* Installs a capture_output for its lifetime, then puts the old one back. */
struct output_scope {
    vtkSmartPointer<vtkOutputWindow> previous;
    vtkNew<capture_output> capture;
    output_scope() : previous(vtkOutputWindow::GetInstance())
    {
        vtkOutputWindow::SetInstance(capture);
        /* VTK also logs every error to stderr itself (loguru); ours are
         * reported through gi_error instead. Nothing else uses VTK here. */
        vtkLogger::SetStderrVerbosity(vtkLogger::VERBOSITY_OFF);
    }
    ~output_scope()
    {
        vtkOutputWindow::SetInstance(previous);
    }
    output_scope(const output_scope &) = delete;
    output_scope &operator=(const output_scope &) = delete;
};

/* A render window on the GL context that is current when it is initialised
 * (see the file comment for why OpenGLInitContext is replaced). */
class egl_window : public vtkGenericOpenGLRenderWindow
{
  public:
    static egl_window *New();
    vtkTypeMacro(egl_window, vtkGenericOpenGLRenderWindow)
    std::string init_error;

  protected:
    void OpenGLInitContext() override
    {
        this->ContextCreationTime.Modified();
        if (this->Initialized)
            return;
        GLenum r = glewInit();
        if (r != GLEW_OK && r != GLEW_ERROR_NO_GLX_DISPLAY) {
            init_error =
                std::string("glewInit: ") + reinterpret_cast<const char *>(glewGetErrorString(r));
            return;
        }
        if (!GLEW_VERSION_3_2) {
            init_error = "the EGL context offers no OpenGL 3.2";
            return;
        }
        this->GlewInitValid = true;
        this->Initialized = true;
        /* As vtkOpenGLRenderWindow does: wide lines are drawn as quads
         * beyond what the hardware draws itself. */
        GLfloat range[2] = {1.0f, 1.0f};
        glGetFloatv(this->LineSmoothing ? GL_SMOOTH_LINE_WIDTH_RANGE : GL_ALIASED_LINE_WIDTH_RANGE,
                    range);
        this->MaximumHardwareLineWidth = glGetError() == GL_NO_ERROR ? range[1] : 1.0f;
    }
};
vtkStandardNewMacro(egl_window);

/* A line plot that draws a series of fewer than two points as markers only
 * (vtkPlotLine would report "a line with <2 points" as an error), so that
 * short and empty series still render and keep their legend entry. */
class short_safe_line : public vtkPlotLine
{
  public:
    static short_safe_line *New();
    vtkTypeMacro(short_safe_line, vtkPlotLine)

    bool Paint(vtkContext2D *painter) override
    {
        if (this->Points && this->Points->GetNumberOfPoints() < 2)
            return this->vtkPlotPoints::Paint(painter);
        return this->vtkPlotLine::Paint(painter);
    }
};
vtkStandardNewMacro(short_safe_line);

bool has_ext(const char *list, const char *name)
{
    size_t n = strlen(name);
    for (const char *p = list; p && (p = strstr(p, name)) != nullptr; p += n)
        if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0'))
            return true;
    return false;
}

/* An OpenGL 3.2 core context of our own, current while this lives; the
 * caller's current context (if any) is current again afterwards. Mesa's
 * surfaceless platform first (llvmpipe: the same pixels on every machine),
 * then EGL devices; GIBENCH_EGL=surfaceless|device forces one, as for the
 * core. The display is never terminated: EGL displays are per-process
 * singletons that gicore may be using. */
struct egl_scope {
    EGLDisplay prev_display = EGL_NO_DISPLAY;
    EGLContext prev_context = EGL_NO_CONTEXT;
    EGLSurface prev_draw = EGL_NO_SURFACE, prev_read = EGL_NO_SURFACE;
    EGLenum prev_api = EGL_OPENGL_ES_API;
    EGLDisplay display = EGL_NO_DISPLAY;
    EGLContext context = EGL_NO_CONTEXT;

    egl_scope()
    {
        prev_display = eglGetCurrentDisplay();
        prev_context = eglGetCurrentContext();
        prev_draw = eglGetCurrentSurface(EGL_DRAW);
        prev_read = eglGetCurrentSurface(EGL_READ);
        prev_api = eglQueryAPI();
    }
    ~egl_scope()
    {
        if (context != EGL_NO_CONTEXT) {
            eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
            eglDestroyContext(display, context);
        }
        eglBindAPI(prev_api);
        if (prev_context != EGL_NO_CONTEXT)
            eglMakeCurrent(prev_display, prev_draw, prev_read, prev_context);
    }
    egl_scope(const egl_scope &) = delete;
    egl_scope &operator=(const egl_scope &) = delete;

    bool try_display(EGLDisplay dpy, std::string &why)
    {
        EGLint major = 0, minor = 0;
        if (dpy == EGL_NO_DISPLAY || !eglInitialize(dpy, &major, &minor)) {
            why = "eglInitialize failed";
            return false;
        }
        const char *exts = eglQueryString(dpy, EGL_EXTENSIONS);
        if (!has_ext(exts, "EGL_KHR_surfaceless_context")) {
            why = "no EGL_KHR_surfaceless_context";
            return false;
        }
        if (!eglBindAPI(EGL_OPENGL_API)) {
            why = "no desktop OpenGL API";
            return false;
        }
        EGLint cfg_attr[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
        EGLConfig cfg = nullptr;
        EGLint ncfg = 0;
        bool have_cfg = eglChooseConfig(dpy, cfg_attr, &cfg, 1, &ncfg) && ncfg > 0;
        if (!have_cfg && !has_ext(exts, "EGL_KHR_no_config_context")) {
            why = "no EGL config for OpenGL";
            return false;
        }
        EGLint ctx_attr[] = {EGL_CONTEXT_MAJOR_VERSION,
                             3,
                             EGL_CONTEXT_MINOR_VERSION,
                             2,
                             EGL_CONTEXT_OPENGL_PROFILE_MASK,
                             EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                             EGL_NONE};
        EGLContext ctx =
            eglCreateContext(dpy, have_cfg ? cfg : EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, ctx_attr);
        if (ctx == EGL_NO_CONTEXT) {
            why = "no OpenGL 3.2 core context";
            return false;
        }
        if (!eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) {
            eglDestroyContext(dpy, ctx);
            why = "eglMakeCurrent failed";
            return false;
        }
        display = dpy;
        context = ctx;
        return true;
    }

    /* Makes our context current; false and the reasons otherwise. */
    bool open(std::string &why)
    {
        /* The charts need any GL: GIBENCH_EGL's other forms (auto, an index,
         * a name: the core's device choice, gpu_egl.c) fall back to the
         * default order here rather than refusing to draw. */
        const char *want = getenv("GIBENCH_EGL");
        if (want && strcmp(want, "device") != 0 && strcmp(want, "surfaceless") != 0)
            want = nullptr;
        const char *client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
        auto get_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
            eglGetProcAddress("eglGetPlatformDisplayEXT"));
        if (!get_display) {
            why = "no eglGetPlatformDisplayEXT";
            return false;
        }
        std::string reasons, r;
        if (!want || !*want || !strcmp(want, "surfaceless")) {
            if (!has_ext(client, "EGL_MESA_platform_surfaceless"))
                reasons += "surfaceless: no EGL_MESA_platform_surfaceless; ";
            else if (try_display(
                         get_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr),
                         r))
                return true;
            else
                reasons += "surfaceless: " + r + "; ";
        }
        if (!want || !*want || !strcmp(want, "device")) {
            auto query_devices = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(
                eglGetProcAddress("eglQueryDevicesEXT"));
            EGLDeviceEXT devices[16];
            EGLint count = 0;
            if (!has_ext(client, "EGL_EXT_platform_device") || !query_devices ||
                !query_devices(16, devices, &count) || count == 0)
                reasons += "device: no EGL devices; ";
            for (EGLint i = 0; i < count; i++) {
                if (try_display(get_display(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr), r))
                    return true;
                reasons += "device " + std::to_string(i) + ": " + r + "; ";
            }
        }
        why = reasons.size() >= 2 ? reasons.substr(0, reasons.size() - 2) : reasons;
        return false;
    }
};

/* Whether point i of s is drawn (charts.h, "Points"). */
bool kept(const gi_chart_desc &d, const gi_chart_series &s, uint32_t i)
{
    double x = s.x[i], y = s.y[i];
    return std::isfinite(x) && std::isfinite(y) && !(d.log_x && x <= 0.0) && !(d.log_y && y <= 0.0);
}

std::string label_of(const gi_chart_series &s, uint32_t k)
{
    return s.label && *s.label ? std::string(s.label) : "series " + std::to_string(k + 1);
}

/* DejaVu Sans (Debian's fonts-dejavu-core) where installed: VTK's embedded
 * "Arial" draws '[' as '(' and has no superscript minus. */
const char *const font_regular = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";
const char *const font_bold = "/usr/share/fonts/truetype/dejavu/DejaVuSans-Bold.ttf";

bool have_dejavu()
{
    return access(font_regular, R_OK) == 0 && access(font_bold, R_OK) == 0;
}

void style_text(vtkTextProperty *p, int size, bool bold, bool dejavu)
{
    if (dejavu) {
        p->SetFontFamily(VTK_FONT_FILE);
        p->SetFontFile(bold ? font_bold : font_regular);
    } else {
        p->SetFontFamilyToArial();
        p->SetBold(bold);
    }
    p->SetFontSize(size);
    p->SetColor(0.0, 0.0, 0.0);
}

/* A tick label m·10^e: plain "%g" from 0.001 to 90000 unless `powers`,
 * else m×10ⁿ when the font has the glyphs ("1e-05" otherwise). */
std::string tick_label(int m, int e, bool dejavu, bool powers)
{
    char text[64];
    if (!dejavu || (!powers && e >= -3 && e <= 4)) {
        snprintf(text, sizeof text, "%g", m * std::pow(10.0, e));
        return text;
    }
    static const char *const sup[] = {"\u2070", "\u00b9", "\u00b2", "\u00b3", "\u2074",
                                      "\u2075", "\u2076", "\u2077", "\u2078", "\u2079"};
    std::string s = m == 1 ? "10" : std::to_string(m) + "\u00d710";
    if (e < 0)
        s += "\u207b";
    for (char c : std::to_string(std::abs(e)))
        s += sup[c - '0'];
    return s;
}

/* Whether an error-bar end v can be drawn on an axis (finite; > 0 on a log axis). */
bool bar_end_ok(double v, int log)
{
    return std::isfinite(v) && !(log && v <= 0.0);
}

/* The error bars of a series as one line plot of separate segments
 * (vtkPlotLine without PolyLine joins points 0-1, 2-3, ...): thin, in the
 * series' colour, no markers, no legend entry. */
void add_bars(vtkChartXY *chart, const gi_chart_desc &d, const gi_chart_series &s,
              const unsigned char *c)
{
    vtkNew<vtkTable> table;
    vtkNew<vtkDoubleArray> xs, ys;
    xs->SetName("x");
    ys->SetName("y");
    auto segment = [&](double x0, double y0, double x1, double y1) {
        if (!bar_end_ok(x0, d.log_x) || !bar_end_ok(x1, d.log_x) || !bar_end_ok(y0, d.log_y) ||
            !bar_end_ok(y1, d.log_y) || (x0 == x1 && y0 == y1))
            return;
        xs->InsertNextValue(x0), ys->InsertNextValue(y0);
        xs->InsertNextValue(x1), ys->InsertNextValue(y1);
    };
    for (uint32_t i = 0; i < s.count; i++) {
        if (!kept(d, s, i))
            continue;
        if (s.x_lo && s.x_hi)
            segment(s.x_lo[i], s.y[i], s.x_hi[i], s.y[i]);
        if (s.y_lo && s.y_hi)
            segment(s.x[i], s.y_lo[i], s.x[i], s.y_hi[i]);
    }
    if (xs->GetNumberOfTuples() == 0)
        return;
    table->AddColumn(xs);
    table->AddColumn(ys);
    vtkNew<vtkPlotLine> bars;
    chart->AddPlot(bars);
    bars->SetInputData(table, 0, 1);
    bars->SetPolyLine(false);
    bars->SetMarkerStyle(vtkPlotPoints::NONE);
    bars->SetLegendVisibility(false);
    bars->SetColor(c[0], c[1], c[2], 255);
    bars->SetWidth(1.5f);
}

/* Adds series k to the chart: its own two-column table, colour, marker.
 * `name` (the title, else the file) identifies the chart in warnings. */
void add_series(vtkChartXY *chart, const gi_chart_desc &d, const gi_chart_series &s, uint32_t k,
                uint32_t reference_index, const char *name)
{
    vtkNew<vtkTable> table;
    vtkNew<vtkDoubleArray> xs, ys;
    xs->SetName("x");
    ys->SetName("y");
    uint32_t dropped = 0;
    for (uint32_t i = 0; i < s.count; i++) {
        if (!kept(d, s, i)) {
            dropped++;
            continue;
        }
        xs->InsertNextValue(s.x[i]);
        ys->InsertNextValue(s.y[i]);
    }
    if (dropped)
        gi_log(GI_LOG_WARN,
               "chart '%s': series '%s': %u of %u points not drawn (NaN, Inf or <= 0 on a log "
               "axis)",
               name, label_of(s, k).c_str(), dropped, s.count);
    table->AddColumn(xs);
    table->AddColumn(ys);

    vtkSmartPointer<vtkPlotPoints> plot;
    if (s.style == GI_CHART_MARKERS)
        plot = vtkSmartPointer<vtkPlotPoints>::New();
    else
        plot = vtkSmartPointer<short_safe_line>::New();
    chart->AddPlot(plot);
    plot->SetInputData(table, 0, 1);
    plot->SetLabel(label_of(s, k));
    /* colour and marker by position, or by the series' own colour index;
     * a reference by its own index among the reference looks */
    uint32_t look = s.color > 0 ? (uint32_t)s.color - 1 : k;
    if (s.style == GI_CHART_REFERENCE && s.color == 0)
        look = reference_index;
    const unsigned char *c = s.style == GI_CHART_REFERENCE ? reference_greys[look % reference_looks]
                                                           : palette[look % palette_size];
    plot->SetColor(c[0], c[1], c[2], s.style == GI_CHART_THIN ? 150 : 255);
    plot->SetWidth(s.style == GI_CHART_THIN ? 1.0f : 2.0f);
    if (s.style == GI_CHART_THIN) {
        plot->SetLegendVisibility(false);
        plot->SetMarkerStyle(markers[look % marker_count]);
        plot->SetMarkerSize(4.0f);
    } else if (s.style == GI_CHART_DASHED) {
        plot->GetPen()->SetLineType(vtkPen::DASH_LINE);
        plot->SetMarkerStyle(vtkPlotPoints::NONE);
    } else if (s.style == GI_CHART_REFERENCE) {
        plot->GetPen()->SetLineType(reference_dashes[look % reference_looks]);
        plot->SetMarkerStyle(vtkPlotPoints::NONE);
    } else {
        plot->SetMarkerStyle(markers[look % marker_count]);
        plot->SetMarkerSize(s.style == GI_CHART_MARKERS ? 9.0f : 7.0f);
    }
    add_bars(chart, d, s, c);
}

/* Range of one axis: the kept points' extent widened by 4 % of the span on
 * each side (in log10 on a log axis), so no marker sits on the frame. An
 * empty axis shows [0, 1] (linear) or [1, 10] (log); a single value is
 * widened to a visible interval. With `floor`, a short span is first
 * widened about its middle to a minimum (charts.h, "Axis ranges"), so
 * that noise is not magnified to fill the axis. */
void axis_range(double lo, double hi, int log, bool floor, double out[2])
{
    if (floor && lo < hi) {
        if (log) {
            double f = 2.0;
            if (hi / lo < f) {
                double mid = std::sqrt(lo * hi);
                lo = mid / std::sqrt(f);
                hi = mid * std::sqrt(f);
            }
        } else {
            double m = std::max(std::fabs(lo), std::fabs(hi)), want = 0.2 * m;
            if (hi - lo < want) {
                double mid = 0.5 * (lo + hi);
                lo = mid - 0.5 * want;
                hi = mid + 0.5 * want;
            }
        }
    }
    if (!(lo <= hi)) { /* no points: NaN-free defaults */
        out[0] = log ? 1.0 : 0.0;
        out[1] = log ? 10.0 : 1.0;
        return;
    }
    if (log) {
        lo = std::log10(lo);
        hi = std::log10(hi);
    }
    double span = hi - lo;
    if (span <= 0.0)
        span = log ? 1.0 : (lo != 0.0 ? std::fabs(lo) : 1.0);
    double pad = 0.04 * span;
    out[0] = lo - (hi > lo ? pad : span / 2);
    out[1] = hi + (hi > lo ? pad : span / 2);
    if (log) {
        out[0] = std::pow(10.0, out[0]);
        out[1] = std::pow(10.0, out[1]);
    }
}

/* Tick marks of a log axis over [lo, hi] (data units), as VTK wants them:
 * positions in log10, one label each ("" = unlabelled minor tick). Labels
 * at 1 x 10^k, else also 2 and 5 x 10^k, else every 1..9 x 10^k, whichever
 * first gives at least three; minor ticks at the other integer mantissas
 * while there are few decades. Narrower than that (a factor of about 3),
 * evenly spaced values with a round step. VTK 9.1's own choice labels
 * only decades or crowds short ranges. */
void log_ticks(double lo, double hi, bool dejavu, vtkDoubleArray *pos, vtkStringArray *labels)
{
    static const std::vector<std::vector<int>> label_sets = {
        {1}, {1, 2, 5}, {1, 2, 3, 4, 5, 6, 7, 8, 9}};
    int d0 = static_cast<int>(std::floor(std::log10(lo))) - 1;
    int d1 = static_cast<int>(std::ceil(std::log10(hi))) + 1;
    int decades = d1 - d0;
    auto add = [&](double v, const std::string &text) {
        pos->InsertNextValue(std::log10(v));
        labels->InsertNextValue(text);
    };
    for (const std::vector<int> &set : label_sets) {
        /* With many decades, label every step-th one. */
        int step = set.size() == 1 ? std::max(1, (decades - 2) / 8) : 1;
        /* Five decades or more labelled at 1 x 10^k read best as 10ⁿ throughout. */
        bool powers = set.size() == 1 && hi / lo >= 1e5;
        int count = 0;
        for (int e = d0; e <= d1; e++)
            for (int m : set)
                count +=
                    (e % step == 0) && m * std::pow(10.0, e) >= lo && m * std::pow(10.0, e) <= hi;
        if (count < 3)
            continue;
        for (int e = d0; e <= d1; e++)
            for (int m = 1; m <= 9; m++) {
                double v = m * std::pow(10.0, e);
                if (v < lo || v > hi)
                    continue;
                bool labelled =
                    (e % step == 0) && std::find(set.begin(), set.end(), m) != set.end();
                if (labelled || decades <= 8)
                    add(v, labelled ? tick_label(m, e, dejavu, powers) : std::string());
            }
        return;
    }
    /* Less than a factor of ~3: a round linear step, e.g. 1.2, 1.4, 1.6. */
    double raw = (hi - lo) / 5.0;
    double mag = std::pow(10.0, std::floor(std::log10(raw)));
    double stepv = raw / mag < 2.0 ? 2.0 * mag : raw / mag < 5.0 ? 5.0 * mag : 10.0 * mag;
    if (raw / mag < 1.5)
        stepv = mag;
    char text[32];
    for (double i = std::ceil(lo / stepv); i * stepv <= hi; i += 1.0) {
        snprintf(text, sizeof text, "%g", i * stepv);
        add(i * stepv, text);
    }
}

void set_axis(vtkAxis *axis, const char *title, int log, const double range[2], bool dejavu,
              const double *ticks, uint32_t tick_count)
{
    axis->SetTitle(title ? title : "");
    axis->SetLogScale(log != 0);
    axis->SetBehavior(vtkAxis::FIXED);
    axis->SetUnscaledRange(range[0], range[1]);
    bool custom = false;
    if (ticks && tick_count) {
        /* the caller's values (e.g. the swept ones), in the axis' units */
        vtkNew<vtkDoubleArray> pos;
        vtkNew<vtkStringArray> labels;
        char text[32];
        for (uint32_t i = 0; i < tick_count; i++) {
            double v = ticks[i];
            if (!std::isfinite(v) || v < range[0] || v > range[1] || (log && v <= 0.0))
                continue;
            pos->InsertNextValue(log ? std::log10(v) : v);
            snprintf(text, sizeof text, "%g", v);
            labels->InsertNextValue(text);
        }
        custom = pos->GetNumberOfTuples() > 0;
        if (custom)
            axis->SetCustomTickPositions(pos, labels);
    }
    if (log && !custom) {
        vtkNew<vtkDoubleArray> pos;
        vtkNew<vtkStringArray> labels;
        log_ticks(range[0], range[1], dejavu, pos, labels);
        axis->SetCustomTickPositions(pos, labels);
    }
    style_text(axis->GetTitleProperties(), 14, true, dejavu);
    style_text(axis->GetLabelProperties(), 12, false, dejavu);
    axis->GetGridPen()->SetColor(220, 220, 220, 255);
}

/* Both axis ranges: the extent of the drawn points and error bars. */
void ranges(const gi_chart_desc &d, const gi_chart_series *series, uint32_t n, double xr[2],
            double yr[2])
{
    double lo[2] = {HUGE_VAL, HUGE_VAL}, hi[2] = {-HUGE_VAL, -HUGE_VAL};
    auto take = [&](int axis, double v) {
        if (bar_end_ok(v, axis ? d.log_y : d.log_x))
            lo[axis] = std::min(lo[axis], v), hi[axis] = std::max(hi[axis], v);
    };
    for (uint32_t k = 0; k < n; k++) {
        const gi_chart_series &s = series[k];
        for (uint32_t i = 0; i < s.count; i++)
            if (kept(d, s, i)) {
                take(0, s.x[i]);
                take(1, s.y[i]);
                if (s.x_lo && s.x_hi && bar_end_ok(s.x_lo[i], d.log_x) &&
                    bar_end_ok(s.x_hi[i], d.log_x))
                    take(0, s.x_lo[i]), take(0, s.x_hi[i]);
                if (s.y_lo && s.y_hi && bar_end_ok(s.y_lo[i], d.log_y) &&
                    bar_end_ok(s.y_hi[i], d.log_y))
                    take(1, s.y_lo[i]), take(1, s.y_hi[i]);
            }
    }
    axis_range(lo[0], hi[0], d.log_x, false, xr);
    axis_range(lo[1], hi[1], d.log_y, true, yr);
}

/* Draws the chart and, when `file` is not NULL, writes it there as PNG.
 * `what` starts every error message (the destination path). */
gi_result render(const gi_chart_desc &d, const gi_chart_series *series, uint32_t n,
                 std::vector<unsigned char> *png, gi_error *err, const char *what)
{
    uint32_t w = d.width ? d.width : default_width;
    uint32_t h = d.height ? d.height : default_height;
    output_scope out;
    egl_scope egl;
    std::string why;
    if (!egl.open(why))
        return gi_error_set(err, GI_ERR_UNSUPPORTED,
                            "%s: no headless OpenGL context for charts (%s)", what, why.c_str());

    vtkNew<egl_window> window;
    window->SetOwnContext(0);
    window->SetIsCurrent(true);
    window->SetReadyForRendering(true);
    window->SetSupportsOpenGL(1);
    window->SetOffScreenRendering(1);
    window->SetFrameBlitModeToNoBlit(); /* no default framebuffer on a surfaceless context */
    window->SetSize(static_cast<int>(w), static_cast<int>(h));
    /* Multisampled lines; fewer samples on huge charts (memory: samples x 8 bytes a pixel). */
    window->SetMultiSamples(uint64_t(w) * h <= (1u << 22) ? 8 : 2);
    window->InitializeFromCurrentContext();
    if (!window->init_error.empty())
        return gi_error_set(err, GI_ERR_UNSUPPORTED, "%s: %s", what, window->init_error.c_str());

    vtkNew<vtkContextView> view;
    view->SetRenderWindow(window);
    view->GetRenderer()->SetBackground(1.0, 1.0, 1.0);

    vtkNew<vtkChartXY> chart;
    view->GetScene()->AddItem(chart);
    const char *title = d.title ? d.title : "";
    chart->SetTitle(title);
    bool dejavu = have_dejavu();
    style_text(chart->GetTitleProperties(), 17, true, dejavu);
    double xr[2], yr[2];
    ranges(d, series, n, xr, yr);
    set_axis(chart->GetAxis(vtkAxis::BOTTOM), d.x_label, d.log_x, xr, dejavu, d.x_ticks,
             d.x_tick_count);
    set_axis(chart->GetAxis(vtkAxis::LEFT), d.y_label, d.log_y, yr, dejavu, nullptr, 0);
    for (uint32_t k = 0, refs = 0; k < n; k++) {
        add_series(chart, d, series[k], k, refs, *title ? title : what);
        refs += series[k].style == GI_CHART_REFERENCE;
    }
    chart->SetRenderEmpty(true); /* axes and title even without a point */
    chart->SetAutoAxes(false);
    chart->GetAxis(vtkAxis::TOP)->SetVisible(false);
    chart->GetAxis(vtkAxis::RIGHT)->SetVisible(false);
    chart->SetShowLegend(n > 0);
    style_text(chart->GetLegend()->GetLabelProperties(), 12, false, dejavu);
    /* Outside the plot area, on its right: a legend inside would hide data
     * wherever the curves happen to run. */
    chart->GetLegend()->SetInline(false);
    chart->GetLegend()->SetHorizontalAlignment(vtkChartLegend::RIGHT);
    chart->GetLegend()->SetVerticalAlignment(vtkChartLegend::TOP);
    /* No frame: VTK puts the legend flush with the picture's right edge. */
    chart->GetLegend()->GetPen()->SetLineType(vtkPen::NO_PEN);
    chart->GetLegend()->GetBrush()->SetOpacity(0);

    window->Render();
    vtkNew<vtkWindowToImageFilter> grab;
    grab->SetInput(window);
    grab->SetInputBufferTypeToRGB();
    grab->ReadFrontBufferOff(); /* the back buffer is VTK's own framebuffer object */
    grab->Update();
    if (!out.capture->first_error.empty())
        return gi_error_set(err, GI_ERR_GL, "%s: VTK: %s", what, out.capture->first_error.c_str());
    int *dims = grab->GetOutput()->GetDimensions();
    if (dims[0] != static_cast<int>(w) || dims[1] != static_cast<int>(h))
        return gi_error_set(err, GI_ERR_GL, "%s: VTK drew %dx%d pixels instead of %ux%u", what,
                            dims[0], dims[1], w, h);
    if (!png)
        return GI_OK;

    /* Encoded in memory: the file itself is written by the core's atomic
     * writer, which checks every write (VTK's does not see a full disk). */
    vtkNew<vtkPNGWriter> writer;
    writer->WriteToMemoryOn();
    writer->SetInputConnection(grab->GetOutputPort());
    writer->Write();
    vtkUnsignedCharArray *result = writer->GetResult();
    if (writer->GetErrorCode() != vtkErrorCode::NoError || !out.capture->first_error.empty() ||
        !result || result->GetNumberOfValues() <= 0)
        return gi_error_set(err, GI_ERR_IO, "%s: PNG encoding failed: %s", what,
                            !out.capture->first_error.empty()
                                ? out.capture->first_error.c_str()
                                : vtkErrorCode::GetStringFromErrorCode(
                                      static_cast<unsigned long>(writer->GetErrorCode())));
    const unsigned char *bytes = result->GetPointer(0);
    png->assign(bytes, bytes + result->GetNumberOfValues());
    return GI_OK;
}

bool ends_with_png(const char *path)
{
    size_t n = strlen(path);
    if (n < 4)
        return false;
    const char *e = path + n - 4;
    return e[0] == '.' && (e[1] | 0x20) == 'p' && (e[2] | 0x20) == 'n' && (e[3] | 0x20) == 'g';
}

gi_result validate(const gi_chart_desc &d, const gi_chart_series *series, uint32_t n,
                   const char *what, gi_error *err)
{
    if (d.width > max_side || d.height > max_side)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "%s: chart size %ux%u is larger than %u pixels a side", what, d.width,
                            d.height, max_side);
    if (n > 0 && !series)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: %u series but no array", what, n);
    if (d.x_tick_count > 0 && !d.x_ticks)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: %u x ticks but no array", what,
                            d.x_tick_count);
    for (uint32_t k = 0; k < n; k++) {
        const gi_chart_series &s = series[k];
        if (s.style != GI_CHART_LINE_MARKERS && s.style != GI_CHART_MARKERS &&
            s.style != GI_CHART_DASHED && s.style != GI_CHART_THIN && s.style != GI_CHART_REFERENCE)
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                "%s: series %u ('%s'): unknown style %d", what, k + 1,
                                label_of(s, k).c_str(), s.style);
        if (s.color < 0)
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                "%s: series %u ('%s'): colour index %d < 0", what, k + 1,
                                label_of(s, k).c_str(), s.color);
        if (s.count > 0 && (!s.x || !s.y))
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                "%s: series %u ('%s'): %u points but no x or y array", what, k + 1,
                                label_of(s, k).c_str(), s.count);
    }
    return GI_OK;
}

/* Encodes the chart in memory, then writes it with the core's one atomic
 * writer (cache.h: gi_file_write_atomic: temporary file, checked writes,
 * fsync, rename), so that a failed write never leaves a file. */
gi_result write_png(const char *path, const gi_chart_desc &d, const gi_chart_series *series,
                    uint32_t n, gi_error *err)
{
    std::vector<unsigned char> png;
    gi_result r = render(d, series, n, &png, err, path);
    if (r != GI_OK)
        return r;
    return gi_file_write_atomic(path, png.data(), png.size(), err);
}

} // namespace

extern "C" gi_result gi_chart_write_png(const char *path, const gi_chart_desc *desc,
                                        const gi_chart_series *series, uint32_t n, gi_error *err)
{
    if (!path || !*path)
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "chart: no output path");
    if (!ends_with_png(path))
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "%s: a chart is written as .png", path);
    gi_chart_desc d{};
    if (desc)
        d = *desc;
    gi_result r = validate(d, series, n, path, err);
    if (r != GI_OK)
        return r;
    try {
        std::lock_guard<std::mutex> lock(chart_mutex);
        return write_png(path, d, series, n, err);
    } catch (const std::bad_alloc &) {
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    } catch (const std::exception &e) {
        return gi_error_set(err, GI_ERR_GL, "%s: %s", path, e.what());
    } catch (...) {
        return gi_error_set(err, GI_ERR_GL, "%s: unknown exception in VTK", path);
    }
}

extern "C" gi_result gi_chart_available(gi_error *err)
{
    static const double x[] = {1.0, 10.0}, y[] = {1.0, 0.1};
    gi_chart_series s = {"probe", x,       y,       2,       GI_CHART_LINE_MARKERS,
                         0,       nullptr, nullptr, nullptr, nullptr};
    gi_chart_desc d = {"probe", "x", "y", 1, 1, 64, 48, nullptr, 0};
    try {
        std::lock_guard<std::mutex> lock(chart_mutex);
        gi_result r = render(d, &s, 1, nullptr, err, "charts");
        return r == GI_OK ? GI_OK : GI_ERR_UNSUPPORTED;
    } catch (const std::bad_alloc &) {
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "charts: out of memory");
    } catch (const std::exception &e) {
        return gi_error_set(err, GI_ERR_UNSUPPORTED, "charts: %s", e.what());
    } catch (...) {
        return gi_error_set(err, GI_ERR_UNSUPPORTED, "charts: unknown exception in VTK");
    }
}

extern "C" void gi_chart_axis_ranges(const gi_chart_desc *desc, const gi_chart_series *series,
                                     uint32_t n, double x_range[2], double y_range[2])
{
    gi_chart_desc d{};
    if (desc)
        d = *desc;
    ranges(d, series, series ? n : 0, x_range, y_range);
}

extern "C" uint32_t gi_chart_points_kept(const gi_chart_desc *desc, const gi_chart_series *s)
{
    if (!s || !s->x || !s->y)
        return 0;
    gi_chart_desc d{};
    if (desc)
        d = *desc;
    uint32_t count = 0;
    for (uint32_t i = 0; i < s->count; i++)
        count += kept(d, *s, i) ? 1u : 0u;
    return count;
}
