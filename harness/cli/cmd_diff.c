/* gibench diff: error metrics of a test image against a reference, and
 * heat maps of the per-pixel errors (metrics.h, heatmap.h). */
#include "cli.h"
#include "runner.h"

#include "heatmap.h"
#include "metrics.h"

#include "gi/image.h"
#include "gi/tonemap.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct diff_opts {
    const char *test, *ref, *heatmap, *flip_map;
    int json, black;
    gi_metrics_opts m;
} diff_opts;

static int has_ext(const char *path, const char *ext)
{
    size_t n = strlen(path), e = strlen(ext);
    if (n < e)
        return 0;
    for (size_t i = 0; i < e; i++)
        if (tolower((unsigned char)path[n - e + i]) != ext[i])
            return 0;
    return 1;
}

static int parse_opts(int argc, char **argv, diff_opts *o)
{
    memset(o, 0, sizeof *o);
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--json")) {
            o->json = 1;
            continue;
        }
        if (!strcmp(a, "--black")) {
            o->black = 1;
            continue;
        }
        if (a[0] != '-' || !a[1]) {
            if (!o->test)
                o->test = a;
            else if (!o->ref)
                o->ref = a;
            else
                return cli_fail(EXIT_USAGE,
                                "diff: one test and one reference image ('%s' is a third)", a);
            continue;
        }
        if (strcmp(a, "--heatmap") && strcmp(a, "--flip-map") && strcmp(a, "--exposure") &&
            strcmp(a, "--ppd") && strcmp(a, "--dark-threshold"))
            return cli_fail(EXIT_USAGE, "diff: unknown argument '%s' (see gibench --help)", a);
        if (!v)
            return cli_fail(EXIT_USAGE, "diff: %s needs a value", a);
        i++;
        if (!strcmp(a, "--heatmap") || !strcmp(a, "--flip-map")) {
            if (!has_ext(v, ".png"))
                return cli_fail(EXIT_USAGE, "diff: %s '%s': use a .png file name", a, v);
            *(!strcmp(a, "--heatmap") ? &o->heatmap : &o->flip_map) = v;
        } else if (!strcmp(a, "--exposure")) {
            if (!cli_parse_exposure(v, &o->m.exposure))
                return cli_fail(EXIT_USAGE,
                                "diff: --exposure '%s' is not a number of stops in [-64, 64]", v);
        } else if (!strcmp(a, "--dark-threshold")) {
            if (!cli_parse_float(v, &o->m.dark_threshold) || !(o->m.dark_threshold > 0.0f) ||
                o->m.dark_threshold > 1.0f)
                return cli_fail(
                    EXIT_USAGE,
                    "diff: --dark-threshold '%s' is not a number in (0, 1] (a share of the "
                    "reference's mean luminance)",
                    v);
        } else {
            if (!cli_parse_float(v, &o->m.flip_ppd) || !(o->m.flip_ppd > 0.0f) ||
                o->m.flip_ppd > 1e4f)
                return cli_fail(EXIT_USAGE, "diff: --ppd '%s' is not a number in (0, 10000]", v);
        }
    }
    if (o->black) {
        /* The trivial answer: a black image of the reference's size. */
        if (o->ref)
            return cli_fail(EXIT_USAGE,
                            "diff: --black takes the reference image only (gibench diff --black "
                            "REFERENCE)");
        o->ref = o->test;
        o->test = NULL;
        if (!o->ref)
            return cli_fail(
                EXIT_USAGE,
                "diff: --black needs the reference image (gibench diff --black REFERENCE)");
        return EXIT_OK;
    }
    if (!o->test || !o->ref)
        return cli_fail(
            EXIT_USAGE,
            "diff: two images needed (gibench diff TEST REFERENCE [--json] [--heatmap FILE.png])");
    return EXIT_OK;
}

/* An 8-bit PNG holds display values (what gibench writes: sRGB-encoded
 * linear radiance); decode them so that every image is compared linear. */
static gi_image *read_linear(const char *path, gi_error *err)
{
    gi_image *img = gi_image_read(path, err);
    if (img && has_ext(path, ".png")) {
        size_t n = (size_t)img->width * img->height;
        for (size_t i = 0; i < n; i++)
            for (int c = 0; c < 3; c++)
                img->rgba[i * 4 + c] = gi_srgb_decode(img->rgba[i * 4 + c]);
    }
    return img;
}

static json_object *image_json(const char *path, const gi_image *img, uint64_t nonfinite)
{
    json_object *o = json_object_new_object();
    json_object_object_add(o, "path", json_object_new_string(path));
    json_object_object_add(o, "width", json_object_new_int64(img->width));
    json_object_object_add(o, "height", json_object_new_int64(img->height));
    json_object_object_add(o, "nonfinite_pixels", json_object_new_int64((int64_t)nonfinite));
    return o;
}

static void print_json(const diff_opts *o, const gi_image *t, const gi_image *r,
                       const gi_metrics *m)
{
    json_object *j = json_object_new_object();
    json_object_object_add(j, "test", image_json(o->test, t, m->nonfinite_test));
    json_object_object_add(j, "reference", image_json(o->ref, r, m->nonfinite_ref));
    runner_metrics_json_add(j, m);
    if (o->heatmap)
        json_object_object_add(j, "heatmap", json_object_new_string(o->heatmap));
    if (o->flip_map)
        json_object_object_add(j, "flip_map", json_object_new_string(o->flip_map));
    puts(json_object_to_json_string_ext(j, JSON_C_TO_STRING_PRETTY | JSON_C_TO_STRING_SPACED |
                                               JSON_C_TO_STRING_NOSLASHESCAPE));
    json_object_put(j);
}

