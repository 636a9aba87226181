/* gibench view: the live error of the method shown against the progressive
 * reference while it converges, the pixel read-out under the cursor, the
 * state line of script line print-state, and parameters set by name
 * (docs/commands.md "gibench view", "Panels"). The relMSE is computed by
 * gi_metrics_compute, the function behind `gibench diff`, so the panel's
 * number is the one `gibench diff` gives for the same pair of images. */
#define _POSIX_C_SOURCE 200809L
#include "view.h"

#include "gi/image.h"
#include "metrics.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The method's image, top row first, alpha 1 (as its screenshot). */
static gi_image *method_image(viewer *v)
{
    gi_image *img = gi_gpu_read_texture(v->target_tex, v->width, v->height);
    if (img)
        for (size_t i = 0; i < (size_t)v->width * v->height; i++)
            img->rgba[4 * i + 3] = 1.0f;
    return img;
}

/* The relMSE of img against the reference taken last; NaN when there is none. */
static double relmse_of(const viewer *v, const gi_image *img)
{
    const gi_image *r = v->ref_img;
    if (!img || !r || r->width != img->width || r->height != img->height)
        return NAN;
    gi_metrics_opts o = {0};
    o.skip_flip = 1;
    gi_metrics m;
    gi_error err;
    if (gi_metrics_compute(img, r, &o, &m, &err) != GI_OK)
        return NAN;
    return m.relmse;
}

static int error_possible(const viewer *v)
{
    return v->method_index >= 0 && v->inst && !v->stale && v->frame_index > 0 && v->ref_img;
}

void view_error_update(viewer *v, int force)
{
    if (!v->err_dirty)
        return;
    double now = gi_now();
    if (!force && now - v->err_time < 0.25)
        return;
    v->err_time = now;
    v->err_dirty = 0;
    v->relmse = NAN;
    if (!error_possible(v))
        return;
    gi_image *img = method_image(v);
    v->relmse = relmse_of(v, img);
    v->err_spp = v->ref_spp;
    gi_image_free(img);
}

void view_pixel_readout(viewer *v, int x, int y)
{
    v->px_valid = 0;
    if (x < 0 || y < 0 || (uint32_t)x >= v->width || (uint32_t)y >= v->height)
        return;
    float m[4] = {0, 0, 0, 0};
    if (v->method_index >= 0 && v->target_tex)
        glGetTextureSubImage(v->target_tex, 0, x, (GLint)v->height - 1 - y, 0, 1, 1, 1, GL_RGBA,
                             GL_FLOAT, sizeof m, m);
    const gi_image *r = v->ref_img;
    int have_ref = r && r->width == v->width && r->height == v->height;
    double e = 0;
    for (int c = 0; c < 3; c++) {
        v->px_method[c] = m[c];
        v->px_ref[c] = have_ref ? r->rgba[4 * ((size_t)y * r->width + (size_t)x) + (size_t)c] : NAN;
        /* gi_metrics_relerr_map's per-pixel error: mean of |x - r| / (r + 0.01) */
        e += fabs((double)m[c] - v->px_ref[c]) / (v->px_ref[c] + 0.01) / 3.0;
    }
    v->px_err = have_ref ? (float)e : NAN;
    v->px_valid = 1;
}

static const char *source_name(int s)
{
    static const char *names[VIEW_SRC_COUNT] = {"output", "error", "reference", "buffer"};
    return s >= 0 && s < VIEW_SRC_COUNT ? names[s] : "?";
}

/* PREFIX_method.exr and PREFIX_ref.exr: the pair the relMSE printed is of. */
static int write_pair(viewer *v, const char *prefix, const gi_image *img)
{
    size_t n = strlen(prefix) + 16;
    char *path = malloc(n);
    if (!path)
        return cli_fail(EXIT_RUN, "out of memory");
    gi_error err;
    int rc = EXIT_OK;
    snprintf(path, n, "%s_method.exr", prefix);
    if (gi_image_write(path, img, NULL, &err) != GI_OK)
        rc = cli_fail(EXIT_RUN, "view: %s", err.text);
    snprintf(path, n, "%s_ref.exr", prefix);
    if (rc == EXIT_OK && gi_image_write(path, v->ref_img, NULL, &err) != GI_OK)
        rc = cli_fail(EXIT_RUN, "view: %s", err.text);
    free(path);
    return rc;
}

