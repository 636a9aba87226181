/* libgibench (gi/gibench.h): the path-traced reference and the metrics,
 * through the same library calls as gibench reference and gibench diff. */
#include "gi/gibench.h"

#include "cli.h"
#include "gibench_internal.h"
#include "metrics.h"
#include "runner.h"
#include "reference.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

gibench_reference_opts gibench_reference_defaults(void)
{
    gibench_reference_opts o;
    memset(&o, 0, sizeof o);
    o.width = o.height = 256;
    o.seed = 1;
    o.max_bounces = -1;
    return o;
}

/* The scene's camera of o->camera, checked as gibench reference checks it. */
static gi_result ref_camera(const gibench_scene *s, const char *name, int *camera, gi_error *err)
{
    const gi_scene *sc = gibench_scene_of(s);
    *camera = sc->camera_count ? 0 : -1;
    if (name) {
        *camera = gi_scene_find_camera(sc, name);
        if (*camera < 0)
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                "reference: %s has no camera '%s' (%u cameras; use a name or #k)",
                                sc->path, name, sc->camera_count);
    }
    return GI_OK;
}

static json_object *ref_stats_json(const gi_ref *r, const char *stop)
{
    gi_ref_stats st;
    gi_ref_get_stats(r, &st);
    json_object *j = json_object_new_object();
    json_object_object_add(j, "renderer", json_object_new_string(gi_ref_renderer(r)));
    json_object_object_add(j, "spp", json_object_new_int64((int64_t)st.spp));
    json_object_object_add(j, "stop", json_object_new_string(stop));
    json_object_object_add(j, "threads", json_object_new_int((int32_t)st.threads));
    json_object_object_add(j, "build_seconds", json_object_new_double(st.build_seconds));
    json_object_object_add(j, "render_seconds", json_object_new_double(st.render_seconds));
    json_object_object_add(j, "render_cpu_seconds", json_object_new_double(st.render_cpu_seconds));
    json_object_object_add(j, "rays", json_object_new_int64((int64_t)st.rays));
    json_object_object_add(j, "nonfinite_samples", json_object_new_int64((int64_t)st.nonfinite));
    double rel = gi_ref_mean_rel_se(r);
    json_object_object_add(j, "mean_rel_se", isfinite(rel) ? json_object_new_double(rel) : NULL);
    double rm = gi_ref_mean_relmse(r);
    json_object_object_add(j, "relmse_estimate", isfinite(rm) ? json_object_new_double(rm) : NULL);
    return j;
}

/* RGB of an RGBA image into out (width * height * 3). */
static void copy_rgb(const gi_image *img, float *out)
{
    for (size_t i = 0; i < (size_t)img->width * img->height; i++)
        memcpy(out + 3 * i, img->rgba + 4 * i, 3 * sizeof(float));
}

gi_result gibench_reference(gibench_scene *s, const gibench_reference_opts *o, float *mean,
                            float *variance, char **stats, gi_error *err)
{
    if (stats)
        *stats = NULL;
    if (!gi_image_size_ok(o->width, o->height))
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "reference: --size '%ux%u' is not WxH with " GI_IMAGE_SIZE_RULE,
                            o->width, o->height);
    int camera;
    gi_result res = ref_camera(s, o->camera, &camera, err);
    if (res != GI_OK)
        return res;
    gi_ref_desc d;
    gi_ref_desc_init(&d);
    d.scene = gibench_scene_of(s);
    d.camera = camera;
    d.time = o->time;
    d.width = o->width;
    d.height = o->height;
    d.seed = o->seed;
    d.max_bounces = o->max_bounces < 0 ? GI_REF_UNLIMITED : o->max_bounces;
    d.threads = o->threads;
    d.pixel_center = o->pixel_center;
    d.robust_traversal = o->robust_traversal;
    gi_ref *r = NULL;
    res = gi_ref_create(&d, &r, err);
    if (res != GI_OK)
        return res;
    /* as gibench reference: with no limit given, DEFAULT_SPP samples */
    gi_ref_until u = {o->spp, o->seconds, o->target_se, o->target_relmse};
    if (!u.spp && u.seconds <= 0.0 && u.target_se <= 0.0 && u.target_relmse <= 0.0)
        u.spp = 256;
    const char *stop = NULL;
    res = gi_ref_progressive(r, &u, NULL, NULL, &stop, err);
    gi_image *m = res == GI_OK ? gi_ref_mean_image(r) : NULL;
    gi_image *v = res == GI_OK ? gi_ref_variance_image(r) : NULL;
    if (res == GI_OK && (!m || !v))
        res = gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "out of memory reading the image");
    if (res == GI_OK) {
        copy_rgb(m, mean);
        if (variance)
            copy_rgb(v, variance);
        if (stats)
            res = gibench_json_out(ref_stats_json(r, stop), stats, err);
    }
    gi_image_free(m);
    gi_image_free(v);
    gi_ref_free(r);
    return res;
}

/* An RGBA gi_image of an RGB buffer (alpha 1). */
static gi_image *image_of(const float *rgb, uint32_t w, uint32_t h)
{
    gi_image *img = gi_image_create(w, h);
    for (size_t i = 0; img && i < (size_t)w * h; i++) {
        memcpy(img->rgba + 4 * i, rgb + 3 * i, 3 * sizeof(float));
        img->rgba[4 * i + 3] = 1.0f;
    }
    return img;
}

/* The metrics under the names of gibench diff --json. */
static json_object *metrics_json(const gi_metrics *m)
{
    json_object *j = json_object_new_object();
    runner_metrics_json_add(j, m);
    return j;
}

gi_result gibench_metrics(const float *test, const float *ref, uint32_t width, uint32_t height,
                          float exposure, float flip_ppd, float *relerr_map, float *flip_map,
                          char **out, gi_error *err)
{
    *out = NULL;
    gi_image *t = image_of(test, width, height), *r = image_of(ref, width, height);
    gi_result res = t && r ? GI_OK : gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "out of memory");
    gi_metrics_opts mo = {exposure, flip_ppd, 0, 0};
    gi_metrics m;
    if (res == GI_OK)
        res = gi_metrics_compute(t, r, &mo, &m, err);
    if (res == GI_OK && relerr_map)
        res = gi_metrics_relerr_map(t, r, relerr_map, err);
    if (res == GI_OK && flip_map)
        res = gi_metrics_flip_map(t, r, &mo, flip_map, NULL, err);
    if (res == GI_OK)
        res = gibench_json_out(metrics_json(&m), out, err);
    gi_image_free(t);
    gi_image_free(r);
    return res;
}
