/* The parallel subfields of the vlf method (paper §2.1, §3.2): each fixed
 * direction's frame, the rasterisation of the faces onto its N S x N S
 * interface rays, and the depth order of every ray's fragments (the
 * "sort" stage, on several threads), with the tile rectangles of the
 * non-diffuse faces (§3.1) recorded on the way. */
#define _POSIX_C_SOURCE 200809L
#include "field_internal.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <pthread.h>

gi_vec3 vlf_to_vlf(const vlf_field *f, gi_vec3 world)
{
    return gi_v3_scale(gi_v3_sub(world, f->centre), 1.0f / f->radius);
}

void vlf_psf_project(const vlf_field *f, uint32_t i, gi_vec3 q, float *x, float *y, float *depth)
{
    const vlf_psf *p = &f->psf[i];
    float N = (float)f->prm.N;
    *x = (gi_v3_dot(q, p->u) + 1.0f) * 0.5f * N;
    *y = (gi_v3_dot(q, p->v) + 1.0f) * 0.5f * N;
    *depth = gi_v3_dot(q, p->n);
}

/* Elements: texels of the face's chart, density per unit length. */
uint32_t vlf_element_at(const vlf_field *f, const vlf_face *fc, gi_vec3 q)
{
    gi_vec3 d = gi_v3_sub(q, fc->origin);
    float x = gi_v3_dot(d, fc->t) * f->prm.density, y = gi_v3_dot(d, fc->b) * f->prm.density;
    int ix = (int)floorf(x), iy = (int)floorf(y);
    ix = ix < 0 ? 0 : ix >= (int)fc->W ? (int)fc->W - 1 : ix;
    iy = iy < 0 ? 0 : iy >= (int)fc->H ? (int)fc->H - 1 : iy;
    return fc->first_elem + (uint32_t)iy * fc->W + (uint32_t)ix;
}

static int frag_push(vlf_frag_buf *b, uint32_t cell, float depth, uint32_t rank, uint32_t elem)
{
    if (b->n == b->cap) {
        size_t cap = b->cap ? b->cap * 2 : 4096;
        vlf_frag *v = realloc(b->v, cap * sizeof *v);
        if (!v)
            return 0;
        b->v = v;
        b->cap = cap;
    }
    b->v[b->n++] = (vlf_frag){cell, depth, rank, elem};
    return 1;
}

/* Rasterises face fi orthographically into subfield i (cell centres inside
 * the projected triangle). Calls emit for each covered cell. */
typedef int (*cell_fn)(void *user, uint32_t cx, uint32_t cy, float depth);

