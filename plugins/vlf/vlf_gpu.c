/* Propagation of the vlf light field on the GPU (see vlf_gpu.h and
 * plugins/vlf/README.md "Propagation on the GPU"). */
#define _POSIX_C_SOURCE 200809L
#include "vlf_gpu.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "gi/glsl_shared.h"
#include "gi/gpu.h"
#include "gi/shader.h"

/* The buffers, in binding order after GI_SSBO_PLUGIN_FIRST (as in
 * shaders/vlf_propagate.comp). */
enum {
    B_FACES,
    B_ELEM_FACE,
    B_ELEM_AREA,
    B_CELL_START,
    B_FRAG,
    B_FRAG_SLOT,
    B_RECV,
    B_EMAP,
    B_TMAP,
    B_STATS,
    B_GATHER,
    B_PERM,
    B_RECTS,
    B_COVER,
    B_FRAMES,
    B_JOBS
};
enum { P_SWEEP, P_GATHER, P_SCATTER, P_FINISH, P_SETTLE };

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

gi_result vlf_gpu_init(vlf_gpu *g, int raster, int sync, gi_error *err)
{
    memset(g, 0, sizeof *g);
    g->raster = raster;
    if (raster) {
        gi_result r = vlf_raster_init(&g->ras, sync, err);
        if (r != GI_OK)
            return r;
    }
    for (int p = 0; p < VLF_GPU_PASSES; p++) {
        char defines[64];
        snprintf(defines, sizeof defines, "#define VLF_PASS %d\n", p);
        gi_error e;
        g->prog[p] = gi_program_build_compute("vlf_propagate.comp", defines, &e);
        if (!g->prog[p]) {
            vlf_gpu_free(g);
            return gi_error_set(err, GI_ERR_GL, "vlf: propagation pass %d: %s", p, e.text);
        }
    }
    return GI_OK;
}

static void free_direction_arrays(vlf_gpu *g)
{
    free(g->start_base), free(g->frag_base), free(g->g_first), free(g->g_elem), free(g->g_count);
    free(g->j_first), free(g->j_count), free(g->j_cells);
}

void vlf_gpu_free(vlf_gpu *g)
{
    for (int p = 0; p < VLF_GPU_PASSES; p++)
        if (g->prog[p])
            glDeleteProgram(g->prog[p]);
    if (g->buf[0])
        glDeleteBuffers(VLF_GPU_BUFFERS, g->buf);
    free_direction_arrays(g);
    vlf_raster_free(&g->ras);
    memset(g, 0, sizeof *g);
}

static void put(GLuint b, const void *data, size_t bytes)
{
    static const uint32_t zero[4] = {0, 0, 0, 0};
    glNamedBufferData(b, (GLsizeiptr)(bytes ? bytes : sizeof zero), bytes ? data : zero,
                      GL_DYNAMIC_DRAW);
}

typedef struct gath_entry {
    uint32_t key, first, count, pad;
} gath_entry;

typedef struct job_entry {
    uint32_t src, dst, face, first_cell;
    float c[4];
} job_entry;

/* A growing array of fixed-size records. */
typedef struct grow {
    void *v;
    size_t n, cap, size;
} grow;

static void *grow_push(grow *a)
{
    if (a->n == a->cap) {
        size_t cap = a->cap ? a->cap * 2 : 1024;
        void *v = realloc(a->v, cap * a->size);
        if (!v)
            return NULL;
        a->v = v;
        a->cap = cap;
    }
    return (char *)a->v + a->size * a->n++;
}

/* The per-direction bases and counts of g for l directions, the old ones
 * freed. 1, or 0 out of memory. */
