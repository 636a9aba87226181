/* The viewer's progressive reference on a worker thread (view_ref.h). */
#include "view_ref.h"

#include "gi/log.h"
#include "reference.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* One request: a renderer made for it, passes of one sample until the
 * request changes or the worker is stopped or paused. */
static void serve(view_ref *r, uint64_t gen, gi_camera_frame cam, float time, uint32_t w,
                  uint32_t h, uint32_t seed)
{
    gi_ref_desc d;
    gi_ref_desc_init(&d);
    d.scene = r->scene;
    d.camera_frame = &cam;
    d.time = time;
    d.width = w;
    d.height = h;
    d.seed = seed;
    d.pixel_center = 1; /* as the methods' G-buffers sample the pixel */
    gi_ref *ref = NULL;
    gi_error err;
    if (gi_ref_create(&d, &ref, &err) != GI_OK) {
        pthread_mutex_lock(&r->mu);
        snprintf(r->error, sizeof r->error, "%s", err.text);
        r->active = 0;
        pthread_mutex_unlock(&r->mu);
        return;
    }
    for (;;) {
        pthread_mutex_lock(&r->mu);
        int go_on = !r->stop && r->active && r->generation == gen;
        pthread_mutex_unlock(&r->mu);
        if (!go_on)
            break;
        if (gi_ref_render(ref, 1, &err) != GI_OK) {
            pthread_mutex_lock(&r->mu);
            snprintf(r->error, sizeof r->error, "%s", err.text);
            r->active = 0;
            pthread_mutex_unlock(&r->mu);
            break;
        }
        gi_image *mean = gi_ref_mean_image(ref);
        pthread_mutex_lock(&r->mu);
        if (mean && r->generation == gen) {
            gi_image_free(r->latest);
            r->latest = mean;
            mean = NULL;
            r->latest_generation = gen;
            r->latest_spp = gi_ref_spp(ref);
            r->fresh = 1;
        }
        pthread_mutex_unlock(&r->mu);
        gi_image_free(mean);
    }
    gi_ref_free(ref);
}

static void *worker(void *arg)
{
    view_ref *r = arg;
    pthread_mutex_lock(&r->mu);
    for (;;) {
        while (!r->stop && !r->active)
            pthread_cond_wait(&r->cv, &r->mu);
        if (r->stop)
            break;
        uint64_t gen = r->generation;
        gi_camera_frame cam = r->camera;
        float time = r->time;
        uint32_t w = r->width, h = r->height, seed = r->seed;
        r->busy = 1;
        pthread_mutex_unlock(&r->mu);
        serve(r, gen, cam, time, w, h, seed);
        pthread_mutex_lock(&r->mu);
        r->busy = 0;
        pthread_cond_broadcast(&r->cv);
        /* a request served to its end (paused or failed) waits for the next */
        if (r->generation == gen && r->active)
            r->active = 0;
    }
    pthread_mutex_unlock(&r->mu);
    return NULL;
}

int view_ref_start(view_ref *r, const gi_scene *scene)
{
    memset(r, 0, sizeof *r);
    r->scene = scene;
    if (pthread_mutex_init(&r->mu, NULL))
        return 0;
    if (pthread_cond_init(&r->cv, NULL)) {
        pthread_mutex_destroy(&r->mu);
        return 0;
    }
    if (pthread_create(&r->thread, NULL, worker, r)) {
        pthread_cond_destroy(&r->cv);
        pthread_mutex_destroy(&r->mu);
        return 0;
    }
    r->started = 1;
    return 1;
}

void view_ref_request(view_ref *r, const gi_camera_frame *camera, float time, uint32_t width,
                      uint32_t height, uint32_t seed)
{
    pthread_mutex_lock(&r->mu);
    r->generation++;
    r->camera = *camera;
    r->time = time;
    r->width = width;
    r->height = height;
    r->seed = seed;
    r->active = 1;
    r->error[0] = '\0';
    r->latest_spp = 0;
    r->fresh = 0;
    pthread_cond_broadcast(&r->cv);
    pthread_mutex_unlock(&r->mu);
}

int view_ref_running(view_ref *r)
{
    pthread_mutex_lock(&r->mu);
    int a = r->active;
    pthread_mutex_unlock(&r->mu);
    return a;
}

void view_ref_pause(view_ref *r)
{
    pthread_mutex_lock(&r->mu);
    r->generation++;
    r->active = 0;
    pthread_mutex_unlock(&r->mu);
}

void view_ref_hold(view_ref *r)
{
    pthread_mutex_lock(&r->mu);
    r->generation++;
    r->active = 0;
    while (r->busy)
        pthread_cond_wait(&r->cv, &r->mu);
    pthread_mutex_unlock(&r->mu);
}

gi_image *view_ref_take(view_ref *r, int always, uint64_t *spp)
{
    gi_image *copy = NULL;
    pthread_mutex_lock(&r->mu);
    if (r->latest && r->latest_generation == r->generation && (r->fresh || always)) {
        copy = gi_image_create(r->latest->width, r->latest->height);
        if (copy)
            memcpy(copy->rgba, r->latest->rgba,
                   sizeof(float) * 4 * (size_t)copy->width * copy->height);
        r->fresh = 0;
        if (spp)
            *spp = r->latest_spp;
    }
    pthread_mutex_unlock(&r->mu);
    return copy;
}

uint64_t view_ref_spp(view_ref *r)
{
    pthread_mutex_lock(&r->mu);
    uint64_t n = r->latest_generation == r->generation ? r->latest_spp : 0;
    pthread_mutex_unlock(&r->mu);
    return n;
}

void view_ref_error(view_ref *r, char *buf, size_t size)
{
    pthread_mutex_lock(&r->mu);
    snprintf(buf, size, "%s", r->error);
    pthread_mutex_unlock(&r->mu);
}

void view_ref_stop(view_ref *r)
{
    if (!r->started)
        return;
    pthread_mutex_lock(&r->mu);
    r->stop = 1;
    pthread_cond_broadcast(&r->cv);
    pthread_mutex_unlock(&r->mu);
    pthread_join(r->thread, NULL);
    gi_image_free(r->latest);
    r->latest = NULL;
    pthread_cond_destroy(&r->cv);
    pthread_mutex_destroy(&r->mu);
    r->started = 0;
}
