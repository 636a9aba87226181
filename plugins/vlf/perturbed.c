/* The perturbed directions of the vlf method (paper §3.5): around each
 * fixed direction, directions drawn in the solid angle it stands for,
 * sorted like fixed ones, used for transport only and discarded; their
 * sorting runs on the CPU beside the propagation. */
#define _POSIX_C_SOURCE 200809L
#include "field_internal.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <pthread.h>

#include "gi/envmap.h"

/* Fragments of all faces along a perturbed direction (frame fr), sorted
 * per ray front to back; kept with their depths (§3.5: perturbed
 * directions are sorted like fixed ones, used for transport, discarded). */
static gi_result perturbed_list(vlf_field *f, const vlf_psf *fr, vlf_frag_buf *buf,
                                vlf_frag_buf *tmp, vlf_sorter *so)
{
    vlf_sort_counts cnt = {0, 0, 0, 0, 0, 0, 0};
    return vlf_list_fragments(f, fr, buf, tmp, so, NULL, &cnt);
}

/* The tile slot of non-diffuse face fc in fixed subfield i holding VLF
 * point q, or SIZE_MAX where q's cell is outside the face there. */
static size_t slot_at(const vlf_field *f, const vlf_face *fc, uint32_t i, gi_vec3 q)
{
    float x, y, z;
    vlf_psf_project(f, i, q, &x, &y, &z);
    const vlf_rect *r = &f->rects[(size_t)fc->nd * f->prm.l + i];
    int cx = (int)floorf(x) - r->x0, cy = (int)floorf(y) - r->y0;
    if (cx < 0 || cy < 0 || cx >= (int)r->w || cy >= (int)r->h)
        return SIZE_MAX;
    size_t slot = r->offset + (size_t)cy * r->w + (size_t)cx;
    return f->nd_cover[slot] ? slot : SIZE_MAX;
}

/* A sweep along a perturbed direction fr->n (sign: +n or -n) standing in
 * for fixed direction i with weight dW: as sweep() in propagate.c, but non-diffuse
 * faces read and write the tiles of fixed subfield i at each fragment's
 * point. */
static void sweep_perturbed(vlf_field *f, uint32_t i, const vlf_psf *fr, const vlf_frag_buf *buf,
                            int sign, float dW, int first_iteration)
{
    uint32_t S = f->prm.S, N = f->prm.N * S;
    float inv_s2 = 1.0f / (float)(S * S);
    gi_vec3 t = gi_v3_scale(fr->n, (float)sign);
    float cell_area = (2.0f / (float)N) * (2.0f / (float)N);
    float min_area = 1.0f / (64.0f * f->prm.density * f->prm.density);
    float sky[3] = {0, 0, 0};
    if (first_iteration && f->env)
        gi_envmap_eval(f->env, gi_v3_scale(t, -1.0f), sky);
    if (first_iteration)
        for (int q = 0; q < 3; q++)
            sky[q] += f->sun[3 * (sign > 0 ? i : i + f->prm.l) + (uint32_t)q];
    double shot = 0, recv = 0, back = 0, esc = 0;
    size_t a = 0;
    while (a < buf->n) {
        size_t e = a;
        while (e < buf->n && buf->v[e].cell == buf->v[a].cell)
            e++;
        uint32_t c = buf->v[a].cell;
        float U = ((float)(c % N) + 0.5f) / (float)N * 2.0f - 1.0f,
              V = ((float)(c / N) + 0.5f) / (float)N * 2.0f - 1.0f;
        gi_vec3 o = gi_v3_add(gi_v3_scale(fr->u, U), gi_v3_scale(fr->v, V));
        float L[3] = {sky[0], sky[1], sky[2]};
        for (size_t j = 0; j < e - a; j++) {
            const vlf_frag *fg = &buf->v[sign > 0 ? a + j : e - 1 - j];
            uint32_t el = fg->elem;
            const vlf_face *fc = &f->faces[f->elem_face[el]];
            float cs = gi_v3_dot(fc->n, t);
            float lum = L[0] + L[1] + L[2];
            size_t slot = SIZE_MAX;
            if (fc->nd >= 0 && cs != 0.0f)
                slot = slot_at(f, fc, i, gi_v3_add(o, gi_v3_scale(fr->n, fg->depth)));
            if (cs < 0.0f) {
                float s = cell_area * dW / fmaxf(f->elem_area[el], min_area);
                for (int q = 0; q < 3; q++)
                    f->E_next[3 * (size_t)el + q] += L[q] * s;
                if (slot != SIZE_MAX)
                    for (int q = 0; q < 3; q++)
                        f->in[3 * slot + q] += L[q] * inv_s2 / (float)f->prm.perturbed;
                recv += lum;
                /* as in propagate.c's sweep: it goes on past a face lit
                 * on its front, and stops at a face met on its back */
            } else if (cs > 0.0f) {
                back += lum;
                L[0] = L[1] = L[2] = 0.0f;
                float own[3];
                for (int q = 0; q < 3; q++)
                    own[q] = f->L_cur[3 * (size_t)el + q] * fc->send_scale;
                if (slot != SIZE_MAX)
                    for (int q = 0; q < 3; q++)
                        own[q] += f->out_cur[3 * slot + q];
                for (int q = 0; q < 3; q++)
                    L[q] += own[q];
                shot += own[0] + own[1] + own[2];
            }
            f->st.samples++;
        }
        esc += L[0] + L[1] + L[2];
        a = e;
    }
    double w = (double)cell_area * dW / 3.0;
    f->st.flux_shot += shot * w;
    f->st.flux_received += recv * w;
    f->st.flux_back += back * w;
    f->st.flux_escaped += esc * w;
}

