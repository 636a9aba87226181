/* Heat maps with a colour bar, tick labels in a built-in 3x5 font (no font
 * library), colours from small tables of matplotlib's viridis and magma. */
#include "heatmap.h"

#include "gi/tonemap.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

/* 17 samples (entries 0, 16, ..., 240, 255 of the 256-entry tables) of
 * matplotlib's perceptually uniform maps by Smith, van der Walt and Firing,
 * released under CC0. sRGB values. */
static const float VIRIDIS[17][3] = {
    {0.267004f, 0.004874f, 0.329415f}, {0.282327f, 0.094955f, 0.417331f},
    {0.278826f, 0.175490f, 0.483397f}, {0.258965f, 0.251537f, 0.524736f},
    {0.229739f, 0.322361f, 0.545706f}, {0.199430f, 0.387607f, 0.554642f},
    {0.172719f, 0.448791f, 0.557885f}, {0.149039f, 0.508051f, 0.557250f},
    {0.127568f, 0.566949f, 0.550556f}, {0.120638f, 0.625828f, 0.533488f},
    {0.157851f, 0.683765f, 0.501686f}, {0.246070f, 0.738910f, 0.452024f},
    {0.369214f, 0.788888f, 0.382914f}, {0.515992f, 0.831158f, 0.294279f},
    {0.678489f, 0.863742f, 0.189503f}, {0.845561f, 0.887322f, 0.099702f},
    {0.993248f, 0.906157f, 0.143936f},
};
static const float MAGMA[17][3] = {
    {0.001462f, 0.000466f, 0.013866f}, {0.039608f, 0.031090f, 0.133515f},
    {0.113094f, 0.065492f, 0.276784f}, {0.211718f, 0.061992f, 0.418647f},
    {0.316654f, 0.071690f, 0.485380f}, {0.414709f, 0.110431f, 0.504662f},
    {0.512831f, 0.148179f, 0.507648f}, {0.613617f, 0.181811f, 0.498536f},
    {0.716387f, 0.214982f, 0.475290f}, {0.816914f, 0.255895f, 0.436461f},
    {0.904281f, 0.319610f, 0.388137f}, {0.960949f, 0.418323f, 0.359630f},
    {0.986700f, 0.535582f, 0.382210f}, {0.996096f, 0.653659f, 0.446213f},
    {0.996898f, 0.769591f, 0.534892f}, {0.992440f, 0.884330f, 0.640099f},
    {0.987053f, 0.991438f, 0.749504f},
};

void gi_colormap_srgb(gi_colormap map, float t, float srgb[3])
{
    const float(*tab)[3] = map == GI_COLORMAP_MAGMA ? MAGMA : VIRIDIS;
    if (!(t > 0.0f))
        t = 0.0f;
    if (t > 1.0f)
        t = 1.0f;
    float u = t * 16.0f;
    int i = (int)u;
    if (i > 15)
        i = 15;
    float f = u - (float)i;
    for (int c = 0; c < 3; c++)
        srgb[c] = tab[i][c] + f * (tab[i + 1][c] - tab[i][c]);
}

/* ---- font: 5 rows of 3 bits, bit 2 = left column ---- */

typedef struct glyph {
    char ch;
    unsigned char rows[5];
} glyph;

static const glyph FONT[] = {
    {'0', {7, 5, 5, 5, 7}}, {'1', {2, 6, 2, 2, 7}}, {'2', {7, 1, 7, 4, 7}}, {'3', {7, 1, 7, 1, 7}},
    {'4', {5, 5, 7, 1, 1}}, {'5', {7, 4, 7, 1, 7}}, {'6', {7, 4, 7, 5, 7}}, {'7', {7, 1, 1, 1, 1}},
    {'8', {7, 5, 7, 5, 7}}, {'9', {7, 5, 7, 1, 7}}, {'A', {2, 5, 7, 5, 5}}, {'B', {6, 5, 6, 5, 6}},
    {'C', {3, 4, 4, 4, 3}}, {'D', {6, 5, 5, 5, 6}}, {'E', {7, 4, 6, 4, 7}}, {'F', {7, 4, 6, 4, 4}},
    {'G', {3, 4, 5, 5, 3}}, {'H', {5, 5, 7, 5, 5}}, {'I', {7, 2, 2, 2, 7}}, {'J', {1, 1, 1, 5, 2}},
    {'K', {5, 5, 6, 5, 5}}, {'L', {4, 4, 4, 4, 7}}, {'M', {5, 7, 7, 5, 5}}, {'N', {6, 5, 5, 5, 5}},
    {'O', {2, 5, 5, 5, 2}}, {'P', {6, 5, 6, 4, 4}}, {'Q', {2, 5, 5, 6, 3}}, {'R', {6, 5, 6, 5, 5}},
    {'S', {3, 4, 2, 1, 6}}, {'T', {7, 2, 2, 2, 2}}, {'U', {5, 5, 5, 5, 7}}, {'V', {5, 5, 5, 5, 2}},
    {'W', {5, 5, 7, 7, 5}}, {'X', {5, 5, 2, 5, 5}}, {'Y', {5, 5, 2, 2, 2}}, {'Z', {7, 1, 2, 4, 7}},
    {'.', {0, 0, 0, 0, 2}}, {'-', {0, 0, 7, 0, 0}}, {'+', {0, 2, 7, 2, 0}}, {'%', {5, 1, 2, 4, 5}},
    {'(', {1, 2, 2, 2, 1}}, {')', {4, 2, 2, 2, 4}}, {'/', {1, 1, 2, 4, 4}}, {' ', {0, 0, 0, 0, 0}},
};