static int alloc_direction_arrays(vlf_gpu *g, uint32_t l)
{
    free_direction_arrays(g);
    g->start_base = calloc(l, sizeof(uint32_t));
    g->frag_base = calloc(l, sizeof(uint32_t));
    g->g_first = calloc(l, sizeof(uint32_t));
    g->g_elem = calloc(l, sizeof(uint32_t));
    g->g_count = calloc(l, sizeof(uint32_t));
    g->j_first = calloc(l, sizeof(uint32_t));
    g->j_count = calloc(l, sizeof(uint32_t));
    g->j_cells = calloc(l, sizeof(uint32_t));
    return g->start_base && g->frag_base && g->g_first && g->g_elem && g->g_count && g->j_first &&
           g->j_count && g->j_cells;
}

/* The largest buffer (the fragments, the element maps or the tile maps)
 * against the GL's limit on a shader storage block. */
static gi_result check_block_size(const vlf_field *f, size_t frags, gi_error *err)
{
    GLint64 max_block = 0;
    glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &max_block);
    size_t largest = frags * sizeof(uint32_t);
    if ((size_t)f->elem_count * 9 * sizeof(float) > largest)
        largest = (size_t)f->elem_count * 9 * sizeof(float);
    if ((size_t)f->nd_cells * 12 * sizeof(float) > largest)
        largest = (size_t)f->nd_cells * 12 * sizeof(float);
    if (max_block > 0 && largest > (size_t)max_block)
        return gi_error_set(
            err, GI_ERR_UNSUPPORTED,
            "vlf: propagate = gpu needs a %zu-byte buffer, the GL allows %lld (lower l, N or S)",
            largest, (long long)max_block);
    return GI_OK;
}

/* What vlf_gpu_setup puts together before the upload: every subfield's
 * cell starts, each fragment's element and tile slot, the gather lists
 * (entries, and the fragments in their order: perm) and the scatter jobs. */
typedef struct setup_lists {
    uint32_t *start, *frag, *slot, *perm;
    uint32_t *cnt, *pos, *touched; /* per element, then per tile cell: gather scratch */
    float *wg;                     /* 2l reflection weights */
    grow gath, jobs;
    size_t pfill; /* entries of perm filled */
} setup_lists;

/* 1, or 0 out of memory (free_lists frees what was had). */
static int alloc_lists(setup_lists *L, const vlf_field *f, size_t frags)
{
    uint32_t l = f->prm.l, NS = f->prm.N * f->prm.S, n2 = NS * NS;
    size_t keys = (size_t)f->elem_count + f->nd_cells + 1;
    L->start = malloc(((size_t)l * (n2 + 1)) * sizeof *L->start);
    L->frag = malloc((frags + 1) * sizeof *L->frag);
    L->slot = malloc((frags + 1) * sizeof *L->slot);
    L->perm = malloc((2 * frags + 1) * sizeof *L->perm);
    L->cnt = calloc(keys, sizeof *L->cnt);
    L->pos = calloc(keys, sizeof *L->pos);
    L->touched = malloc(keys * sizeof *L->touched);
    L->wg = malloc((size_t)2 * l * sizeof *L->wg);
    L->gath = (grow){NULL, 0, 0, sizeof(gath_entry)};
    L->jobs = (grow){NULL, 0, 0, sizeof(job_entry)};
    L->pfill = 0;
    return L->start && L->frag && L->slot && L->perm && L->cnt && L->pos && L->touched && L->wg;
}

static void free_lists(setup_lists *L)
{
    free(L->start), free(L->frag), free(L->slot), free(L->perm);
    free(L->cnt), free(L->pos), free(L->touched), free(L->wg), free(L->gath.v), free(L->jobs.v);
}

/* Subfield i's fragments from fbase on: each one's element and, on a
 * non-diffuse face, its tile slot (UINT32_MAX for none). */