int view_print_state(viewer *v, const char *prefix)
{
    /* the newest reference pass, so that the number is of the reference as it is now */
    if (v->method_index >= 0)
        view_poll_reference(v);
    gi_image *img = error_possible(v) ? method_image(v) : NULL;
    double relmse = relmse_of(v, img);
    int rc = EXIT_OK;
    if (prefix) {
        if (!img || !v->ref_img)
            rc = cli_fail(EXIT_RUN, "view: print-state %s: no method image or no reference yet",
                          prefix);
        else
            rc = write_pair(v, prefix, img);
    }
    gi_image_free(img);
    if (rc != EXIT_OK)
        return rc;
    view_pixel_readout(v, v->cursor_px, v->cursor_py);
    if (!v->px_valid) /* no pixel under the mouse: NaN */
        for (int c = 0; c < 3; c++)
            v->px_method[c] = v->px_ref[c] = v->px_err = NAN;
    char *params = v->params ? gi_params_to_string(v->params) : NULL;
    printf("state: method=%s method2=%s split=%d source=%s panels=%d image=%ux%u region=%dx%d "
           "zoom=%g pan=%g,%g frame=%u frame2=%u spp=%llu relmse=%.9g params=%s cursor=%d,%d "
           "pixel_method=%.6g,%.6g,%.6g pixel_ref=%.6g,%.6g,%.6g pixel_err=%.6g\n",
           v->method_index < 0 ? "reference" : v->m->id,
           v->second.method_index >= 0 && v->second.m ? v->second.m->id : "-", v->split,
           source_name(v->source), v->show_panels, v->width, v->height, v->image_w, v->image_h,
           (double)v->zoom, (double)v->pan_x, (double)v->pan_y, v->frame_index,
           v->second.frame_index, (unsigned long long)v->ref_spp, relmse,
           params && *params ? params : "-", v->cursor_px, v->cursor_py, (double)v->px_method[0],
           (double)v->px_method[1], (double)v->px_method[2], (double)v->px_ref[0],
           (double)v->px_ref[1], (double)v->px_ref[2], (double)v->px_err);
    fflush(stdout);
    free(params);
    return EXIT_OK;
}

/* "a=1,b=2" with k's value replaced by kv (or kv appended); NULL when out of memory. */
static char *replace_param(const char *all, const char *kv)
{
    size_t klen = (size_t)(strchr(kv, '=') - kv), n = strlen(all) + strlen(kv) + 2, used = 0;
    char *out = malloc(n);
    if (!out)
        return NULL;
    out[0] = '\0';
    int done = 0;
    for (const char *p = all; p && *p;) {
        const char *end = strchr(p, ',');
        size_t len = end ? (size_t)(end - p) : strlen(p);
        int same = len > klen && !strncmp(p, kv, klen) && p[klen] == '=';
        used += (size_t)snprintf(out + used, n - used, "%s%.*s", used ? "," : "",
                                 (int)(same ? strlen(kv) : len), same ? kv : p);
        done |= same;
        p = end ? end + 1 : NULL;
    }
    if (!done)
        snprintf(out + used, n - used, "%s%s", used ? "," : "", kv);
    return out;
}

int view_set_param(viewer *v, const char *kv)
{
    if (v->method_index < 0 || !v->params)
        return cli_fail(EXIT_USAGE, "view: param %s: the reference has no parameters", kv);
    if (!strchr(kv, '=') || kv[0] == '=')
        return cli_fail(EXIT_USAGE, "view: param '%s' is not NAME=VALUE", kv);
    /* checked before the method is unloaded, so that a bad value leaves it as it was */
    gi_error err;
    const char *one[1] = {kv};
    gi_params *check = gi_params_parse(v->m->id, v->m->params, one, 1, &err);
    if (!check)
        return cli_fail(EXIT_USAGE, "%s", err.text);
    gi_params_free(check);
    char *all = gi_params_to_string(v->params);
    char *s = all ? replace_param(all, kv) : NULL;
    free(all);
    return view_remake(v, s);
}
