/* The llvmpipe fence guard (core/src/mutex_guard.c): the process-wide
 * pthread_mutex_destroy is libgicore's, and it waits for a mutex another
 * thread still holds instead of destroying it under that thread (glibc's
 * own returns EBUSY at once, and the memory would then be freed while
 * the other thread still unlocks it). */
#define _GNU_SOURCE
#include "check.h"

#include <dlfcn.h>
#include <pthread.h>
#include <string.h>
#include <time.h>

static pthread_mutex_t held = PTHREAD_MUTEX_INITIALIZER;
static volatile int locked, released;

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

/* Holds the mutex for 200 ms, as a preempted signalling thread would. */
static void *holder(void *arg)
{
    (void)arg;
    pthread_mutex_lock(&held);
    locked = 1;
    struct timespec ts = {0, 200 * 1000 * 1000};
    nanosleep(&ts, NULL);
    released = 1;
    pthread_mutex_unlock(&held);
    return NULL;
}

int main(void)
{
    /* a library loaded later (the GL driver) resolves the name here */
    void *fn = dlsym(RTLD_DEFAULT, "pthread_mutex_destroy");
    Dl_info info;
    CHECK(fn && dladdr(fn, &info) && info.dli_fname && strstr(info.dli_fname, "libgicore"));

    pthread_t t;
    CHECK(pthread_create(&t, NULL, holder, NULL) == 0);
    while (!locked) {
        struct timespec ts = {0, 1000 * 1000};
        nanosleep(&ts, NULL);
    }
    double t0 = now();
    int r = pthread_mutex_destroy(&held);
    double waited = now() - t0;
    CHECK(released); /* the holder had let go before the destroy */
    CHECK_MSG(waited > 0.1, "waited %.3f s", waited);
    CHECK(r == 0);
    pthread_join(t, NULL);

    /* an unheld mutex is destroyed at once */
    pthread_mutex_t m;
    pthread_mutex_init(&m, NULL);
    t0 = now();
    CHECK(pthread_mutex_destroy(&m) == 0);
    CHECK(now() - t0 < 0.05);
    return gi_test_finish();
}