static void direction_fragments(const vlf_field *f, uint32_t i, size_t fbase, setup_lists *L)
{
    const vlf_psf *ps = &f->psf[i];
    uint32_t l = f->prm.l, S = f->prm.S, NS = f->prm.N * S, n2 = NS * NS;
    for (uint32_t c = 0; c < n2; c++)
        for (uint32_t k = ps->cell_start[c]; k < ps->cell_start[c + 1]; k++) {
            uint32_t el = ps->frag[k];
            const vlf_face *fc = &f->faces[f->elem_face[el]];
            uint32_t s = UINT32_MAX;
            if (fc->nd >= 0) {
                const vlf_rect *r = &f->rects[(size_t)fc->nd * l + i];
                int32_t cx = (int32_t)((c % NS) / S), cy = (int32_t)((c / NS) / S);
                s = r->offset + (uint32_t)(cy - r->y0) * r->w + (uint32_t)(cx - r->x0);
            }
            L->frag[fbase + k] = el;
            L->slot[fbase + k] = s;
        }
}

/* Subfield i's gather lists: each element's fragments, then each tile
 * cell's, in fragment order (the order the CPU's sweep adds them in).
 * 1, or 0 out of memory. */
static int gather_lists(vlf_gpu *g, const vlf_field *f, uint32_t i, size_t fbase, setup_lists *L)
{
    const vlf_psf *ps = &f->psf[i];
    uint32_t *cnt = L->cnt, *pos = L->pos, *touched = L->touched;
    int ok = 1;
    g->g_first[i] = (uint32_t)L->gath.n;
    for (int pass = 0; pass < 2 && ok; pass++) {
        uint32_t nt = 0, koff = pass ? f->elem_count : 0;
        for (uint32_t k = 0; k < ps->frag_count; k++) {
            uint32_t key = pass ? L->slot[fbase + k] : L->frag[fbase + k];
            if (key == UINT32_MAX)
                continue;
            if (cnt[koff + key]++ == 0)
                touched[nt++] = key;
        }
        uint32_t run = (uint32_t)L->pfill;
        for (uint32_t t = 0; t < nt; t++) {
            gath_entry *ge = grow_push(&L->gath);
            if (!ge) {
                ok = 0;
                break;
            }
            *ge = (gath_entry){touched[t], run, cnt[koff + touched[t]], 0};
            pos[koff + touched[t]] = run;
            run += cnt[koff + touched[t]];
        }
        for (uint32_t k = 0; ok && k < ps->frag_count; k++) {
            uint32_t key = pass ? L->slot[fbase + k] : L->frag[fbase + k];
            if (key != UINT32_MAX)
                L->perm[pos[koff + key]++] = k;
        }
        for (uint32_t t = 0; t < nt; t++)
            cnt[koff + touched[t]] = 0;
        L->pfill = run;
        if (pass == 0)
            g->g_elem[i] = nt;
    }
    g->g_count[i] = (uint32_t)L->gath.n - g->g_first[i];
    return ok;
}

/* Subfield i's scatter jobs (§3.4, as vlf_scatter() in scatter.c): one per
 * non-diffuse face and direction it reflects into, numbering the cells of
 * the target rectangles. 1, or 0 out of memory. */
static int scatter_jobs(vlf_gpu *g, const vlf_field *f, uint32_t i, setup_lists *L)
{
    uint32_t l = f->prm.l;
    float *wg = L->wg;
    int ok = 1;
    g->j_first[i] = (uint32_t)L->jobs.n;
    uint32_t cells = 0;
    for (uint32_t fi = 0; ok && fi < f->face_count; fi++) {
        const vlf_face *fc = &f->faces[fi];
        if (fc->nd < 0)
            continue;
        const vlf_rect *ri = &f->rects[(size_t)fc->nd * l + i];
        float ci = gi_v3_dot(fc->n, f->dirs.signed_dirs[i]);
        if (ri->w == 0 || ci == 0.0f)
            continue;
        uint32_t sd_in = ci < 0.0f ? i : i + l;
        gi_vec3 t = f->dirs.signed_dirs[sd_in];
        gi_vec3 r = gi_v3_sub(t, gi_v3_scale(fc->n, 2.0f * gi_v3_dot(t, fc->n)));
        double norm = vlf_reflect_weights(f, fc, r, wg);
        if (norm <= 0.0)
            continue;
        float scale = (float)((double)fabsf(ci) * f->dirs.solid_angle[sd_in] / norm);
        for (uint32_t j = 0; j < 2 * l; j++) {
            if (wg[j] <= 0.0f)
                continue;
            uint32_t pj = j % l;
            const vlf_rect *rj = &f->rects[(size_t)fc->nd * l + pj];
            if (rj->w == 0 || fabsf(gi_v3_dot(f->psf[pj].n, fc->n)) < 1e-6f)
                continue;
            job_entry *je = grow_push(&L->jobs);
            if (!je) {
                ok = 0;
                break;
            }
            *je = (job_entry){
                (uint32_t)fc->nd * l + i, (uint32_t)fc->nd * l + pj, fi, cells, {0, 0, 0, 0}};
            for (int q = 0; q < 3; q++)
                je->c[q] = fc->ks[q] * wg[j] * scale;
            cells += rj->w * rj->h;
        }
    }
    g->j_count[i] = (uint32_t)L->jobs.n - g->j_first[i];
    g->j_cells[i] = cells;
    return ok;
}