static const glyph *find_glyph(char ch)
{
    ch = (char)toupper((unsigned char)ch);
    for (size_t i = 0; i < sizeof FONT / sizeof FONT[0]; i++)
        if (FONT[i].ch == ch)
            return &FONT[i];
    return NULL;
}

int gi_heatmap_glyph_pixel(char ch, int col, int row)
{
    const glyph *g = find_glyph(ch);
    if (!g || col < 0 || col > 2 || row < 0 || row > 4)
        return 0;
    return (g->rows[row] >> (2 - col)) & 1;
}

/* ---- drawing on a linear RGBA canvas ---- */

typedef struct canvas {
    gi_image *img;
} canvas;

static void put(canvas *cv, int64_t x, int64_t y, const float lin[3])
{
    if (x < 0 || y < 0 || x >= cv->img->width || y >= cv->img->height)
        return;
    float *p = cv->img->rgba + ((size_t)y * cv->img->width + (size_t)x) * 4;
    p[0] = lin[0];
    p[1] = lin[1];
    p[2] = lin[2];
    p[3] = 1.0f;
}

static void rect(canvas *cv, int64_t x0, int64_t y0, int64_t w, int64_t h, const float lin[3])
{
    for (int64_t y = y0; y < y0 + h; y++)
        for (int64_t x = x0; x < x0 + w; x++)
            put(cv, x, y, lin);
}

/* Text with its top-left corner at (x, y), each font pixel s x s. */
static void text(canvas *cv, int64_t x, int64_t y, int s, const char *str, const float lin[3])
{
    for (; *str; str++, x += 4 * s)
        for (int row = 0; row < 5; row++)
            for (int col = 0; col < 3; col++)
                if (gi_heatmap_glyph_pixel(*str, col, row))
                    rect(cv, x + col * s, y + row * s, s, s, lin);
}

static void srgb_to_linear3(const float srgb[3], float lin[3])
{
    for (int c = 0; c < 3; c++)
        lin[c] = gi_srgb_decode(srgb[c]);
}

/* ---- the heat map ---- */

typedef struct scale {
    int log;
    double lo, hi;
} scale;

static float scale_t(const scale *sc, double v)
{
    double t;
    if (sc->log)
        t = v > 0.0 ? (log10(v) - log10(sc->lo)) / (log10(sc->hi) - log10(sc->lo)) : 0.0;
    else
        t = (v - sc->lo) / (sc->hi - sc->lo);
    return (float)(t > 0.0 ? (t < 1.0 ? t : 1.0) : 0.0);
}

#define MAX_TICKS 16

static int ticks_of(const scale *sc, double *tick)
{
    int n = 0;
    if (!sc->log) {
        for (int k = 0; k <= 4; k++)
            tick[n++] = sc->lo + k * (sc->hi - sc->lo) / 4.0;
        return n;
    }
    /* lo and hi come as floats: 1e-3f is 1.0000000475e-3, so allow a little slack */
    int d0 = (int)ceil(log10(sc->lo) - 1e-5), d1 = (int)floor(log10(sc->hi) + 1e-5);
    if (d1 < d0) { /* no decade inside: label the ends */
        tick[n++] = sc->lo;
        tick[n++] = sc->hi;
        return n;
    }
    int step = 1 + (d1 - d0) / (MAX_TICKS - 1);
    for (int d = d0; d <= d1 && n < MAX_TICKS; d += step)
        tick[n++] = pow(10.0, d);
    return n;
}

static void label_of(double v, char *buf, size_t size)
{
    snprintf(buf, size, "%g", v);
}