/* Perturbed direction k of fixed direction i: uniform in the cap of solid
 * angle dOmega_i around w_i (the paper's samples spread over the solid
 * angle each fixed direction stands for), from a hash of (seed, i, k). */
static gi_vec3 perturbed_dir(const vlf_field *f, uint32_t i, uint32_t k)
{
    uint32_t h = f->prm.seed * 0x9E3779B9u ^ (i * 0x85EBCA6Bu) ^ (k * 0xC2B2AE35u);
    float u[2];
    for (int j = 0; j < 2; j++) {
        h ^= h >> 16;
        h *= 0x7FEB352Du;
        h ^= h >> 15;
        h *= 0x846CA68Bu;
        h ^= h >> 16;
        u[j] = (float)(h >> 8) / 16777216.0f;
    }
    float cos_max = 1.0f - f->dirs.solid_angle[i] / (2.0f * GI_PI);
    float cz = 1.0f - u[0] * (1.0f - cos_max), sz = sqrtf(fmaxf(0.0f, 1.0f - cz * cz));
    float phi = 2.0f * GI_PI * u[1];
    const vlf_psf *p = &f->psf[i];
    return gi_v3_normalize(
        gi_v3_add(gi_v3_scale(p->n, cz),
                  gi_v3_add(gi_v3_scale(p->u, sz * cosf(phi)), gi_v3_scale(p->v, sz * sinf(phi)))));
}

/* The sorting of one fixed direction's perturbed directions beside its
 * propagation (§3.5: "carried out on the CPU in parallel with
 * propagation"): worker threads build the fragment lists of perturbed
 * directions k = t, t + T, ... into their slots, while the propagating
 * thread sweeps them in order k = 0, 1, ... as they become ready (the
 * same lists and the same order of sweeps for any thread count). */
typedef struct pert_pipe {
    vlf_field *f;
    uint32_t i, T, P;
    vlf_frag_buf *slot; /* P fragment lists */
    vlf_psf *frame;     /* P frames */
    uint8_t *ready;     /* P: 0 not yet, 1 ready, 2 failed */
    int sync;           /* the mutex and condition are set up (and the rest owned) */
    pthread_mutex_t mu;
    pthread_cond_t cv;
} pert_pipe;

typedef struct pert_worker {
    pert_pipe *pp;
    uint32_t t;
    vlf_frag_buf tmp;
    vlf_sorter so;
} pert_worker;

/* The perturbed directions' state during propagation: the lists sorted in
 * line (one thread), or the pipe and its workers. */
struct vlf_perturbed {
    vlf_field *f;
    vlf_frag_buf buf, tmp;
    vlf_sorter so;
    int pipelined;
    pert_pipe pp;
    pert_worker *wk;
};

static void *pert_thread(void *arg)
{
    pert_worker *w = arg;
    pert_pipe *pp = w->pp;
    int ok = 1;
    for (uint32_t k = w->t; k < pp->P; k += pp->T) {
        if (ok) {
            vlf_psf *fr = &pp->frame[k];
            fr->n = perturbed_dir(pp->f, pp->i, k);
            gi_onb(fr->n, &fr->u, &fr->v);
            ok = perturbed_list(pp->f, fr, &pp->slot[k], &w->tmp, &w->so) == GI_OK;
        }
        pthread_mutex_lock(&pp->mu);
        pp->ready[k] = ok ? 1 : 2;
        pthread_cond_broadcast(&pp->cv);
        pthread_mutex_unlock(&pp->mu);
    }
    return NULL;
}

static void pipe_free(pert_pipe *pp, pert_worker *wk)
{
    if (!pp->sync)
        return;
    for (uint32_t k = 0; k < pp->P; k++)
        free(pp->slot[k].v);
    for (uint32_t t = 0; t < pp->T; t++) {
        free(wk[t].tmp.v);
        vlf_sorter_free(&wk[t].so);
    }
    free(pp->slot), free(pp->frame), free(pp->ready), free(wk);
    pthread_mutex_destroy(&pp->mu);
    pthread_cond_destroy(&pp->cv);
    pp->sync = 0;
}

/* The perturbed sweeps of fixed direction i with the lists sorted beside
 * them on T threads. */
