/* gibench view's progressive reference: the Embree path tracer
 * (reference.h) on a worker thread, one sample per pixel per pass,
 * accumulating while the view stays the same and starting again when it
 * changes, so that the window stays responsive. */
#ifndef GIBENCH_VIEW_REF_H
#define GIBENCH_VIEW_REF_H

#include "gi/image.h"
#include "gi/scene.h"

#include <pthread.h>
#include <stdint.h>

typedef struct view_ref {
    pthread_t thread;
    int started;
    pthread_mutex_t mu;
    pthread_cond_t cv;
    const gi_scene *scene; /* borrowed, read only */
    /* what is asked (under mu) */
    int active, stop;
    int busy;            /* the worker is serving a request (reading the scene) */
    uint64_t generation; /* raised by every change of what is asked */
    gi_camera_frame camera;
    float time;
    uint32_t width, height, seed;
    /* what was rendered (under mu) */
    gi_image *latest; /* the mean after latest_spp samples of latest_generation */
    uint64_t latest_generation, latest_spp;
    int fresh;                /* latest is newer than what the caller took */
    char error[GI_ERROR_MAX]; /* set when the reference could not be made */
} view_ref;

/* Starts the worker (idle until view_ref_request); 1 on success. */
int view_ref_start(view_ref *r, const gi_scene *scene);
/* Asks for the reference of this camera, time and size, from 0 samples. */
void view_ref_request(view_ref *r, const gi_camera_frame *camera, float time, uint32_t width,
                      uint32_t height, uint32_t seed);
/* Whether a request is being served (not paused, not failed). */
int view_ref_running(view_ref *r);
/* Stops accumulating (the worker idles). */
void view_ref_pause(view_ref *r);
/* Stops accumulating and waits until the worker no longer reads the
 * scene, so that the caller may change it (objects or lights moved). */
void view_ref_hold(view_ref *r);
/* A copy of the newest image of the current request when there is one
 * newer than the last taken (or always, with `always`), and its samples
 * per pixel; NULL otherwise. The caller frees it. */
gi_image *view_ref_take(view_ref *r, int always, uint64_t *spp);
/* Samples per pixel of the current request so far (0 before the first pass). */
uint64_t view_ref_spp(view_ref *r);
/* Copies the worker's error (empty when none) into buf. */
void view_ref_error(view_ref *r, char *buf, size_t size);
void view_ref_stop(view_ref *r);

#endif
