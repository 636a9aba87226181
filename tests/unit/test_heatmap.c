/* Heat maps (harness/metrics/heatmap.h): colour maps, the built-in font, layout, and
 * that a written PNG shows the colour map's sRGB colours. */
#define _POSIX_C_SOURCE 200809L /* mkdtemp */
#include "check.h"
#include "heatmap.h"

#include "gi/tonemap.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static const float *px(const gi_image *img, uint32_t x, uint32_t y)
{
    return img->rgba + ((size_t)y * img->width + x) * 4;
}

static void test_colormaps(void)
{
    float c[3];
    /* Ends of matplotlib's tables. */
    gi_colormap_srgb(GI_COLORMAP_VIRIDIS, 0.0f, c);
    CHECK_NEAR(c[0], 0.267004, 1e-6);
    CHECK_NEAR(c[2], 0.329415, 1e-6);
    gi_colormap_srgb(GI_COLORMAP_VIRIDIS, 1.0f, c);
    CHECK_NEAR(c[0], 0.993248, 1e-6);
    CHECK_NEAR(c[1], 0.906157, 1e-6);
    gi_colormap_srgb(GI_COLORMAP_MAGMA, 0.0f, c);
    CHECK(c[0] < 0.01f && c[1] < 0.01f && c[2] < 0.02f);
    gi_colormap_srgb(GI_COLORMAP_MAGMA, 1.0f, c);
    CHECK_NEAR(c[1], 0.991438, 1e-6);
    /* Clamped outside [0, 1]; NaN is the low end. */
    float lo[3], hi[3];
    gi_colormap_srgb(GI_COLORMAP_VIRIDIS, -3.0f, lo);
    gi_colormap_srgb(GI_COLORMAP_VIRIDIS, 0.0f, c);
    CHECK(memcmp(lo, c, sizeof c) == 0);
    gi_colormap_srgb(GI_COLORMAP_VIRIDIS, NAN, lo);
    CHECK(memcmp(lo, c, sizeof c) == 0);
    gi_colormap_srgb(GI_COLORMAP_VIRIDIS, 7.0f, hi);
    gi_colormap_srgb(GI_COLORMAP_VIRIDIS, 1.0f, c);
    CHECK(memcmp(hi, c, sizeof c) == 0);
    /* Both maps rise in lightness: compare the Rec. 709 luma of the ends
     * and the middle. */
    for (int m = 0; m < 2; m++) {
        float prev = -1.0f;
        for (int k = 0; k <= 16; k++) {
            gi_colormap_srgb((gi_colormap)m, (float)k / 16.0f, c);
            float luma = 0.2126f * gi_srgb_decode(c[0]) + 0.7152f * gi_srgb_decode(c[1]) +
                         0.0722f * gi_srgb_decode(c[2]);
            CHECK_MSG(luma > prev, "map %d step %d", m, k);
            prev = luma;
        }
    }
}

static void test_font(void)
{
    /* '1': a stem in the middle column, a foot across. */
    CHECK(gi_heatmap_glyph_pixel('1', 1, 0) && !gi_heatmap_glyph_pixel('1', 0, 0));
    CHECK(gi_heatmap_glyph_pixel('1', 0, 4) && gi_heatmap_glyph_pixel('1', 2, 4));
    /* '.' only bottom middle */
    int dots = 0;
    for (int r = 0; r < 5; r++)
        for (int c = 0; c < 3; c++)
            dots += gi_heatmap_glyph_pixel('.', c, r);
    CHECK(dots == 1 && gi_heatmap_glyph_pixel('.', 1, 4));
    /* Every digit is drawn and differs from every other. */
    for (char a = '0'; a <= '9'; a++) {
        int set = 0;
        for (int r = 0; r < 5; r++)
            for (int c = 0; c < 3; c++)
                set += gi_heatmap_glyph_pixel(a, c, r);
        CHECK(set >= 5);
        for (char b = a + 1; b <= '9'; b++) {
            int differ = 0;
            for (int r = 0; r < 5; r++)
                for (int c = 0; c < 3; c++)
                    differ |= gi_heatmap_glyph_pixel(a, c, r) != gi_heatmap_glyph_pixel(b, c, r);
            CHECK_MSG(differ, "'%c' and '%c' look alike", a, b);
        }
    }
    CHECK(gi_heatmap_glyph_pixel('e', 0, 0) == gi_heatmap_glyph_pixel('E', 0, 0));
    CHECK(!gi_heatmap_glyph_pixel('#', 1, 1)); /* not in the font: blank */
    CHECK(!gi_heatmap_glyph_pixel('8', 3, 0) && !gi_heatmap_glyph_pixel('8', 0, 5));
}