/* Per face: normal, emission normaliser, albedo, nd, chart origin (12
 * floats). */
static void pack_faces(const vlf_field *f, float *faces)
{
    for (uint32_t i = 0; i < f->face_count; i++) {
        const vlf_face *fc = &f->faces[i];
        float *F = faces + 12 * (size_t)i;
        memcpy(F, &fc->n, 3 * sizeof(float));
        F[3] = fc->send_scale;
        memcpy(F + 4, fc->kd, 3 * sizeof(float));
        int32_t nd = fc->nd;
        memcpy(F + 7, &nd, sizeof nd);
        memcpy(F + 8, &fc->origin, 3 * sizeof(float));
    }
}

/* The faces, tile rectangles, subfield frames and coverage packed, and
 * they and the lists uploaded. 1, or 0 out of memory. */
static int upload_lists(vlf_gpu *g, const vlf_field *f, const setup_lists *L, size_t frags,
                        uint32_t max_frags)
{
    uint32_t l = f->prm.l, NS = f->prm.N * f->prm.S, n2 = NS * NS;
    float *faces = calloc((size_t)f->face_count * 12 + 4, sizeof *faces);
    int32_t *rects = calloc((size_t)f->nd_count * l * 8 + 8, sizeof *rects);
    float *frames = calloc((size_t)l * 12, sizeof *frames);
    uint8_t *cover = calloc((size_t)f->nd_cells + 4, 1);
    int ok = faces && rects && frames && cover;
    if (ok) {
        pack_faces(f, faces);
        for (size_t r = 0; r < (size_t)f->nd_count * l; r++) {
            const vlf_rect *R = &f->rects[r];
            rects[8 * r] = R->x0, rects[8 * r + 1] = R->y0;
            rects[8 * r + 2] = (int32_t)R->w, rects[8 * r + 3] = (int32_t)R->h;
            rects[8 * r + 4] = (int32_t)R->offset;
        }
        for (uint32_t i = 0; i < l; i++) {
            const vlf_psf *p = &f->psf[i];
            gi_vec3 fr[3] = {p->u, p->v, p->n};
            for (int k = 0; k < 3; k++)
                memcpy(frames + 4 * (3 * i + (uint32_t)k), &fr[k], 3 * sizeof(float));
        }
        memcpy(cover, f->nd_cover, f->nd_cells);
        put(g->buf[B_FACES], faces, (size_t)f->face_count * 12 * sizeof *faces);
        put(g->buf[B_ELEM_FACE], f->elem_face, (size_t)f->elem_count * sizeof(uint32_t));
        /* each element's area, then its albedo (3 floats) */
        glNamedBufferData(g->buf[B_ELEM_AREA],
                          (GLsizeiptr)(((size_t)f->elem_count * 4 + 4) * sizeof(float)), NULL,
                          GL_DYNAMIC_DRAW);
        glNamedBufferSubData(g->buf[B_ELEM_AREA], 0,
                             (GLsizeiptr)((size_t)f->elem_count * sizeof(float)), f->elem_area);
        glNamedBufferSubData(g->buf[B_ELEM_AREA], (GLintptr)((size_t)f->elem_count * sizeof(float)),
                             (GLsizeiptr)((size_t)f->elem_count * 3 * sizeof(float)), f->elem_kd);
        /* the rasterised sweeps need no fragment lists; their receivers
         * sum into B_RECV (per element, then per tile cell) */
        size_t nrecv = g->raster ? (size_t)f->elem_count + f->nd_cells : (size_t)max_frags + 1;
        put(g->buf[B_CELL_START], L->start,
            g->raster ? 0 : (size_t)l * (n2 + 1) * sizeof *L->start);
        put(g->buf[B_FRAG], L->frag, frags * sizeof *L->frag);
        put(g->buf[B_FRAG_SLOT], L->slot, frags * sizeof *L->slot);
        glNamedBufferData(g->buf[B_RECV],
                          (GLsizeiptr)((nrecv + 1) * 3 * (g->raster ? 2 : 1) * sizeof(float)), NULL,
                          GL_DYNAMIC_DRAW);
        glClearNamedBufferData(g->buf[B_RECV], GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, NULL);
        put(g->buf[B_GATHER], L->gath.v, L->gath.n * sizeof(gath_entry));
        put(g->buf[B_PERM], L->perm, L->pfill * sizeof *L->perm);
        put(g->buf[B_RECTS], rects, (size_t)f->nd_count * l * 8 * sizeof *rects);
        put(g->buf[B_COVER], cover, ((size_t)f->nd_cells + 3) / 4 * 4);
        put(g->buf[B_FRAMES], frames, (size_t)l * 12 * sizeof *frames);
        put(g->buf[B_JOBS], L->jobs.v, L->jobs.n * sizeof(job_entry));
    }
    free(faces), free(rects), free(frames), free(cover);
    return ok;
}

