/* The data of index.html's image viewer (report.h): per reference set its
 * references and runs, each image with its PNG, its linear RGB as a
 * script beside the .exr (the page's exposure control) and its error maps. */
#define _POSIX_C_SOURCE 200809L
#include "report_internal.h"

#include "gi/cache.h"
#include "gi/image.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char b64_chars[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

/* Writes the linear RGB of dir/exr_rel as a script beside it (same stem,
 * .js) for the viewer's exposure control and pixel values: GIB_HDR(key,
 * width, height, base64 of RGBE bytes), the key being the script's path
 * relative to the page. js_rel gets that path; 0 when there is no image. */
static int write_hdr_js(const char *dir, const char *exr_rel, char *js_rel, size_t js_size)
{
    size_t n = strlen(exr_rel);
    if (n < 5 || strcmp(exr_rel + n - 4, ".exr") || !report_exists_in(dir, exr_rel))
        return 0;
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, exr_rel);
    gi_error err;
    gi_image *img = gi_image_read(path, &err);
    if (!img)
        return 0;
    snprintf(js_rel, js_size, "%.*s.js", (int)(n - 4), exr_rel);
    size_t px = (size_t)img->width * img->height, nb = px * 4;
    unsigned char *rgbe = malloc(nb);
    text t = {0};
    int ok = rgbe != NULL;
    for (size_t i = 0; ok && i < px; i++) {
        float *c = img->rgba + i * 4;
        float r = isfinite(c[0]) && c[0] > 0 ? c[0] : 0, g = isfinite(c[1]) && c[1] > 0 ? c[1] : 0,
              b = isfinite(c[2]) && c[2] > 0 ? c[2] : 0;
        float v = r > g ? (r > b ? r : b) : (g > b ? g : b);
        unsigned char *o = rgbe + i * 4;
        if (v < 1e-32f) {
            o[0] = o[1] = o[2] = o[3] = 0;
        } else {
            int e;
            float scale = frexpf(v, &e) * 256.0f / v;
            o[0] = (unsigned char)(r * scale);
            o[1] = (unsigned char)(g * scale);
            o[2] = (unsigned char)(b * scale);
            o[3] = (unsigned char)(e + 128);
        }
    }
    if (ok) {
        put(&t, "GIB_HDR(\"%s\", %u, %u, \"", js_rel, img->width, img->height);
        for (size_t i = 0; i < nb; i += 3) {
            unsigned v = (unsigned)rgbe[i] << 16 | (i + 1 < nb ? (unsigned)rgbe[i + 1] << 8 : 0) |
                         (i + 2 < nb ? rgbe[i + 2] : 0);
            put(&t, "%c%c%c%c", b64_chars[v >> 18 & 63], b64_chars[v >> 12 & 63],
                i + 1 < nb ? b64_chars[v >> 6 & 63] : '=', i + 2 < nb ? b64_chars[v & 63] : '=');
        }
        put(&t, "\");\n");
        ok = snprintf(path, sizeof path, "%s/%s", dir, js_rel) < (int)sizeof path && t.s &&
             gi_file_write_atomic(path, t.s, t.len, &err) == GI_OK;
    }
    free(t.s);
    free(rgbe);
    gi_image_free(img);
    return ok;
}

/* exr_rel with .png for .exr, when that file exists. */
static const char *png_of(const char *dir, const char *exr_rel, char *buf, size_t size)
{
    size_t n = strlen(exr_rel);
    if (n < 5 || strcmp(exr_rel + n - 4, ".exr"))
        return NULL;
    snprintf(buf, size, "%.*s.png", (int)(n - 4), exr_rel);
    return report_exists_in(dir, buf) ? buf : NULL;
}