static gi_result perturbed_pipelined(vlf_field *f, uint32_t i, int first_iteration, pert_pipe *pp,
                                     pert_worker *wk)
{
    uint32_t T = pp->T, P = pp->P, l = f->prm.l, prec = f->prm.precision;
    pp->i = i;
    memset(pp->ready, 0, P);
    pthread_t *th = calloc(T, sizeof *th);
    uint8_t *started = calloc(T, 1);
    if (!th || !started) {
        free(th), free(started);
        return GI_ERR_OUT_OF_MEMORY;
    }
    for (uint32_t t = 0; t < T; t++)
        started[t] = pthread_create(&th[t], NULL, pert_thread, &wk[t]) == 0;
    for (uint32_t t = 0; t < T; t++)
        if (!started[t])
            pert_thread(&wk[t]); /* no thread to be had: its share here */
    int ok = 1;
    for (uint32_t k = 0; k < P && ok; k++) {
        pthread_mutex_lock(&pp->mu);
        while (pp->ready[k] == 0)
            pthread_cond_wait(&pp->cv, &pp->mu);
        ok = pp->ready[k] == 1;
        pthread_mutex_unlock(&pp->mu);
        if (!ok)
            break;
        /* each sign's solid angle: the fixed direction's, shared */
        sweep_perturbed(f, i, &pp->frame[k], &pp->slot[k], +1, f->dirs.solid_angle[i] / (float)P,
                        first_iteration);
        vlf_quantise(prec, f->E_next, f->elem_count);
        sweep_perturbed(f, i, &pp->frame[k], &pp->slot[k], -1,
                        f->dirs.solid_angle[i + l] / (float)P, first_iteration);
        vlf_quantise(prec, f->E_next, f->elem_count);
    }
    for (uint32_t t = 0; t < T; t++)
        if (started[t])
            pthread_join(th[t], NULL);
    free(th), free(started);
    return ok ? GI_OK : GI_ERR_OUT_OF_MEMORY;
}

/* Sets up the pipe of P = f->prm.perturbed lists sorted on
 * min(f->prm.threads, P) worker threads (*wk, one per thread); 0 out of
 * memory (nothing then left to free). */
static int pipe_init(pert_pipe *pp, pert_worker **wk, vlf_field *f)
{
    pp->f = f;
    pp->T = f->prm.threads < f->prm.perturbed ? f->prm.threads : f->prm.perturbed;
    pp->P = f->prm.perturbed;
    pp->slot = calloc(pp->P, sizeof *pp->slot);
    pp->frame = calloc(pp->P, sizeof *pp->frame);
    pp->ready = calloc(pp->P, 1);
    *wk = calloc(pp->T, sizeof **wk);
    int ok = pp->slot && pp->frame && pp->ready && *wk && pthread_mutex_init(&pp->mu, NULL) == 0;
    if (ok && pthread_cond_init(&pp->cv, NULL) != 0) {
        pthread_mutex_destroy(&pp->mu);
        ok = 0;
    }
    if (!ok) {
        free(pp->slot), free(pp->frame), free(pp->ready), free(*wk);
        return 0;
    }
    pp->sync = 1;
    for (uint32_t t = 0; t < pp->T; t++)
        (*wk)[t].pp = pp, (*wk)[t].t = t;
    return 1;
}

/* The perturbed sweeps of fixed direction i with each list sorted just
 * before its sweeps on the propagating thread. */
static gi_result perturbed_in_line(vlf_perturbed *pt, uint32_t i, int first_iteration)
{
    vlf_field *f = pt->f;
    uint32_t l = f->prm.l, prec = f->prm.precision;
    for (uint32_t k = 0; k < f->prm.perturbed; k++) {
        vlf_psf fr;
        fr.n = perturbed_dir(f, i, k);
        gi_onb(fr.n, &fr.u, &fr.v);
        if (perturbed_list(f, &fr, &pt->buf, &pt->tmp, &pt->so) != GI_OK)
            return GI_ERR_OUT_OF_MEMORY;
        /* each sign's solid angle: the fixed direction's, shared */
        sweep_perturbed(f, i, &fr, &pt->buf, +1, f->dirs.solid_angle[i] / (float)f->prm.perturbed,
                        first_iteration);
        vlf_quantise(prec, f->E_next, f->elem_count);
        sweep_perturbed(f, i, &fr, &pt->buf, -1,
                        f->dirs.solid_angle[i + l] / (float)f->prm.perturbed, first_iteration);
        vlf_quantise(prec, f->E_next, f->elem_count);
    }
    return GI_OK;
}

vlf_perturbed *vlf_perturbed_create(vlf_field *f)
{
    vlf_perturbed *pt = calloc(1, sizeof *pt);
    if (!pt)
        return NULL;
    pt->f = f;
    pt->pipelined = f->prm.threads > 1;
    if (pt->pipelined && !pipe_init(&pt->pp, &pt->wk, f)) {
        free(pt);
        return NULL;
    }
    return pt;
}

gi_result vlf_perturbed_sweeps(vlf_perturbed *pt, uint32_t i, int first_iteration)
{
    return pt->pipelined ? perturbed_pipelined(pt->f, i, first_iteration, &pt->pp, pt->wk)
                         : perturbed_in_line(pt, i, first_iteration);
}

void vlf_perturbed_free(vlf_perturbed *pt)
{
    if (!pt)
        return;
    pipe_free(&pt->pp, pt->wk);
    free(pt->buf.v), free(pt->tmp.v), vlf_sorter_free(&pt->so);
    free(pt);
}