gi_result vlf_gpu_setup(vlf_gpu *g, const vlf_field *f, gi_error *err)
{
    double t0 = now_s();
    uint32_t l = f->prm.l, NS = f->prm.N * f->prm.S, n2 = NS * NS;
    if (f->prm.perturbed > 0)
        return gi_error_set(err, GI_ERR_UNSUPPORTED,
                            "vlf: propagate = %s runs the fixed directions only (perturbed = 0)",
                            g->raster ? "raster" : "gpu");
    if (!g->buf[0])
        glCreateBuffers(VLF_GPU_BUFFERS, g->buf);
    int ok = alloc_direction_arrays(g, l);
    size_t frags = 0;
    uint32_t max_frags = 0;
    for (uint32_t i = 0; i < l && !g->raster; i++) {
        frags += f->psf[i].frag_count;
        if (f->psf[i].frag_count > max_frags)
            max_frags = f->psf[i].frag_count;
    }
    gi_result r = check_block_size(f, frags, err);
    if (r != GI_OK)
        return r;
    setup_lists L;
    ok = alloc_lists(&L, f, frags) && ok;
    size_t fbase = 0;
    for (uint32_t i = 0; ok && i < l; i++) {
        const vlf_psf *ps = &f->psf[i];
        g->start_base[i] = i * (n2 + 1);
        g->frag_base[i] = (uint32_t)fbase;
        if (!g->raster) {
            memcpy(L.start + (size_t)i * (n2 + 1), ps->cell_start, (n2 + 1) * sizeof *L.start);
            direction_fragments(f, i, fbase, &L);
            ok = gather_lists(g, f, i, fbase, &L);
            fbase += ps->frag_count;
        }
        ok = ok && scatter_jobs(g, f, i, &L);
    }
    ok = ok && upload_lists(g, f, &L, frags, max_frags);
    free_lists(&L);
    if (!ok)
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY,
                            "vlf: out of memory setting up the GPU propagation");
    if (g->raster && (r = vlf_raster_setup(&g->ras, g->buf, f, err)) != GI_OK)
        return r;
    r = gi_gl_check("vlf: GPU propagation set-up", err);
    if (r != GI_OK)
        return r;
    g->setup_s = now_s() - t0;
    return GI_OK;
}

