/* A saved view of gibench view ("save view", README.md "gibench view"):
 * scene, camera, time, method and its parameters, image size, exposure and
 * the frames accumulated, as a small JSON file that `gibench render --view
 * FILE` reproduces in batch. */
#ifndef GIBENCH_VIEW_FILE_H
#define GIBENCH_VIEW_FILE_H

#include "gi/scene.h"

#include <stddef.h>
#include <stdint.h>

#define VIEW_FILE_MAX_PARAMS 64

typedef struct view_file {
    char scene[4096];
    char method[64];   /* a method id, or "reference" for the path tracer */
    char *params[VIEW_FILE_MAX_PARAMS]; /* "k=v", malloc'd */
    uint32_t param_count;
    uint32_t width, height;
    uint32_t frames;   /* frames accumulated since the last change (progressive methods) */
    uint32_t seed;
    float time, exposure;
    gi_vec3 eye, forward, up; /* the camera: eye looking along forward, up roughly +Y */
    float yfov, znear, zfar;
} view_file;

/* Sets params from gi_params_to_string's canonical "a=1,b=x" text (replacing any). */
int view_file_set_params(view_file *v, const char *canonical);
/* The camera frame the view describes. */
gi_camera_frame view_file_camera(const view_file *v);
/* Writes the view as JSON; 1 on success, else 0 with why. */
int view_file_write(const char *path, const view_file *v, char *why, size_t why_size);
/* Reads and checks a view (finite camera, sizes 1..16384, known keys);
 * 1 on success, else 0 with a one-line why. Free with view_file_free. */
int view_file_read(const char *path, view_file *v, char *why, size_t why_size);
void view_file_free(view_file *v);

#endif
