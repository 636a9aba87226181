/* A guard against a race in Mesa's llvmpipe (22.3, Debian 12, and as of
 * this writing upstream too), docs/gpu.md "llvmpipe's fence race".
 *
 * A rasteriser thread signals a fence under the fence's mutex: count++,
 * broadcast, unlock. The main thread reads count without the mutex
 * (lp_fence_signalled, in lp_setup_get_empty_scene and fence_finish) and,
 * when it sees the fence done, may drop the last reference and free the
 * fence while the rasteriser thread is still between count++ and its
 * unlock. The unlock then writes 0 into freed memory: malloc's free-list
 * pointer of that chunk. Under load (the thread preempted in that window)
 * this corrupted the heap of `gibench conformance --method cssm_hrc` in
 * 1-4 items per run; the chunk read back from the core dumps held a freed
 * fence (issued 1, rank 2, count 2) with its lock word zeroed.
 *
 * lp_fence_destroy destroys the mutex before it frees the fence. This
 * definition of pthread_mutex_destroy, found before libc's by every
 * library loaded after libgicore (the driver among them), first waits
 * until no other thread holds the mutex, so that a signalling thread has
 * left it before the memory goes. A mutex its caller still holds (an
 * error the caller made) is destroyed after a bounded wait, as before. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <pthread.h>
#include <stdatomic.h>
#include <string.h>
#include <time.h>

typedef int (*mutex_destroy_fn)(pthread_mutex_t *);

/* libc's pthread_mutex_destroy, the next definition after this library. */
static mutex_destroy_fn real_destroy(void)
{
    static _Atomic(mutex_destroy_fn) fn;
    mutex_destroy_fn f = atomic_load_explicit(&fn, memory_order_acquire);
    if (!f) {
        void *sym = dlsym(RTLD_NEXT, "pthread_mutex_destroy");
        memcpy(&f, &sym, sizeof f);
        atomic_store_explicit(&fn, f, memory_order_release);
    }
    return f;
}

__attribute__((visibility("default"))) int pthread_mutex_destroy(pthread_mutex_t *m)
{
    /* up to about 2 s for another thread to let go; a holder that keeps it
     * longer (or the caller itself) is not waited for further */
    for (int tries = 0; tries < 40000; tries++) {
        int r = pthread_mutex_trylock(m);
        if (r == 0) {
            pthread_mutex_unlock(m);
            break;
        }
        if (r != EBUSY)
            break;
        struct timespec pause = {0, 50000};
        nanosleep(&pause, NULL);
    }
    mutex_destroy_fn f = real_destroy();
    return f ? f(m) : 0;
}
