/* Traced direct light for implicit_vis (iv_traced.h; README "Traced
 * direct light"). */
#include "iv_traced.h"

#include "gi/rng.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>

iv_traced *iv_traced_create(const gi_scene *s, float t, uint32_t elems, uint32_t samples,
                            uint32_t threads, gi_error *err)
{
    iv_traced *tr = calloc(1, sizeof *tr);
    if (!tr) {
        gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "implicit_vis: out of memory");
        return NULL;
    }
    tr->elems = elems;
    tr->samples = samples;
    tr->threads = threads ? threads : 1;
    tr->elem = calloc((size_t)elems * 6 + 1, sizeof(float));
    if (!tr->elem) {
        gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "implicit_vis: out of memory");
        iv_traced_free(tr);
        return NULL;
    }
    if (gi_rt_create(s, t, &tr->rt, err) != GI_OK) {
        iv_traced_free(tr);
        return NULL;
    }
    return tr;
}

void iv_traced_free(iv_traced *tr)
{
    if (!tr)
        return;
    gi_direct_rays_free(tr->dr);
    gi_rt_free(tr->rt);
    free(tr->elem), free(tr->pos), free(tr->nrm), free(tr->pixel);
    if (tr->ssbo_pixel)
        glDeleteBuffers(1, &tr->ssbo_pixel);
    free(tr);
}

/* One job over items 0 .. count - 1, shared by tr->threads threads, item i
 * on thread i mod threads. */
typedef struct job {
    const iv_traced *tr;
    const iv_hier *h; /* elements; NULL: pixels */
    uint32_t count, threads, index;
} job;

/* The seed of item i in this frame (elements and pixels draw apart). */
static uint32_t seed_of(const iv_traced *tr, uint32_t i, uint32_t salt)
{
    return gi_pcg_hash(gi_pcg_hash(i ^ salt) + tr->frame * 0x9e3779b9u);
}

static void element_direct(const iv_traced *tr, const iv_hier *h, uint32_t e)
{
    uint32_t x = h->elem_node[e];
    gi_vec3 p = gi_v3_load(&h->pos[3 * x]), n = gi_v3_load(&h->nrm[3 * x]);
    float *o = &tr->elem[6 * (size_t)e];
    gi_direct_rays_irradiance(tr->dr, p, n, tr->samples, tr->samples, seed_of(tr, e, 0x11u), o);
    o[3] = o[4] = o[5] = 0.0f;
    if (h->elem_two_sided_emit[e]) /* double-sided: the back is a surface too */
        gi_direct_rays_irradiance(tr->dr, p, gi_v3_scale(n, -1.0f), tr->samples, tr->samples,
                                  seed_of(tr, e, 0x22u), o + 3);
}

static void pixel_direct(const iv_traced *tr, uint32_t i)
{
    float *o = &tr->pixel[4 * (size_t)i];
    o[0] = o[1] = o[2] = o[3] = 0.0f;
    if (!(tr->pos[4 * (size_t)i + 3] > 0.0f)) /* no hit (eye depth 0) */
        return;
    gi_vec3 n = gi_v3_load(&tr->nrm[4 * (size_t)i]);
    float len = gi_v3_length(n);
    if (!(len > 0.0f))
        return;
    gi_direct_rays_irradiance(tr->dr, gi_v3_load(&tr->pos[4 * (size_t)i]),
                              gi_v3_scale(n, 1.0f / len), tr->samples, tr->samples,
                              seed_of(tr, i, 0x33u), o);
}

static void *work(void *arg)
{
    const job *j = arg;
    for (uint32_t i = j->index; i < j->count; i += j->threads) {
        if (j->h)
            element_direct(j->tr, j->h, i);
        else
            pixel_direct(j->tr, i);
    }
    return NULL;
}

/* Runs the job on tr->threads threads (fewer when a thread cannot start:
 * the calling thread takes over its items). */
static void run(const iv_traced *tr, const iv_hier *h, uint32_t count)
{
    enum { MAX_THREADS = 256 };
    uint32_t T = tr->threads > MAX_THREADS ? MAX_THREADS : tr->threads;
    T = T > count ? (count ? count : 1) : T;
    job jobs[MAX_THREADS];
    pthread_t tid[MAX_THREADS];
    int made[MAX_THREADS] = {0};
    for (uint32_t i = 0; i < T; i++) {
        jobs[i] = (job){tr, h, count, T, i};
        if (i > 0)
            made[i] = pthread_create(&tid[i], NULL, work, &jobs[i]) == 0;
    }
    work(&jobs[0]);
    for (uint32_t i = 1; i < T; i++) {
        if (made[i])
            pthread_join(tid[i], NULL);
        else
            work(&jobs[i]);
    }
}

gi_result iv_traced_elements(iv_traced *tr, const iv_hier *h, float t, gi_error *err)
{
    if (gi_rt_time(tr->rt) != t && gi_rt_set_time(tr->rt, t, err) != GI_OK)
        return GI_ERR_INVALID_ARGUMENT;
    gi_direct_rays_free(tr->dr);
    tr->dr = NULL;
    gi_result r = gi_direct_rays_create(tr->rt, &tr->dr, err);
    if (r != GI_OK)
        return r;
    tr->frame++;
    run(tr, h, h->elem_count);
    return GI_OK;
}

gi_result iv_traced_pixels(iv_traced *tr, const gi_gbuffer *gb, gi_error *err)
{
    size_t n = (size_t)gb->width * gb->height;
    if (n > tr->pixels) {
        free(tr->pos), free(tr->nrm), free(tr->pixel);
        tr->pos = malloc(n * 4 * sizeof(float));
        tr->nrm = malloc(n * 4 * sizeof(float));
        tr->pixel = malloc(n * 4 * sizeof(float));
        tr->pixels = tr->pos && tr->nrm && tr->pixel ? n : 0;
        if (!tr->pixels)
            return gi_error_set(err, GI_ERR_OUT_OF_MEMORY,
                                "implicit_vis: out of memory for %zu pixels", n);
        if (tr->ssbo_pixel)
            glDeleteBuffers(1, &tr->ssbo_pixel);
        glCreateBuffers(1, &tr->ssbo_pixel);
        glNamedBufferData(tr->ssbo_pixel, (GLsizeiptr)(n * 4 * sizeof(float)), NULL,
                          GL_DYNAMIC_DRAW);
    }
    GLsizei bytes = (GLsizei)(n * 4 * sizeof(float));
    glGetTextureImage(gb->tex_position, 0, GL_RGBA, GL_FLOAT, bytes, tr->pos);
    glGetTextureImage(gb->tex_normal, 0, GL_RGBA, GL_FLOAT, bytes, tr->nrm);
    run(tr, NULL, (uint32_t)n);
    glNamedBufferSubData(tr->ssbo_pixel, 0, bytes, tr->pixel);
    return gi_gl_check("implicit_vis: traced direct light", err);
}