gi_image *gi_heatmap_render(const float *values, uint32_t width, uint32_t height,
                            const gi_heatmap_opts *opts, gi_error *err)
{
    gi_heatmap_opts defaults = {0};
    const gi_heatmap_opts *o = opts ? opts : &defaults;
    scale sc = {o->log_scale != 0, o->lo, o->hi};
    if (o->lo == 0.0f && o->hi == 0.0f) {
        sc.lo = sc.log ? GI_HEATMAP_RELERR_LO : 0.0;
        sc.hi = sc.log ? GI_HEATMAP_RELERR_HI : 1.0;
    }
    if (!isfinite(sc.lo) || !isfinite(sc.hi) || !(sc.hi > sc.lo) || (sc.log && !(sc.lo > 0.0))) {
        gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "heat map: range %g..%g is not increasing%s",
                     sc.lo, sc.hi, sc.log ? " and positive" : "");
        return NULL;
    }
    if (width == 0 || height == 0 || width > 65536 || height > 65536) {
        gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "heat map: bad size %ux%u", width, height);
        return NULL;
    }

    double tick[MAX_TICKS];
    int nt = ticks_of(&sc, tick);
    size_t label_chars = 0;
    for (int i = 0; i < nt; i++) {
        char buf[32];
        label_of(tick[i], buf, sizeof buf);
        if (strlen(buf) > label_chars)
            label_chars = strlen(buf);
    }
    const char *title = o->title && *o->title ? o->title : NULL;
    size_t title_chars = title ? strlen(title) : 0;
    if (title_chars > 64)
        title_chars = 64;

    /* Layout, in units of the font pixel s (larger for larger images). */
    int s = (int)(height / 128);
    s = s < 1 ? 1 : s > 4 ? 4 : s;
    int64_t m = 4 * s;                                     /* margin */
    int64_t bar_x = (int64_t)width + 2 * m, bar_w = 8 * s; /* colour strip */
    int64_t tick_len = 2 * s, label_x = bar_x + bar_w + tick_len + 2 * s;
    int64_t bar_top = m + (title ? 7 * s : 0) + 3 * s; /* room for half a label above */
    int64_t canvas_w = label_x + (int64_t)label_chars * 4 * s + m;
    if (title && bar_x + (int64_t)title_chars * 4 * s + m > canvas_w)
        canvas_w = bar_x + (int64_t)title_chars * 4 * s + m;
    int64_t canvas_h = (int64_t)height;
    if (canvas_h < bar_top + 64 * s + 3 * s + m)
        canvas_h = bar_top + 64 * s + 3 * s + m;
    int64_t bar_bottom = canvas_h - m - 3 * s - 1;

    gi_image *img = gi_image_create((uint32_t)canvas_w, (uint32_t)canvas_h);
    if (!img) {
        gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "heat map: out of memory for %lldx%lld pixels",
                     (long long)canvas_w, (long long)canvas_h);
        return NULL;
    }
    canvas cv = {img};
    const float white[3] = {1, 1, 1}, black[3] = {0, 0, 0};
    float grey[3];
    const float grey_srgb[3] = {0.5f, 0.5f, 0.5f};
    srgb_to_linear3(grey_srgb, grey);
    rect(&cv, 0, 0, canvas_w, canvas_h, white);

    for (uint32_t y = 0; y < height; y++)
        for (uint32_t x = 0; x < width; x++) {
            float v = values[(size_t)y * width + x], srgb[3], lin[3];
            if (isnan(v)) {
                put(&cv, x, y, grey);
                continue;
            }
            gi_colormap_srgb(o->colormap, scale_t(&sc, v), srgb);
            srgb_to_linear3(srgb, lin);
            put(&cv, x, y, lin);
        }

    /* The strip, framed, value rising upwards. */
    rect(&cv, bar_x - 1, bar_top - 1, bar_w + 2, bar_bottom - bar_top + 3, black);
    for (int64_t y = bar_top; y <= bar_bottom; y++) {
        float srgb[3], lin[3];
        gi_colormap_srgb(o->colormap, (float)(bar_bottom - y) / (float)(bar_bottom - bar_top),
                         srgb);
        srgb_to_linear3(srgb, lin);
        rect(&cv, bar_x, y, bar_w, 1, lin);
    }
    int64_t thick = s > 1 ? s / 2 : 1;
    for (int i = 0; i < nt; i++) {
        int64_t y =
            bar_bottom - (int64_t)lround(scale_t(&sc, tick[i]) * (double)(bar_bottom - bar_top));
        rect(&cv, bar_x + bar_w, y - thick / 2, tick_len, thick, black);
        char buf[32];
        label_of(tick[i], buf, sizeof buf);
        text(&cv, label_x, y - (5 * s) / 2, s, buf, black);
    }
    if (title) {
        char t[65];
        snprintf(t, sizeof t, "%s", title);
        text(&cv, bar_x, m, s, t, black);
    }
    return img;
}