static void print_human(const diff_opts *o, const gi_metrics *m)
{
    printf("test       %s (%ux%u, %llu non-finite pixels)\n", o->test, m->width, m->height,
           (unsigned long long)m->nonfinite_test);
    printf("reference  %s (%ux%u, %llu non-finite pixels)\n", o->ref, m->width, m->height,
           (unsigned long long)m->nonfinite_ref);
    printf("pixels     %llu compared, %llu excluded (non-finite in either image)\n",
           (unsigned long long)m->pixels, (unsigned long long)m->excluded);
    printf("rmse       %.6g\n", m->rmse);
    printf("relmse     %.6g\n", m->relmse);
    printf("mae        %.6g\n", m->mae);
    printf("psnr       %.4g dB (tonemapped, exposure %g)\n", m->psnr, (double)m->exposure);
    printf("ssim       %.6f (tonemapped luminance)\n", m->ssim);
    printf("mean_lum   %+.4g %% (test %.6g, reference %.6g)\n", m->mean_lum_diff_pct,
           m->mean_lum_test, m->mean_lum_ref);
    printf("flip       %.6f (LDR-FLIP at %.2f pixels per degree)\n", m->flip, (double)m->flip_ppd);
    printf("hdr_flip   %.6f (HDR-FLIP of the linear images, %d exposures %.4f..%.4f stops)\n",
           m->hdr_flip, m->hdr_flip_exposures, m->hdr_flip_start, m->hdr_flip_stop);
    printf("leak       %.6g of the reference's light, in its dark pixels (%.4g %% of the image: "
           "luminance "
           "below %g x its mean, the reference's own share there %.6g)\n",
           m->leaked_energy, 100.0 * m->dark_fraction, (double)m->dark_threshold,
           m->dark_energy_ref);
    if (o->heatmap)
        printf("heatmap    %s (|x - r| / (r + 0.01), log10 %g..%g, viridis)\n", o->heatmap,
               (double)GI_HEATMAP_RELERR_LO, (double)GI_HEATMAP_RELERR_HI);
    if (o->flip_map)
        printf("flip_map   %s (FLIP 0..1, magma)\n", o->flip_map);
}

/* Renders a per-pixel map and writes it; EXIT_OK or EXIT_RUN. */
static int write_map(const char *path, const float *map, uint32_t w, uint32_t h,
                     const gi_heatmap_opts *ho)
{
    gi_error err;
    gi_image *img = gi_heatmap_render(map, w, h, ho, &err);
    if (!img)
        return cli_fail(EXIT_RUN, "diff: %s: %s", path, err.text);
    gi_result r = gi_image_write(path, img, NULL, &err);
    gi_image_free(img);
    if (r)
        return cli_fail(EXIT_RUN, "diff: %s", err.text);
    return EXIT_OK;
}

int cmd_diff(int argc, char **argv)
{
    diff_opts o;
    int rc = parse_opts(argc, argv, &o);
    if (rc)
        return rc;
    gi_error err;
    gi_image *r = read_linear(o.ref, &err);
    if (!r)
        return cli_fail(EXIT_USAGE, "diff: %s", err.text);
    gi_image *t = o.black ? gi_image_create(r->width, r->height) : read_linear(o.test, &err);
    if (!t) {
        gi_image_free(r);
        return o.black ? cli_fail(EXIT_RUN, "diff: out of memory for the black image")
                       : cli_fail(EXIT_USAGE, "diff: %s", err.text);
    }
    if (o.black)
        o.test = "black";
    if (t->width != r->width || t->height != r->height) {
        rc = cli_fail(EXIT_USAGE,
                      "diff: image sizes differ: test %s is %ux%u, reference %s is %ux%u", o.test,
                      t->width, t->height, o.ref, r->width, r->height);
        goto done;
    }

    gi_metrics m;
    float *map = NULL;
    gi_result res = gi_metrics_compute(t, r, &o.m, &m, &err);
    if (res) {
        rc = cli_fail(res == GI_ERR_INVALID_ARGUMENT ? EXIT_USAGE : EXIT_RUN, "diff: %s", err.text);
        goto done;
    }
    if (o.heatmap || o.flip_map) {
        map = malloc((size_t)t->width * t->height * sizeof *map);
        if (!map) {
            rc = cli_fail(EXIT_RUN, "diff: out of memory for the heat map");
            goto done;
        }
    }
    if (o.heatmap) {
        gi_metrics_relerr_map(t, r, map, &err);
        gi_heatmap_opts ho = {GI_COLORMAP_VIRIDIS, 1, GI_HEATMAP_RELERR_LO, GI_HEATMAP_RELERR_HI,
                              "REL ERR"};
        rc = write_map(o.heatmap, map, t->width, t->height, &ho);
    }
    if (!rc && o.flip_map) {
        res = gi_metrics_flip_map(t, r, &o.m, map, NULL, &err);
        if (res) {
            rc = cli_fail(EXIT_RUN, "diff: %s", err.text);
        } else {
            gi_heatmap_opts ho = {GI_COLORMAP_MAGMA, 0, 0.0f, 1.0f, "FLIP"};
            rc = write_map(o.flip_map, map, t->width, t->height, &ho);
        }
    }
    free(map);
    if (!rc) {
        if (o.json)
            print_json(&o, t, r, &m);
        else
            print_human(&o, &m);
    }
done:
    gi_image_free(t);
    gi_image_free(r);
    return rc;
}