/* A viewer image: label, title (hover), the PNG, the HDR script, error maps, info line. */
static json_object *viewer_image(const char *dir, const char *label, const char *title,
                                 const char *png, const char *exr)
{
    json_object *im = json_object_new_object();
    json_object_object_add(im, "label", json_object_new_string(label));
    json_object_object_add(im, "title", json_object_new_string(title));
    char buf[4096], js[4096];
    if (!png && exr)
        png = png_of(dir, exr, buf, sizeof buf);
    if (png && report_exists_in(dir, png))
        json_object_object_add(im, "png", json_object_new_string(png));
    if (exr && write_hdr_js(dir, exr, js, sizeof js))
        json_object_object_add(im, "hdr", json_object_new_string(js));
    json_object_object_add(im, "maps", json_object_new_array());
    return im;
}

/* A run's short name: method and the parameters the study set. */
static void run_label(json_object *o, char *buf, size_t size)
{
    const char *p = report_raw(o, "params"), *l = report_raw(o, "label");
    snprintf(buf, size, "%s %s%s%s", report_str(o, "method"), *p ? p : "(defaults)", *l ? " " : "",
             l);
}

static void run_info(json_object *o, char *buf, size_t size)
{
    snprintf(buf, size, "run %s, %s", report_str(o, "run"), report_str(o, "status"));
    const char *names[] = {"frame ms (median)", "prepare ms", "relMSE full", "relMSE matched",
                           "HDR-FLIP full",     "FLIP full",  "SSIM full"};
    double vals[] = {
        report_num(o, "frame_ms", "median", NULL),    report_num(o, "prepare_ms", NULL, NULL),
        report_num(o, "metrics", "full", "relmse"),   report_num(o, "metrics", "matched", "relmse"),
        report_num(o, "metrics", "full", "hdr_flip"), report_num(o, "metrics", "full", "flip"),
        report_num(o, "metrics", "full", "ssim")};
    for (size_t k = 0; k < sizeof vals / sizeof vals[0]; k++)
        if (vals[k] == vals[k]) {
            size_t used = strlen(buf);
            snprintf(buf + used, size - used, "; %s %.4g", names[k], vals[k]);
        }
    size_t used = strlen(buf);
    snprintf(buf + used, size - used, "; params %s", report_str(o, "params"));
}

static json_object *find_run(json_object *runs, const char *id)
{
    for (size_t i = 0; i < json_object_array_length(runs); i++) {
        json_object *o = json_object_array_get_idx(runs, i);
        if (!strcmp(report_raw(o, "run"), id))
            return o;
    }
    return NULL;
}

/* Whether an image labelled `have` shows the setting labelled `label`:
 * the label itself, or it with a repeat's number (" #2", " #3", ...). */
static int same_setting(const char *have, const char *label)
{
    size_t n = strlen(label);
    if (strncmp(have, label, n))
        return 0;
    if (!have[n])
        return 1;
    if (strncmp(have + n, " #", 2) || !have[n + 2])
        return 0;
    return strspn(have + n + 2, "0123456789") == strlen(have + n + 2);
}

static void add_run_image(const char *dir, json_object *images, json_object *o)
{
    if (strcmp(report_raw(o, "status"), "ok"))
        return;
    char label[600], title[8192], info[8192];
    run_label(o, label, sizeof label);
    /* repeats of one setting: numbered among themselves only (a prefix
     * match would count "light_samples=16" as a repeat of "light_samples=1") */
    int same = 0;
    for (size_t k = 0; k < json_object_array_length(images); k++)
        same += same_setting(report_raw(json_object_array_get_idx(images, k), "label"), label);
    if (same) {
        size_t used = strlen(label);
        snprintf(label + used, sizeof label - used, " #%d", same + 1);
    }
    snprintf(title, sizeof title, "run %s: %s", report_raw(o, "run"), report_str(o, "params"));
    const char *png = report_raw(o, "png");
    json_object *im = viewer_image(dir, label, title, *png ? png : NULL,
                                   *report_raw(o, "image") ? report_raw(o, "image") : NULL);
    if (!json_object_object_get_ex(im, "png", NULL) &&
        !json_object_object_get_ex(im, "hdr", NULL)) {
        json_object_put(im);
        return;
    }
    json_object *maps;
    json_object_object_get_ex(im, "maps", &maps);
    const char *heat = report_raw(o, "heatmap");
    if (report_exists_in(dir, heat)) {
        json_object *m = json_object_new_object();
        json_object_object_add(m, "name", json_object_new_string("relative error"));
        json_object_object_add(m, "png", json_object_new_string(heat));
        json_object_array_add(maps, m);
    }
    char flip[4200];
    /* FLIP's map: named in the record, or beside the heat map (older records) */
    snprintf(flip, sizeof flip, "%s",
             *report_raw(o, "flip_map") ? report_raw(o, "flip_map") : heat);
    char *slash = strrchr(flip, '/');
    if (slash) {
        snprintf(slash + 1, sizeof flip - (size_t)(slash + 1 - flip), "flip.png");
        if (report_exists_in(dir, flip)) {
            json_object *m = json_object_new_object();
            json_object_object_add(m, "name", json_object_new_string("FLIP"));
            json_object_object_add(m, "png", json_object_new_string(flip));
            json_object_array_add(maps, m);
        }
    }
    run_info(o, info, sizeof info);
    json_object_object_add(im, "info", json_object_new_string(info));
    json_object_array_add(images, im);
}

