/* Image files and statistics (image.h): exact EXR/PFM round trips, PNG
 * within one 8-bit step of the tonemapped value, EXR layers, the PFM byte
 * layout against the spec, atomic writes and error messages, cropped
 * files placed in their display window (OpenEXR and OpenImageIO readers). */
#define _POSIX_C_SOURCE 200809L /* mkdtemp */
#include <dirent.h>
#include <sys/stat.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "gi/image.h"
#include "gi/tonemap.h"

/* A per-run scratch directory under the build tree. */
static void make_dir(char *dir, size_t size)
{
    snprintf(dir, size, "%s/tests/tmp_image_XXXXXX", GI_BINARY_DIR);
    if (!mkdtemp(dir)) {
        snprintf(dir, size, "/tmp/gi_test_image_XXXXXX");
        if (!mkdtemp(dir)) {
            perror("mkdtemp");
            exit(1);
        }
    }
}

/* Deterministic test picture with HDR values, negatives and fractions. */
static gi_image *pattern(uint32_t w, uint32_t h, float seed)
{
    gi_image *img = gi_image_create(w, h);
    for (uint32_t y = 0; y < h; y++)
        for (uint32_t x = 0; x < w; x++) {
            float *p = img->rgba + ((size_t)y * w + x) * 4;
            p[0] = (float)x / (float)w + seed;
            p[1] = (float)y * 0.37f - 1.5f;
            p[2] = (float)(x * y) * 1.7f + 1e-6f * seed;
            p[3] = 0.25f + 0.5f * (float)((x + y) & 1);
        }
    return img;
}

static int same_pixels(const gi_image *a, const gi_image *b, int channels)
{
    if (a->width != b->width || a->height != b->height)
        return 0;
    for (size_t i = 0; i < (size_t)a->width * a->height; i++)
        for (int c = 0; c < channels; c++)
            if (a->rgba[i * 4 + c] != b->rgba[i * 4 + c])
                return 0;
    return 1;
}

static int count_entries(const char *dir)
{
    DIR *d = opendir(dir);
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL)
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, ".."))
            n++;
    closedir(d);
    return n;
}

static void test_exr(const char *dir)
{
    char path[1100];
    snprintf(path, sizeof path, "%s/a.exr", dir);
    gi_image *img = pattern(7, 5, 0.5f);
    gi_error err = {{0}};
    CHECK(gi_image_write(path, img, NULL, &err) == GI_OK);
    gi_image *back = gi_image_read(path, &err);
    CHECK_MSG(back != NULL, "%s", err.text);
    if (back) {
        CHECK(same_pixels(img, back, 4));
        gi_image_free(back);
    }
    /* Upper-case extension works the same. */
    snprintf(path, sizeof path, "%s/b.EXR", dir);
    CHECK(gi_image_write(path, img, NULL, &err) == GI_OK);
    gi_image_free(img);
}

static void test_pfm(const char *dir)
{
    char path[1100];
    snprintf(path, sizeof path, "%s/a.pfm", dir);
    gi_image *img = pattern(6, 4, 1.25f);
    gi_error err = {{0}};
    CHECK_MSG(gi_image_write(path, img, NULL, &err) == GI_OK, "%s", err.text);

    /* Byte layout by the spec: "PF", size, negative scale (little-endian
     * host), then rows from the bottom of the picture. */
    FILE *f = fopen(path, "rb");
    CHECK(f != NULL);
    if (f) {
        char magic[3] = {0};
        unsigned w = 0, h = 0;
        float scale = 0;
        CHECK(fscanf(f, "%2s %u %u %f", magic, &w, &h, &scale) == 4);
        fgetc(f); /* the single whitespace after the scale */
        CHECK(strcmp(magic, "PF") == 0);
        CHECK(w == 6 && h == 4);
        uint32_t one = 1;
        unsigned char lsb;
        memcpy(&lsb, &one, 1);
        CHECK(lsb == 1 ? scale < 0 : scale > 0);
        float first[3], last[3];
        CHECK(fread(first, sizeof(float), 3, f) == 3);
        CHECK(fseek(f, -(long)(3 * sizeof(float)), SEEK_END) == 0);
        CHECK(fread(last, sizeof(float), 3, f) == 3);
        const float *bottom_left = img->rgba + (size_t)(4 - 1) * 6 * 4;
        const float *top_right = img->rgba + (size_t)(6 - 1) * 4;
        for (int c = 0; c < 3; c++) {
            CHECK(first[c] == bottom_left[c]);
            CHECK(last[c] == top_right[c]);
        }
        fclose(f);
    }

    gi_image *back = gi_image_read(path, &err);
    CHECK_MSG(back != NULL, "%s", err.text);
    if (back) {
        CHECK(same_pixels(img, back, 3));
        CHECK(back->rgba[3] == 1.0f); /* PFM has no alpha */
        gi_image_free(back);
    }
    gi_image_free(img);
}