/* Dispatches `count` invocations of 64 (x, then y past 65535 groups), z
 * layers. */
static void dispatch(uint32_t count, uint32_t z)
{
    uint32_t groups = (count + 63) / 64;
    if (groups == 0)
        return;
    uint32_t gx = groups < 65535 ? groups : 65535, gy = (groups + gx - 1) / gx;
    glDispatchCompute(gx, gy, z);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
}

static void set_u(GLuint p, const char *name, uint32_t v)
{
    glProgramUniform1ui(p, glGetUniformLocation(p, name), v);
}

static void set_f(GLuint p, const char *name, float v)
{
    glProgramUniform1f(p, glGetUniformLocation(p, name), v);
}

/* The maps as vlf_propagate_init left them, and the flux counters
 * cleared, uploaded; every buffer bound. */
static void upload_maps(vlf_gpu *g, const vlf_field *f, uint32_t n2)
{
    size_t ne = (size_t)f->elem_count * 3, nc = (size_t)f->nd_cells * 3;
    glNamedBufferData(g->buf[B_EMAP], (GLsizeiptr)((3 * ne + 3) * sizeof(float)), NULL,
                      GL_DYNAMIC_DRAW);
    glNamedBufferSubData(g->buf[B_EMAP], 0, (GLsizeiptr)(ne * sizeof(float)), f->E_next);
    glNamedBufferSubData(g->buf[B_EMAP], (GLintptr)(ne * sizeof(float)),
                         (GLsizeiptr)(ne * sizeof(float)), f->E_tot);
    glNamedBufferSubData(g->buf[B_EMAP], (GLintptr)(2 * ne * sizeof(float)),
                         (GLsizeiptr)(ne * sizeof(float)), f->L_cur);
    glNamedBufferData(g->buf[B_TMAP], (GLsizeiptr)((4 * nc + 3) * sizeof(float)), NULL,
                      GL_DYNAMIC_DRAW);
    glClearNamedBufferData(g->buf[B_TMAP], GL_R32F, GL_RED, GL_FLOAT, NULL);
    glNamedBufferSubData(g->buf[B_TMAP], (GLintptr)(nc * sizeof(float)),
                         (GLsizeiptr)(nc * sizeof(float)), f->out_next);
    glNamedBufferData(g->buf[B_STATS], (GLsizeiptr)((size_t)2 * n2 * 4 * sizeof(float)), NULL,
                      GL_DYNAMIC_DRAW);
    glClearNamedBufferData(g->buf[B_STATS], GL_R32F, GL_RED, GL_FLOAT, NULL);
    for (int b = 0; b < VLF_GPU_BUFFERS; b++)
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, GI_SSBO_PLUGIN_FIRST + (GLuint)b, g->buf[b]);
}

/* The uniforms every pass keeps through the propagation. */
static void set_constants(vlf_gpu *g, const vlf_field *f, float cell_area)
{
    uint32_t S = f->prm.S;
    size_t ne = (size_t)f->elem_count * 3, nc = (size_t)f->nd_cells * 3;
    for (int p = 0; p < VLF_GPU_PASSES; p++) {
        GLuint P = g->prog[p];
        set_u(P, "u_precision", f->prm.precision);
        set_u(P, "u_ne", (uint32_t)ne);
        set_u(P, "u_nc", (uint32_t)nc);
        set_u(P, "u_l", f->prm.l);
        set_u(P, "u_N", f->prm.N);
        set_f(P, "u_cell_area", cell_area);
        set_f(P, "u_min_area", 1.0f / (64.0f * f->prm.density * f->prm.density));
        set_f(P, "u_inv_s2", 1.0f / (float)(S * S));
    }
}

