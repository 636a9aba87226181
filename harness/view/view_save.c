/* gibench view: screenshots and saved views (docs/commands.md "gibench view"):
 * PREFIX.exr, PREFIX.png and PREFIX.json, and the view file that
 * `gibench render --view` reproduces (keys P and V, script lines
 * screenshot and save-view). */
#include "view.h"

#include "gi/image.h"
#include "gi/log.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void view_describe(const viewer *v, view_file *f)
{
    memset(f, 0, sizeof *f);
    snprintf(f->scene, sizeof f->scene, "%s", v->scene_path);
    snprintf(f->method, sizeof f->method, "%s", v->method_index < 0 ? "reference" : v->m->id);
    if (v->params) {
        char *s = gi_params_to_string(v->params);
        view_file_set_params(f, s);
        free(s);
    }
    f->width = v->width;
    f->height = v->height;
    f->frames = v->method_index < 0 ? (uint32_t)(v->ref_spp ? v->ref_spp : 1)
                                    : (v->frame_index ? v->frame_index : 1);
    f->seed = v->seed;
    f->time = v->time;
    f->exposure = v->exposure;
    gi_vec3 eye = view_eye(v);
    f->eye = eye;
    f->forward = gi_v3_normalize(gi_v3_sub(v->center, eye));
    f->up = gi_v3(0, 1, 0);
    f->yfov = v->yfov;
    f->znear = v->znear;
    f->zfar = v->zfar;
    view_describe_nodes(v, f);
}

int view_save(const viewer *v, const char *path)
{
    view_file f;
    view_describe(v, &f);
    char why[600];
    int ok = view_file_write(path, &f, why, sizeof why);
    view_file_free(&f);
    if (!ok)
        return cli_fail(EXIT_RUN, "view: %s", why);
    gi_log(GI_LOG_INFO, "view: saved the view to %s", path);
    return EXIT_OK;
}

/* PREFIX.exr (linear), PREFIX.png (exposure, sRGB) and PREFIX.json (the
 * view, which `gibench render --view` reproduces). */
int view_screenshot(viewer *v, const char *prefix)
{
    gi_image *img = NULL;
    if (v->method_index >= 0 && v->stale) {
        /* the method could not follow a change: its black target is not
         * an image of this view, and the view file would claim it is */
        gi_log(GI_LOG_WARN, "view: no screenshot %s: %s", prefix, v->status);
        return EXIT_OK;
    }
    if (v->method_index < 0) {
        uint64_t spp = 0;
        img = view_ref_take(&v->ref, 1, &spp);
        if (!img)
            return cli_fail(EXIT_RUN, "view: screenshot: the reference has no sample yet");
        v->ref_spp = spp;
    } else {
        img = gi_gpu_read_texture(v->target_tex, v->width, v->height);
        if (!img)
            return cli_fail(EXIT_RUN, "out of memory reading the image back");
        for (size_t i = 0; i < (size_t)v->width * v->height; i++)
            img->rgba[4 * i + 3] = 1.0f;
    }
    size_t n = strlen(prefix) + 8;
    char *path = malloc(n);
    if (!path) {
        gi_image_free(img);
        return cli_fail(EXIT_RUN, "out of memory");
    }
    gi_error err;
    gi_image_write_opts wo = {v->exposure};
    const char *ext[2] = {".exr", ".png"};
    int rc = EXIT_OK;
    for (int k = 0; k < 2 && rc == EXIT_OK; k++) {
        snprintf(path, n, "%s%s", prefix, ext[k]);
        if (gi_image_write(path, img, &wo, &err) != GI_OK)
            rc = cli_fail(EXIT_RUN, "view: %s", err.text);
    }
    gi_image_free(img);
    if (rc == EXIT_OK) {
        snprintf(path, n, "%s.json", prefix);
        rc = view_save(v, path);
    }
    if (rc == EXIT_OK)
        if (gi_log_get_level() >= GI_LOG_WARN)
            printf("view: screenshot %s.exr, .png, .json\n", prefix);
    free(path);
    return rc;
}

/* The next free DIR/gibench_view_NNNN (keys P and V). */
void view_next_name(viewer *v, char *out, size_t size)
{
    for (;;) {
        snprintf(out, size, "%s/gibench_view_%04u", v->shot_dir, v->shot_counter++);
        char probe[4200];
        snprintf(probe, sizeof probe, "%s.json", out);
        FILE *f = fopen(probe, "rb");
        if (!f)
            return;
        fclose(f);
    }
}