static void test_png(const char *dir)
{
    char path[1100];
    snprintf(path, sizeof path, "%s/a.png", dir);
    gi_image *img = pattern(9, 3, 0.0f);
    /* Cover the whole display range, the linear toe and a NaN. */
    for (uint32_t i = 0; i < 9; i++)
        img->rgba[i * 4] = (float)i / 16.0f;
    img->rgba[4 * 4 + 1] = 0.001f;
    img->rgba[5 * 4 + 2] = NAN;
    gi_image_write_opts opts = {.exposure = 0.5f};
    gi_error err = {{0}};
    CHECK_MSG(gi_image_write(path, img, &opts, &err) == GI_OK, "%s", err.text);
    gi_image *back = gi_image_read(path, &err);
    CHECK_MSG(back != NULL, "%s", err.text);
    if (back) {
        CHECK(back->width == 9 && back->height == 3);
        double worst = 0;
        for (size_t i = 0; i < 27; i++)
            for (int c = 0; c < 3; c++) {
                double want = gi_tonemap(img->rgba[i * 4 + c], opts.exposure);
                double d = fabs(back->rgba[i * 4 + c] - want);
                worst = d > worst ? d : worst;
            }
        /* Rounding to 8 bits costs at most half a step. */
        CHECK_MSG(worst <= 0.5 / 255.0 + 1e-6, "worst %g", worst);
        CHECK(back->rgba[5 * 4 + 2] == 0.0f);
        CHECK(back->rgba[3] == 1.0f);
        gi_image_free(back);
    }
    gi_image_free(img);
}

static void test_layers(const char *dir)
{
    char path[1100];
    snprintf(path, sizeof path, "%s/layers.exr", dir);
    gi_image *rgba = pattern(5, 4, 0.0f);
    gi_image *var = pattern(5, 4, 3.0f);
    gi_image *cnt = pattern(5, 4, -7.0f);
    const gi_image *layers[2] = {var, cnt};
    const char *names[2] = {"variance", "count"};
    gi_error err = {{0}};
    CHECK_MSG(gi_image_write_exr_layers(path, rgba, layers, names, 2, &err) == GI_OK, "%s",
              err.text);
    gi_image *a = gi_image_read(path, &err);
    gi_image *b = gi_image_read_layer(path, "variance", &err);
    gi_image *c = gi_image_read_layer(path, "count", &err);
    CHECK(a && b && c);
    if (a && b && c) {
        CHECK(same_pixels(a, rgba, 4));
        CHECK(same_pixels(b, var, 4));
        CHECK(same_pixels(c, cnt, 4));
    }
    gi_image_free(a);
    gi_image_free(b);
    gi_image_free(c);

    gi_image *missing = gi_image_read_layer(path, "albedo", &err);
    CHECK(missing == NULL);
    CHECK_MSG(strncmp(err.text, path, strlen(path)) == 0 && strstr(err.text, "albedo"), "%s",
              err.text);

    /* Mismatched layer size and duplicate names are refused. */
    gi_image *small = gi_image_create(2, 2);
    const gi_image *bad[1] = {small};
    CHECK(gi_image_write_exr_layers(path, rgba, bad, names, 1, &err) == GI_ERR_INVALID_ARGUMENT);
    const gi_image *twice[2] = {var, var};
    const char *dup[2] = {"v", "v"};
    CHECK(gi_image_write_exr_layers(path, rgba, twice, dup, 2, &err) == GI_ERR_INVALID_ARGUMENT);
    gi_image_free(small);

    /* No layers at all is a plain RGBA EXR. */
    CHECK(gi_image_write_exr_layers(path, rgba, NULL, NULL, 0, &err) == GI_OK);
    gi_image_free(rgba);
    gi_image_free(var);
    gi_image_free(cnt);
}