/* Fixed direction i in one iteration: the sweeps both ways, then the
 * gathers and the scattering of subfield i. */
static void run_direction(vlf_gpu *g, vlf_field *f, uint32_t i, int first_iteration,
                          float cell_area)
{
    uint32_t l = f->prm.l, NS = f->prm.N * f->prm.S, n2 = NS * NS;
    float t[6], sky[6], w[2], dW[2];
    for (int s = 0; s < 2; s++) {
        uint32_t sd = s == 0 ? i : i + l;
        memcpy(t + 3 * s, &f->dirs.signed_dirs[sd], 3 * sizeof(float));
        vlf_sweep_sky(f, i, s == 0 ? 1 : -1, first_iteration, sky + 3 * s);
        dW[s] = f->dirs.solid_angle[sd];
        w[s] = (float)((double)cell_area * dW[s] / 3.0);
    }
    for (int p = 0; p < 3; p++) {
        GLuint P = g->prog[p];
        set_u(P, "u_i", i);
        glProgramUniform3fv(P, glGetUniformLocation(P, "u_t"), 2, t);
        glProgramUniform1fv(P, glGetUniformLocation(P, "u_dW"), 2, dW);
    }
    GLuint P;
    if (!g->raster) {
        P = g->prog[P_SWEEP];
        glUseProgram(P);
        set_u(P, "u_count", n2);
        set_u(P, "u_start_base", g->start_base[i]);
        set_u(P, "u_frag_base", g->frag_base[i]);
        glProgramUniform3fv(P, glGetUniformLocation(P, "u_sky"), 2, sky);
        glProgramUniform1fv(P, glGetUniformLocation(P, "u_w"), 2, w);
        dispatch(n2, 2);
    }
    if (!g->raster && g->g_count[i]) {
        P = g->prog[P_GATHER];
        glUseProgram(P);
        set_u(P, "u_count", g->g_count[i]);
        set_u(P, "u_first", g->g_first[i]);
        set_u(P, "u_n_elem", g->g_elem[i]);
        dispatch(g->g_count[i], 1);
    }
    if (g->j_count[i]) {
        P = g->prog[P_SCATTER];
        glUseProgram(P);
        set_u(P, "u_count", g->j_cells[i]);
        set_u(P, "u_first", g->j_first[i]);
        set_u(P, "u_n_elem", g->j_count[i]);
        dispatch(g->j_cells[i], 1);
    }
    f->st.samples += 2 * (uint64_t)f->psf[i].frag_count;
}

/* One iteration by the rasteriser: the sweeps of every direction drawn
 * (vlf_raster.c), what the receivers brought settled into the maps, then
 * each direction's scattering as above (the directions of an iteration
 * read only its current maps, so their sweeps may all come first). */
static gi_result run_raster_iteration(vlf_gpu *g, vlf_field *f, int first_iteration,
                                      float cell_area, int (*cancelled)(void *), void *user,
                                      gi_error *err)
{
    gi_result r = vlf_raster_iteration(&g->ras, f, first_iteration, cancelled, user, err);
    if (r != GI_OK)
        return r;
    GLuint P = g->prog[P_SETTLE];
    glUseProgram(P);
    uint32_t n = f->elem_count > f->nd_cells ? f->elem_count : f->nd_cells;
    set_u(P, "u_count", n);
    dispatch(n, 1);
    for (uint32_t i = 0; i < f->prm.l; i++)
        run_direction(g, f, i, first_iteration, cell_area);

    return GI_OK;
}

/* The end of an iteration (the finish pass). */
static void run_finish(vlf_gpu *g, const vlf_field *f)
{
    GLuint P = g->prog[P_FINISH];
    glUseProgram(P);
    uint32_t n = f->elem_count > f->nd_cells ? f->elem_count : f->nd_cells;
    set_u(P, "u_count", n);
    dispatch(n, 1);
}