static int raster_tri(const vlf_field *f, const vlf_psf *fr, const gi_vec3 *p, cell_fn emit,
                      void *user)
{
    float x[3], y[3], z[3];
    float NS = (float)(f->prm.N * f->prm.S);
    for (int k = 0; k < 3; k++) {
        x[k] = (gi_v3_dot(p[k], fr->u) + 1.0f) * 0.5f * NS;
        y[k] = (gi_v3_dot(p[k], fr->v) + 1.0f) * 0.5f * NS;
        z[k] = gi_v3_dot(p[k], fr->n);
    }
    float area2 = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
    if (fabsf(area2) < 1e-9f)
        return 1;
    int N = (int)(f->prm.N * f->prm.S);
    int x0 = (int)floorf(fminf(x[0], fminf(x[1], x[2])) - 0.5f),
        x1 = (int)ceilf(fmaxf(x[0], fmaxf(x[1], x[2])));
    int y0 = (int)floorf(fminf(y[0], fminf(y[1], y[2])) - 0.5f),
        y1 = (int)ceilf(fmaxf(y[0], fmaxf(y[1], y[2])));
    if (x0 < 0)
        x0 = 0;
    if (y0 < 0)
        y0 = 0;
    if (x1 > N - 1)
        x1 = N - 1;
    if (y1 > N - 1)
        y1 = N - 1;
    float inv = 1.0f / area2;
    for (int cy = y0; cy <= y1; cy++) {
        float py = (float)cy + 0.5f;
        for (int cx = x0; cx <= x1; cx++) {
            float px = (float)cx + 0.5f;
            float w1 = ((px - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (py - y[0])) * inv;
            float w2 = ((x[1] - x[0]) * (py - y[0]) - (px - x[0]) * (y[1] - y[0])) * inv;
            float w0 = 1.0f - w1 - w2;
            if (w0 < 0.0f || w1 < 0.0f || w2 < 0.0f)
                continue;
            float depth = w0 * z[0] + w1 * z[1] + w2 * z[2];
            if (!emit(user, (uint32_t)cx, (uint32_t)cy, depth))
                return 0;
        }
    }
    return 1;
}

typedef struct sort_ctx {
    vlf_frag_buf *buf;
    const vlf_field *f;
    const vlf_psf *psf;
    const vlf_face *face;
    uint32_t N;
    int32_t *bbox; /* minx, miny, maxx, maxy of the face in this subfield */
} sort_ctx;

static int emit_frag(void *user, uint32_t cx, uint32_t cy, float depth)
{
    sort_ctx *c = user;
    int32_t *bb = c->bbox;
    int32_t X = (int32_t)(cx / c->f->prm.S),
            Y = (int32_t)(cy / c->f->prm.S); /* the subfield's cell */
    if (X < bb[0])
        bb[0] = X;
    if (Y < bb[1])
        bb[1] = Y;
    if (X > bb[2])
        bb[2] = X;
    if (Y > bb[3])
        bb[3] = Y;
    float U = ((float)cx + 0.5f) / (float)c->N * 2.0f - 1.0f,
          V = ((float)cy + 0.5f) / (float)c->N * 2.0f - 1.0f;
    gi_vec3 q = gi_v3_add(gi_v3_add(gi_v3_scale(c->psf->u, U), gi_v3_scale(c->psf->v, V)),
                          gi_v3_scale(c->psf->n, depth));
    uint32_t e = vlf_element_at(c->f, c->face, q);
    if (c->face->twin < 0)
        return frag_push(c->buf, cy * c->N + cx, depth, 0, e);
    /* A double-sided face (§3.1: values for both sides): two fragments at
     * the same depth, first the side facing against +w (the receiver of the
     * sweep along +w), then the side facing along +w; the sweep along -w
     * walks them the other way, so each sweep meets its receiver first and
     * its sender second. The two charts are the same, so the element index
     * differs by the charts' offset. */
    const vlf_face *tw = &c->f->faces[c->face->twin];
    uint32_t e2 = tw->first_elem + (e - c->face->first_elem);
    int own_first = gi_v3_dot(c->face->n, c->psf->n) < 0.0f;
    return frag_push(c->buf, cy * c->N + cx, depth, 0, own_first ? e : e2) &&
           frag_push(c->buf, cy * c->N + cx, depth, 1, own_first ? e2 : e);
}

static int frag_cmp(const void *a, const void *b)
{
    const vlf_frag *x = a, *y = b;
    if (x->cell != y->cell)
        return x->cell < y->cell ? -1 : 1;
    if (x->depth != y->depth)
        return x->depth < y->depth ? -1 : 1;
    if (x->rank != y->rank)
        return x->rank < y->rank ? -1 : 1;
    return x->elem < y->elem ? -1 : (x->elem > y->elem);
}

gi_result vlf_list_fragments(const vlf_field *f, const vlf_psf *fr, vlf_frag_buf *buf,
                             vlf_frag_buf *tmp, vlf_sorter *so, int32_t *bbox, vlf_sort_counts *cnt)
{
    uint32_t N = f->prm.N * f->prm.S;
    int32_t dummy[4];
    buf->n = 0;
    if (f->prm.order == VLF_ORDER_RAYS) {
        for (uint32_t ti = 0; ti < f->sort_count; ti++) {
            uint32_t fi = f->sort_face[ti];
            sort_ctx c = {buf, f, fr, &f->faces[fi], N, bbox ? bbox + 4 * fi : dummy};
            if (!raster_tri(f, fr, f->sort_p + 3 * (size_t)ti, emit_frag, &c))
                return GI_ERR_OUT_OF_MEMORY;
        }
        qsort(buf->v, buf->n, sizeof *buf->v, frag_cmp);
        return GI_OK;
    }
    int mode = f->prm.order == VLF_ORDER_PLAIN     ? VLF_SORT_PLAIN
               : f->prm.order == VLF_ORDER_NOSPLIT ? VLF_SORT_NOSPLIT
                                                   : VLF_SORT_NEWELL;
    so->cancelled = f->prm.cancelled; /* a cancel stops the sort within 1024 candidates */
    so->cancel_user = f->prm.cancel_user;
    gi_result sr = vlf_sort_faces(so, f->sort_p, f->sort_count, f->sort_group, f->prm.hier_min,
                                  fr->u, fr->v, fr->n, mode, f->prm.bsp_levels, f->prm.bsp_min);
    if (sr != GI_OK)
        return sr;
    cnt->pieces += so->nout;
    cnt->splits += so->splits;
    cnt->bsp_cuts += so->bsp_cuts;
    cnt->unresolved += so->unresolved;
    cnt->tests += so->tests;
    cnt->groups += so->groups;
    cnt->fallbacks += so->hier_fallbacks;
    for (uint32_t k = 0; k < so->nout; k++) {
        const vlf_piece *pc = &so->poly[so->out[k]];
        uint32_t fi = f->sort_face[pc->tri];
        sort_ctx c = {buf, f, fr, &f->faces[fi], N, bbox ? bbox + 4 * fi : dummy};
        /* back from the frame to VLF coordinates; a fan over the convex piece */
        gi_vec3 q[3];
        const gi_vec3 *v = so->vert + pc->first;
        for (uint32_t j = 1; j + 1 < pc->count; j++) {
            const gi_vec3 *w[3] = {&v[0], &v[j], &v[j + 1]};
            for (int a = 0; a < 3; a++)
                q[a] =
                    gi_v3_add(gi_v3_add(gi_v3_scale(fr->u, w[a]->x), gi_v3_scale(fr->v, w[a]->y)),
                              gi_v3_scale(fr->n, w[a]->z));
            if (!raster_tri(f, fr, q, emit_frag, &c))
                return GI_ERR_OUT_OF_MEMORY;
        }
    }
    /* stable bucket sort by cell: each ray keeps the faces' order */
    uint32_t *start = calloc((size_t)N * N + 1, sizeof *start);
    if (!start)
        return GI_ERR_OUT_OF_MEMORY;
    if (tmp->cap < buf->n) {
        vlf_frag *t = realloc(tmp->v, (buf->n ? buf->n : 1) * sizeof *t);
        if (!t) {
            free(start);
            return GI_ERR_OUT_OF_MEMORY;
        }
        tmp->v = t;
        tmp->cap = buf->n ? buf->n : 1;
    }
    for (size_t k = 0; k < buf->n; k++)
        start[buf->v[k].cell + 1]++;
    for (uint32_t c = 0; c < N * N; c++)
        start[c + 1] += start[c];
    for (size_t k = 0; k < buf->n; k++)
        tmp->v[start[buf->v[k].cell]++] = buf->v[k];
    free(start);
    tmp->n = buf->n;
    vlf_frag_buf sw = *buf;
    *buf = *tmp;
    *tmp = sw;
    return GI_OK;
}

/* 1 if piece pc is its scene triangle whole (the same corners in the same
 * order), so that the draw can take the triangle itself. */
static int piece_is_whole(const vlf_field *f, const vlf_psf *fr, const vlf_sorter *so,
                          const vlf_piece *pc)
{
    if (pc->count != 3)
        return 0;
    for (uint32_t k = 0; k < 3; k++) {
        gi_vec3 p = f->sort_p[3 * (size_t)pc->tri + k], w = so->vert[pc->first + k];
        if (fabsf(gi_v3_dot(p, fr->u) - w.x) > 1e-6f || fabsf(gi_v3_dot(p, fr->v) - w.y) > 1e-6f ||
            fabsf(gi_v3_dot(p, fr->n) - w.z) > 1e-6f)
            return 0;
    }
    return 1;
}

static int push_u32(uint32_t **v, uint32_t *n, uint32_t *cap, uint32_t x)
{
    if (*n == *cap) {
        uint32_t c = *cap ? *cap * 2 : 1024;
        uint32_t *t = realloc(*v, (size_t)c * sizeof *t);
        if (!t)
            return 0;
        *v = t, *cap = c;
    }
    (*v)[(*n)++] = x;
    return 1;
}

/* Subfield p's face order as the rasteriser draws it (§3.2, vlf_psf.rorder):
 * the sorter's pieces front to back, a whole triangle by its index, a
 * split piece as the triangles of its fan; a double-sided face's piece
 * twice, the side facing against +w first (as emit_frag orders the two
 * fragments). 1, or 0 out of memory. */
static int record_raster(const vlf_field *f, vlf_psf *p, const vlf_sorter *so)
{
    uint32_t cap = 0, ecap = 0, ne = 0;
    for (uint32_t k = 0; k < so->nout; k++) {
        const vlf_piece *pc = &so->poly[so->out[k]];
        uint32_t fi = f->sort_face[pc->tri];
        const vlf_face *fc = &f->faces[fi];
        uint32_t sides[2] = {0, 0}, nsides = 1;
        if (fc->twin >= 0) {
            int own_first = gi_v3_dot(fc->n, p->n) < 0.0f;
            sides[0] = own_first ? 0u : 0x80000000u;
            sides[1] = own_first ? 0x80000000u : 0u;
            nsides = 2;
        }
        uint32_t first = p->rextra_count, ntri = 0;
        if (piece_is_whole(f, p, so, pc)) {
            for (uint32_t s = 0; s < nsides; s++)
                if (!push_u32(&p->rorder, &p->rorder_count, &cap, pc->tri | sides[s]))
                    return 0;
            continue;
        }
        const gi_vec3 *v = so->vert + pc->first;
        for (uint32_t j = 1; j + 1 < pc->count; j++, ntri++) {
            const gi_vec3 *w[3] = {&v[0], &v[j], &v[j + 1]};
            for (int a = 0; a < 3; a++) {
                gi_vec3 q =
                    gi_v3_add(gi_v3_add(gi_v3_scale(p->u, w[a]->x), gi_v3_scale(p->v, w[a]->y)),
                              gi_v3_scale(p->n, w[a]->z));
                uint32_t c[4] = {0, 0, 0, fi};
                memcpy(c, &q, 3 * sizeof(float));
                for (int b = 0; b < 4; b++)
                    if (!push_u32(&p->rextra, &ne, &ecap, c[b]))
                        return 0;
            }
            p->rextra_count++;
        }
        for (uint32_t s = 0; s < nsides; s++)
            for (uint32_t t = 0; t < ntri; t++)
                if (!push_u32(&p->rorder, &p->rorder_count, &cap,
                              (first + t) | 0x40000000u | sides[s]))
                    return 0;
    }
    return 1;
}

/* Depth order of subfield i (the "sort" stage, §3.2): the fragments of
 * every face on the N S x N S rays, each ray's front to back
 * (vlf_list_fragments); the tile rectangles of non-diffuse faces recorded on
 * the way. Writes only psf[i] and the rectangles of subfield i. */
static int build_psf(vlf_field *f, uint32_t i, vlf_frag_buf *buf, vlf_frag_buf *tmp, vlf_sorter *so,
                     vlf_sort_counts *cnt)
{
    vlf_rect *rects = f->rects;
    vlf_psf *p = &f->psf[i];
    gi_vec3 w = f->dirs.signed_dirs[i];
    p->n = w;
    gi_onb(w, &p->u, &p->v);
    uint32_t N = f->prm.N * f->prm.S, m = f->prm.m;
    int32_t *bbox = malloc(((size_t)f->face_count * 4 + 4) * sizeof *bbox);
    if (!bbox)
        return 0;
    for (uint32_t fi = 0; fi < f->face_count; fi++) {
        bbox[4 * fi] = bbox[4 * fi + 1] = INT32_MAX;
        bbox[4 * fi + 2] = bbox[4 * fi + 3] = -1;
    }
    if (vlf_list_fragments(f, p, buf, tmp, so, bbox, cnt) != GI_OK ||
        (f->prm.raster && f->prm.order != VLF_ORDER_RAYS && !record_raster(f, p, so))) {
        free(bbox);
        return 0;
    }
    for (uint32_t fi = 0; fi < f->face_count; fi++) /* a back side covers the cells of its front */
        if (f->faces[fi].back)
            memcpy(bbox + 4 * fi, bbox + 4 * (size_t)f->faces[fi].twin, 4 * sizeof *bbox);
    for (uint32_t fi = 0; fi < f->face_count; fi++) {
        if (f->faces[fi].nd < 0)
            continue;
        vlf_rect *r = &rects[(size_t)f->faces[fi].nd * f->prm.l + i];
        const int32_t *bb = bbox + 4 * fi;
        if (bb[2] < 0) {
            *r = (vlf_rect){0, 0, 0, 0, 0};
        } else {
            int32_t tx0 = bb[0] / (int32_t)m, ty0 = bb[1] / (int32_t)m;
            int32_t tx1 = bb[2] / (int32_t)m, ty1 = bb[3] / (int32_t)m;
            *r = (vlf_rect){tx0 * (int32_t)m, ty0 * (int32_t)m, (uint32_t)(tx1 - tx0 + 1) * m,
                            (uint32_t)(ty1 - ty0 + 1) * m, 0};
        }
    }
    free(bbox);
    p->cell_start = calloc((size_t)N * N + 1, sizeof *p->cell_start);
    p->frag = malloc((buf->n ? buf->n : 1) * sizeof *p->frag);
    if (!p->cell_start || !p->frag)
        return 0;
    p->frag_count = (uint32_t)buf->n;
    for (size_t k = 0; k < buf->n; k++) {
        p->cell_start[buf->v[k].cell + 1]++;
        p->frag[k] = buf->v[k].elem;
    }
    for (uint32_t c = 0; c < N * N; c++)
        p->cell_start[c + 1] += p->cell_start[c];
    return 1;
}

/* One thread of the sort stage: subfields t, t + T, t + 2T, ... (each
 * subfield's order depends on nothing else, so any thread count gives the
 * same field). */
typedef struct sort_job {
    vlf_field *f;
    uint32_t t, T;
    int ok;
    vlf_sort_counts cnt;
} sort_job;

static void *sort_thread(void *arg)
{
    sort_job *j = arg;
    vlf_frag_buf buf = {0}, tmp = {0};
    vlf_sorter so;
    memset(&so, 0, sizeof so);
    j->ok = 1;
    for (uint32_t i = j->t; i < j->f->prm.l && j->ok; i += j->T) {
        if (j->f->prm.cancelled && j->f->prm.cancelled(j->f->prm.cancel_user)) {
            j->ok = 0;
            break;
        }
        j->ok = build_psf(j->f, i, &buf, &tmp, &so, &j->cnt);
    }
    free(buf.v);
    free(tmp.v);
    vlf_sorter_free(&so);
    return NULL;
}

gi_result vlf_build_subfields(vlf_field *f)
{
    uint32_t T = f->prm.threads < 1 ? 1 : f->prm.threads;
    if (T > f->prm.l)
        T = f->prm.l;
    sort_job *jobs = calloc(T, sizeof *jobs);
    pthread_t *th = calloc(T, sizeof *th);
    uint8_t *started = calloc(T, 1);
    if (!jobs || !th || !started) {
        free(jobs), free(th), free(started);
        return GI_ERR_OUT_OF_MEMORY;
    }
    for (uint32_t t = 0; t < T; t++) {
        jobs[t] = (sort_job){f, t, T, 0, {0, 0, 0, 0, 0, 0, 0}};
        if (t > 0)
            started[t] = pthread_create(&th[t], NULL, sort_thread, &jobs[t]) == 0;
    }
    sort_thread(&jobs[0]);
    int ok = jobs[0].ok;
    for (uint32_t t = 1; t < T; t++) {
        if (started[t])
            pthread_join(th[t], NULL);
        else
            sort_thread(&jobs[t]); /* no thread to be had: do its share here */
        ok = ok && jobs[t].ok;
    }
    for (uint32_t t = 0; t < T; t++) {
        f->st.sort_pieces += jobs[t].cnt.pieces;
        f->st.sort_splits += jobs[t].cnt.splits;
        f->st.sort_bsp_cuts += jobs[t].cnt.bsp_cuts;
        f->st.sort_unresolved += jobs[t].cnt.unresolved;
        f->st.sort_tests += jobs[t].cnt.tests;
        f->st.sort_groups += jobs[t].cnt.groups;
        f->st.sort_hier_fallbacks += jobs[t].cnt.fallbacks;
    }
    free(jobs), free(th), free(started);
    return ok ? GI_OK : GI_ERR_OUT_OF_MEMORY;
}