static void test_atomic_and_errors(const char *root)
{
    char dir[1100], path[1200];
    snprintf(dir, sizeof dir, "%s/atomic", root);
    CHECK(mkdir(dir, 0755) == 0);
    gi_image *img = pattern(4, 4, 0.0f);
    gi_error err = {{0}};
    const char *exts[3] = {"exr", "pfm", "png"};
    for (int i = 0; i < 3; i++) {
        snprintf(path, sizeof path, "%s/out.%s", dir, exts[i]);
        CHECK(gi_image_write(path, img, NULL, &err) == GI_OK);
        /* Overwriting an existing file goes through a rename as well. */
        CHECK(gi_image_write(path, img, NULL, &err) == GI_OK);
    }
    CHECK_MSG(count_entries(dir) == 3, "%d entries: a temporary file was left behind",
              count_entries(dir));

    /* Unsupported extension: a clear message and nothing written. */
    snprintf(path, sizeof path, "%s/out.xyz", dir);
    CHECK(gi_image_write(path, img, NULL, &err) == GI_ERR_INVALID_ARGUMENT);
    CHECK_MSG(strstr(err.text, "unsupported image format '.xyz' (use .exr, .pfm or .png)"), "%s",
              err.text);
    snprintf(path, sizeof path, "%s/noext", dir);
    CHECK(gi_image_write(path, img, NULL, &err) == GI_ERR_INVALID_ARGUMENT);
    CHECK(count_entries(dir) == 3);

    /* A directory that does not exist: I/O error, nothing left anywhere. */
    snprintf(path, sizeof path, "%s/no/such/dir/x.exr", dir);
    CHECK(gi_image_write(path, img, NULL, &err) == GI_ERR_IO);
    CHECK_MSG(strncmp(err.text, path, strlen(path)) == 0, "%s", err.text);

    /* Reading a missing file and a file that is not an image. */
    snprintf(path, sizeof path, "%s/missing.exr", dir);
    CHECK(gi_image_read(path, &err) == NULL);
    CHECK_MSG(strncmp(err.text, path, strlen(path)) == 0 && strstr(err.text, "No such file"), "%s",
              err.text);
    snprintf(path, sizeof path, "%s/garbage.exr", dir);
    FILE *f = fopen(path, "wb");
    fputs("this is not an OpenEXR file\n", f);
    fclose(f);
    CHECK(gi_image_read(path, &err) == NULL);
    CHECK_MSG(strncmp(err.text, path, strlen(path)) == 0 && strlen(err.text) > strlen(path) + 2,
              "%s", err.text);
    CHECK(gi_image_read(dir, &err) == NULL);
    CHECK(strstr(err.text, "directory") != NULL);
    gi_image_free(img);
}