/* The maps and the flux counters back into the field. */
static gi_result read_back(vlf_gpu *g, vlf_field *f, uint32_t n2, gi_error *err)
{
    size_t ne = (size_t)f->elem_count * 3, nc = (size_t)f->nd_cells * 3;
    glGetNamedBufferSubData(g->buf[B_EMAP], 0, (GLsizeiptr)(ne * sizeof(float)), f->E_next);
    glGetNamedBufferSubData(g->buf[B_EMAP], (GLintptr)(ne * sizeof(float)),
                            (GLsizeiptr)(ne * sizeof(float)), f->E_tot);
    glGetNamedBufferSubData(g->buf[B_EMAP], (GLintptr)(2 * ne * sizeof(float)),
                            (GLsizeiptr)(ne * sizeof(float)), f->L_cur);
    glGetNamedBufferSubData(g->buf[B_TMAP], 0, (GLsizeiptr)(nc * sizeof(float)), f->out_cur);
    glGetNamedBufferSubData(g->buf[B_TMAP], (GLintptr)(nc * sizeof(float)),
                            (GLsizeiptr)(nc * sizeof(float)), f->out_next);
    glGetNamedBufferSubData(g->buf[B_TMAP], (GLintptr)(2 * nc * sizeof(float)),
                            (GLsizeiptr)(nc * sizeof(float)), f->out_tot);
    glGetNamedBufferSubData(g->buf[B_TMAP], (GLintptr)(3 * nc * sizeof(float)),
                            (GLsizeiptr)(nc * sizeof(float)), f->in);
    if (g->raster)
        return vlf_raster_counters(&g->ras, f, err);
    float *st = malloc((size_t)2 * n2 * 4 * sizeof *st);
    if (!st)
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY,
                            "vlf: out of memory reading the GPU's counters");
    glGetNamedBufferSubData(g->buf[B_STATS], 0, (GLsizeiptr)((size_t)2 * n2 * 4 * sizeof *st), st);
    double sum[4] = {0, 0, 0, 0};
    for (size_t k = 0; k < (size_t)2 * n2; k++)
        for (int q = 0; q < 4; q++)
            sum[q] += st[4 * k + (size_t)q];
    free(st);
    f->st.flux_shot = sum[0], f->st.flux_received = sum[1], f->st.flux_back = sum[2],
    f->st.flux_escaped = sum[3];
    return GI_OK;
}

gi_result vlf_gpu_propagate(vlf_gpu *g, vlf_field *f, int (*cancelled)(void *), void *user,
                            gi_error *err)
{
    double t0 = now_s();
    uint32_t NS = f->prm.N * f->prm.S, n2 = NS * NS;
    gi_result rc = vlf_propagate_init(f, err);
    if (rc != GI_OK)
        return rc;
    upload_maps(g, f, n2);
    float cell_area = (2.0f / (float)NS) * (2.0f / (float)NS);
    set_constants(g, f, cell_area);
    if (g->raster) {
        vlf_raster_constants(&g->ras, f, cell_area);
        vlf_raster_clear_counters(&g->ras);
    }
    for (uint32_t it = 0; it < f->prm.iterations && rc == GI_OK; it++) {
        if (g->raster)
            rc = run_raster_iteration(g, f, it == 0, cell_area, cancelled, user, err);
        for (uint32_t i = 0; i < f->prm.l && !g->raster; i++) {
            if (cancelled && cancelled(user)) {
                rc = gi_error_set(err, GI_ERR_CANCELLED, "vlf: propagation cancelled");
                break;
            }
            run_direction(g, f, i, it == 0, cell_area);
        }
        if (rc != GI_OK)
            break;
        run_finish(g, f);
    }
    glUseProgram(0);
    double t1 = now_s();
    if (rc == GI_OK) {
        rc = read_back(g, f, n2, err);
        if (rc != GI_OK)
            return rc;
        rc = gi_gl_check("vlf: GPU propagation", err);
    }
    g->readback_s = now_s() - t1;
    f->st.propagate_s = now_s() - t0;
    return rc;
}