static void test_render(void)
{
    /* 8x4 map on the default log scale 1e-3..10: 1e-3 is the bottom colour,
     * 10 the top, 0.1 half way (two of four decades), NaN grey. */
    float v[32];
    for (int i = 0; i < 32; i++)
        v[i] = 0.1f;
    v[0] = 1e-3f;
    v[1] = 10.0f;
    v[2] = 0.0f; /* below the range: bottom colour */
    v[3] = NAN;
    v[4] = 1e6f; /* above: top colour */
    gi_heatmap_opts o = {GI_COLORMAP_VIRIDIS, 1, 0, 0, "REL ERR"};
    gi_error err;
    gi_image *img = gi_heatmap_render(v, 8, 4, &o, &err);
    CHECK_MSG(img != NULL, "%s", err.text);
    if (!img)
        return;
    CHECK(img->width > 8 + 20 && img->height >= 64); /* room for the bar and labels */
    float c[3];
    gi_colormap_srgb(GI_COLORMAP_VIRIDIS, 0.0f, c);
    for (int k = 0; k < 3; k++) {
        CHECK_NEAR(px(img, 0, 0)[k], gi_srgb_decode(c[k]), 1e-6);
        CHECK_NEAR(px(img, 2, 0)[k], gi_srgb_decode(c[k]), 1e-6);
    }
    gi_colormap_srgb(GI_COLORMAP_VIRIDIS, 1.0f, c);
    for (int k = 0; k < 3; k++) {
        CHECK_NEAR(px(img, 1, 0)[k], gi_srgb_decode(c[k]), 1e-6);
        CHECK_NEAR(px(img, 4, 0)[k], gi_srgb_decode(c[k]), 1e-6);
    }
    gi_colormap_srgb(GI_COLORMAP_VIRIDIS, 0.5f, c);
    for (int k = 0; k < 3; k++)
        CHECK_NEAR(px(img, 5, 2)[k], gi_srgb_decode(c[k]), 1e-5);
    CHECK_NEAR(px(img, 3, 0)[0], gi_srgb_decode(0.5f), 1e-6); /* NaN: grey */
    CHECK(px(img, 3, 0)[3] == 1.0f);

    /* Right of the map: a colour strip running from the top colour (upper
     * rows) to the bottom colour, and black label pixels beyond it. */
    int strip_x = -1;
    for (uint32_t x = 8; x < img->width && strip_x < 0; x++) {
        const float *p = px(img, x, img->height / 2);
        if (!(p[0] == 1.0f && p[1] == 1.0f && p[2] == 1.0f) &&
            !(p[0] == 0.0f && p[1] == 0.0f && p[2] == 0.0f))
            strip_x = (int)x;
    }
    CHECK(strip_x > 8);
    if (strip_x > 8) {
        /* scan the strip's column for its extent */
        uint32_t top = 0, bottom = 0;
        for (uint32_t y = 0; y < img->height; y++) {
            const float *p = px(img, (uint32_t)strip_x + 1, y);
            int coloured = !(p[0] == p[1] && p[1] == p[2]);
            if (coloured && !top)
                top = y;
            if (coloured)
                bottom = y;
        }
        CHECK(bottom > top + 32);
        gi_colormap_srgb(GI_COLORMAP_VIRIDIS, 1.0f, c);
        CHECK_NEAR(px(img, (uint32_t)strip_x + 1, top)[1], gi_srgb_decode(c[1]), 1e-6);
        gi_colormap_srgb(GI_COLORMAP_VIRIDIS, 0.0f, c);
        CHECK_NEAR(px(img, (uint32_t)strip_x + 1, bottom)[1], gi_srgb_decode(c[1]), 1e-6);
    }
    uint64_t black = 0;
    for (uint32_t y = 0; y < img->height; y++)
        for (uint32_t x = (uint32_t)(strip_x > 0 ? strip_x : 8) + 12; x < img->width; x++)
            black += px(img, x, y)[0] == 0.0f && px(img, x, y)[1] == 0.0f;
    CHECK_MSG(black > 5 * 10, "%llu label pixels", (unsigned long long)black); /* five labels */

    /* Written as PNG it shows the colour map's 8-bit sRGB colours. */
    char dir[] = "/tmp/gi_test_heatmap_XXXXXX", path[64];
    CHECK(mkdtemp(dir) != NULL);
    snprintf(path, sizeof path, "%s/map.png", dir);
    CHECK_MSG(gi_image_write(path, img, NULL, &err) == GI_OK, "%s", err.text);
    gi_image *back = gi_image_read(path, &err);
    CHECK_MSG(back != NULL, "%s", err.text);
    if (back) {
        gi_colormap_srgb(GI_COLORMAP_VIRIDIS, 1.0f, c);
        for (int k = 0; k < 3; k++)
            CHECK_NEAR(px(back, 1, 0)[k] * 255.0f, roundf(c[k] * 255.0f), 1e-3);
        CHECK_NEAR(px(back, 3, 0)[0] * 255.0f, 128.0f, 1e-3); /* sRGB 0.5 */
        gi_image_free(back);
    }
    unlink(path);
    rmdir(dir);
    gi_image_free(img);

    /* Linear scale, magma, bigger image: bigger text and still a bar. */
    float *big = malloc(300 * 300 * sizeof *big);
    for (int i = 0; i < 300 * 300; i++)
        big[i] = (float)(i % 300) / 299.0f;
    gi_heatmap_opts lin = {GI_COLORMAP_MAGMA, 0, 0.0f, 1.0f, "FLIP"};
    img = gi_heatmap_render(big, 300, 300, &lin, &err);
    CHECK(img && img->height == 300 && img->width > 300);
    if (img) {
        gi_colormap_srgb(GI_COLORMAP_MAGMA, 1.0f, c);
        CHECK_NEAR(px(img, 299, 7)[1], gi_srgb_decode(c[1]), 1e-6);
        gi_image_free(img);
    }
    free(big);

    /* Bad ranges. */
    gi_heatmap_opts bad = {GI_COLORMAP_VIRIDIS, 1, -1.0f, 1.0f, NULL};
    CHECK(gi_heatmap_render(v, 8, 4, &bad, &err) == NULL && strstr(err.text, "range"));
    bad.log_scale = 0;
    bad.lo = 2.0f;
    CHECK(gi_heatmap_render(v, 8, 4, &bad, &err) == NULL);
}

int main(void)
{
    test_colormaps();
    test_font();
    test_render();
    return gi_test_finish();
}