/* The viewer's data: per reference set, its references and runs
 * (meta "references", from study), or one set with the report's reference
 * and every run (compare). */
json_object *report_viewer_sets(const char *dir, json_object *runs, json_object *meta)
{
    json_object *sets = json_object_new_array(), *refs;
    double ev = report_num(meta, "exposure", NULL, NULL);
    if (json_object_object_get_ex(meta, "references", &refs) &&
        json_object_is_type(refs, json_type_array)) {
        for (size_t r = 0; r < json_object_array_length(refs); r++) {
            json_object *rs = json_object_array_get_idx(refs, r), *set = json_object_new_object();
            json_object *images = json_object_new_array(), *matched, *ids;
            json_object_object_add(set, "name", json_object_new_string(report_raw(rs, "name")));
            char label[128];
            snprintf(label, sizeof label, "reference, full GI (%g bounces)",
                     report_num(rs, "bounces", NULL, NULL));
            json_object_array_add(images, viewer_image(dir, label, report_raw(rs, "full"), NULL,
                                                       report_raw(rs, "full")));
            if (json_object_object_get_ex(rs, "matched", &matched))
                for (size_t k = 0; k < json_object_array_length(matched); k++) {
                    json_object *m = json_object_array_get_idx(matched, k);
                    snprintf(label, sizeof label, "reference, %g bounce%s",
                             report_num(m, "bounces", NULL, NULL),
                             report_num(m, "bounces", NULL, NULL) == 1 ? "" : "s");
                    json_object_array_add(images, viewer_image(dir, label, report_raw(m, "image"),
                                                               NULL, report_raw(m, "image")));
                }
            if (json_object_object_get_ex(rs, "runs", &ids))
                for (size_t k = 0; k < json_object_array_length(ids); k++) {
                    json_object *o =
                        find_run(runs, json_object_get_string(json_object_array_get_idx(ids, k)));
                    if (o)
                        add_run_image(dir, images, o);
                }
            json_object_object_add(set, "images", images);
            json_object_object_add(set, "exposure", json_object_new_double(ev == ev ? ev : 0));
            json_object_array_add(sets, set);
        }
        return sets;
    }
    json_object *set = json_object_new_object(), *images = json_object_new_array();
    const char *ref_png = report_raw(meta, "reference_png");
    if (report_exists_in(dir, ref_png)) {
        char exr[4096];
        size_t n = strlen(ref_png);
        snprintf(exr, sizeof exr, "%.*s.exr", n > 4 ? (int)(n - 4) : 0, ref_png);
        json_object_array_add(images, viewer_image(dir, "reference", ref_png, ref_png, exr));
    }
    for (size_t i = 0; i < json_object_array_length(runs); i++)
        add_run_image(dir, images, json_object_array_get_idx(runs, i));
    json_object_object_add(set, "name", json_object_new_string(report_raw(meta, "title")));
    json_object_object_add(set, "images", images);
    json_object_object_add(set, "exposure", json_object_new_double(ev == ev ? ev : 0));
    json_object_array_add(sets, set);
    return sets;
}