static void test_stats(void)
{
    CHECK(gi_image_create(0, 4) == NULL);
    CHECK(gi_image_create(4, 0) == NULL);
    CHECK(gi_image_create(1u << 16, 1u << 16) == NULL);

    gi_image *img = gi_image_create(3, 2);
    for (int i = 0; i < 6; i++)
        for (int c = 0; c < 4; c++)
            img->rgba[i * 4 + c] = (float)(i + c);
    double mean[4];
    gi_image_mean(img, mean);
    for (int c = 0; c < 4; c++)
        CHECK_NEAR(mean[c], 2.5 + c, 1e-12);
    CHECK(gi_image_count_nonfinite(img) == 0);
    img->rgba[1 * 4 + 0] = NAN;
    img->rgba[1 * 4 + 2] = INFINITY; /* same pixel counts once */
    img->rgba[4 * 4 + 1] = -INFINITY;
    img->rgba[5 * 4 + 3] = NAN; /* alpha is not counted */
    CHECK(gi_image_count_nonfinite(img) == 2);

    gi_image *odd = gi_image_create(2, 3);
    for (int i = 0; i < 24; i++)
        odd->rgba[i] = (float)i;
    gi_image_flip_rows(odd);
    CHECK(odd->rgba[0] == 16.0f && odd->rgba[7] == 23.0f);
    CHECK(odd->rgba[8] == 8.0f && odd->rgba[15] == 15.0f);
    CHECK(odd->rgba[16] == 0.0f && odd->rgba[23] == 7.0f);
    gi_image_flip_rows(odd);
    for (int i = 0; i < 24; i++)
        CHECK(odd->rgba[i] == (float)i);
    gi_image_free(odd);
    gi_image_free(img);
    gi_image_free(NULL);
}

/* A cropped EXR (data window 12x10 at (5, 7) in a 32x24 display window)
 * reads as the whole display window, the data in place and zeros around
 * it; the same file as TIFF (written with the zeros by oiiotool) through
 * the OpenImageIO module reads the same. The files come from tests/data/
 * valid/images: gradient.exr = `oiiotool --pattern fill:topleft=1,0,0,1:
 * topright=0,1,0,1:bottomleft=0,0,1,1:bottomright=1,1,1,1 32x24 4 -d float
 * -o gradient.exr`, cropped.exr = `oiiotool gradient.exr --crop 12x10+5+7
 * -o cropped.exr`, cropped.tif = `oiiotool cropped.exr -d float -o
 * cropped.tif`. */
static void test_cropped(void)
{
    gi_error err = {{0}};
    gi_image *full = gi_image_read(GI_TEST_DATA "/valid/images/gradient.exr", &err);
    CHECK_MSG(full != NULL, "%s", err.text);
    gi_image *exr = gi_image_read(GI_TEST_DATA "/valid/images/cropped.exr", &err);
    CHECK_MSG(exr != NULL, "%s", err.text);
    gi_image *tif = gi_image_read(GI_TEST_DATA "/valid/images/cropped.tif", &err);
    CHECK_MSG(tif != NULL, "%s", err.text);
    if (!full || !exr || !tif)
        goto done;
    CHECK(full->width == 32 && full->height == 24);
    CHECK(exr->width == 32 && exr->height == 24 && tif->width == 32 && tif->height == 24);
    int inside_ok = 1, outside_ok = 1, tif_ok = 1;
    for (uint32_t y = 0; y < 24; y++)
        for (uint32_t x = 0; x < 32; x++)
            for (int c = 0; c < 4; c++) {
                size_t i = ((size_t)y * 32 + x) * 4 + (size_t)c;
                int inside = x >= 5 && x < 17 && y >= 7 && y < 17;
                if (inside)
                    inside_ok &= exr->rgba[i] == full->rgba[i];
                else
                    outside_ok &= exr->rgba[i] == 0.0f;
                tif_ok &= tif->rgba[i] == exr->rgba[i];
            }
    CHECK(inside_ok);
    CHECK(outside_ok);
    CHECK(tif_ok);
    CHECK(exr->rgba[((size_t)7 * 32 + 5) * 4 + 3] == 1.0f);
done:
    gi_image_free(full);
    gi_image_free(exr);
    gi_image_free(tif);
}

int main(void)
{
    char dir[1024];
    make_dir(dir, sizeof dir);
    test_stats();
    test_exr(dir);
    test_pfm(dir);
    test_png(dir);
    test_layers(dir);
    test_atomic_and_errors(dir);
    test_cropped();
    char cmd[1200];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    if (gi_test_failed == 0 && system(cmd) != 0)
        fprintf(stderr, "could not remove %s\n", dir);
    return gi_test_finish();
}
