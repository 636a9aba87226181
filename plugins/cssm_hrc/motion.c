/* Moving rigid objects (§3.3): per mover its CSSM and CSM, D T^-1
 * look-ups, the convex-hull condition checked per frame and pair
 * (motion.h). */
#include "motion.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define SHRINK                                                                                     \
    1e-3f /* a mover's hull shrunk by this about its centroid: resting contact is no intrusion */

int32_t cssm_motion_find(const gi_scene *s, uint32_t *count)
{
    int32_t found = -1;
    *count = 0;
    for (uint32_t k = 0; k < s->object_count; k++)
        if (s->objects[k].animated) {
            if (found < 0)
                found = (int32_t)k;
            (*count)++;
        }
    return found;
}

void cssm_motion_free(cssm_motion *m)
{
    if (!m)
        return;
    free(m->on_moving);
    free(m->on_static);
    free(m->local_p);
    free(m->local_n);
    free(m->local_charts);
    free(m->object_of);
    free(m->object_moves);
    free(m->mover_of);
    free(m->obj_first);
    free(m->obj_texels);
    for (uint32_t k = 0; m->movers && k < m->mover_count; k++) {
        cssm_maps_free(&m->movers[k].self);
        gi_csm_distant_free(&m->movers[k].csm);
    }
    free(m->movers);
    for (uint32_t k = 0; m->hulls && k < m->object_count; k++)
        gi_hull_free(&m->hulls[k]);
    free(m->hulls);
    for (uint32_t k = 0; m->static_csm && k < m->object_count; k++)
        gi_csm_distant_free(&m->static_csm[k]);
    free(m->static_csm);
    free(m->static_Tinv);
    free(m->static_scale);
    free(m->pairs);
    memset(m, 0, sizeof *m);
    m->moving = -1;
}

static float transform_scale(const float T[16])
{
    float det = T[0] * (T[5] * T[10] - T[9] * T[6]) - T[4] * (T[1] * T[10] - T[9] * T[2]) +
                T[8] * (T[1] * T[6] - T[5] * T[2]);
    return cbrtf(fabsf(det));
}

/* Frees m and sets the error of a failed allocation for `what`. */
static gi_result oom(cssm_motion *m, gi_error *err, const char *what)
{
    cssm_motion_free(m);
    return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "cssm_hrc: out of memory for %s", what);
}

/* The per-texel, per-object and per-mover arrays of a motion of N
 * texels, O objects and K movers, zeroed. */
static gi_result motion_alloc(const cssm_atlas *a, uint32_t O, uint32_t K, cssm_motion *out,
                              gi_error *err)
{
    const uint32_t N = a->count;
    out->on_moving = calloc(N ? N : 1, 1);
    out->on_static = calloc(N ? N : 1, 1);
    out->local_p = calloc(N ? N : 1, sizeof *out->local_p);
    out->local_n = calloc(N ? N : 1, sizeof *out->local_n);
    out->local_charts = calloc(a->chart_count ? a->chart_count : 1, sizeof *out->local_charts);
    out->object_of = calloc(N ? N : 1, sizeof *out->object_of);
    out->object_moves = calloc(O ? O : 1, 1);
    out->mover_of = calloc(O ? O : 1, sizeof *out->mover_of);
    out->movers = calloc(K ? K : 1, sizeof *out->movers);
    out->obj_first = calloc(O + 1, sizeof *out->obj_first);
    out->obj_texels = calloc(N ? N : 1, sizeof *out->obj_texels);
    out->hulls = calloc(O ? O : 1, sizeof *out->hulls);
    out->static_csm = calloc(O ? O : 1, sizeof *out->static_csm);
    out->static_Tinv = calloc(16 * (size_t)(O ? O : 1), sizeof *out->static_Tinv);
    out->static_scale = calloc(O ? O : 1, sizeof *out->static_scale);
    if (!out->on_moving || !out->on_static || !out->local_p || !out->local_n ||
        !out->local_charts || !out->object_of || !out->object_moves || !out->mover_of ||
        !out->movers || !out->obj_first || !out->obj_texels || !out->hulls || !out->static_csm ||
        !out->static_Tinv || !out->static_scale)
        return oom(out, err, "the moving objects");
    return GI_OK;
}

/* Every object's frame at prepare time t (its inverse and scale), and a
 * mover for each animated object. */
static gi_result motion_frames(const gi_scene *s, float t, cssm_motion *out, gi_error *err)
{
    for (uint32_t k = 0, i = 0; k < out->object_count; k++) {
        out->mover_of[k] = -1;
        float T0[16], *Ti = &out->static_Tinv[16 * (size_t)k];
        gi_scene_object_transform(s, k, t, T0);
        if (!gi_mat4_invert(Ti, T0)) {
            const char *name = s->objects[k].name ? s->objects[k].name : "?";
            cssm_motion_free(out);
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                "cssm_hrc: the object '%.100s' has a singular transform", name);
        }
        out->static_scale[k] = transform_scale(T0);
        if (!s->objects[k].animated)
            continue;
        cssm_mover *mv = &out->movers[i];
        mv->object = k;
        memcpy(mv->T0inv, Ti, sizeof mv->T0inv);
        memcpy(mv->T, T0, sizeof mv->T);
        memcpy(mv->Tinv, Ti, sizeof mv->Tinv);
        mv->scale = out->static_scale[k];
        out->mover_of[k] = (int32_t)i++;
        out->object_moves[k] = 1;
    }
    return GI_OK;
}

/* Per texel its object and whether it moves (then its position and
 * normal in the mover's frame); the texels of each object; the charts of
 * movers in their frames. */
static gi_result motion_texels(const gi_scene *s, const cssm_atlas *a, cssm_motion *out,
                               gi_error *err)
{
    const uint32_t N = a->count, O = out->object_count;
    for (uint32_t i = 0; i < N; i++) {
        const cssm_texel *x = &a->texels[i];
        uint32_t o = s->vertices[s->indices[3 * x->triangle]].object;
        out->object_of[i] = o;
        out->obj_first[o + 1]++;
        out->on_moving[i] = out->object_moves[o];
        out->on_static[i] = !out->on_moving[i];
        if (out->on_moving[i]) {
            const float *Ti = out->movers[out->mover_of[o]].T0inv;
            out->local_p[i] = gi_mat4_point(Ti, x->p);
            out->local_n[i] = gi_v3_normalize(gi_mat4_dir(Ti, x->n));
        }
    }
    for (uint32_t k = 0; k < O; k++)
        out->obj_first[k + 1] += out->obj_first[k];
    uint32_t *fill = calloc(O ? O : 1, sizeof *fill);
    if (!fill)
        return oom(out, err, "the moving objects");
    for (uint32_t i = 0; i < N; i++) {
        uint32_t o = out->object_of[i];
        out->obj_texels[out->obj_first[o] + fill[o]++] = i;
    }
    free(fill);
    for (uint32_t c = 0; c < a->chart_count; c++) {
        cssm_chart ch = a->charts[c];
        if (ch.object < O && out->object_moves[ch.object]) {
            const float *Ti = out->movers[out->mover_of[ch.object]].T0inv;
            ch.origin = gi_mat4_point(Ti, ch.origin);
            ch.u = gi_mat4_dir(Ti, ch.u);
            ch.v = gi_mat4_dir(Ti, ch.v);
            ch.normal = gi_v3_normalize(gi_mat4_dir(Ti, ch.normal));
        }
        out->local_charts[c] = ch;
    }
    return GI_OK;
}

/* The pairs of objects with a mover in it, and the convex hull of each
 * object's vertices, local frame, once. */
static gi_result motion_hulls(const gi_scene *s, cssm_motion *out, gi_error *err)
{
    const uint32_t O = out->object_count;
    out->pairs = calloc(O ? (size_t)O * O / 2 + 1 : 1, sizeof *out->pairs);
    if (!out->pairs)
        return oom(out, err, "the hull pairs");
    for (uint32_t p = 0; p < O; p++)
        for (uint32_t q = p + 1; q < O; q++)
            if (out->object_moves[p] || out->object_moves[q])
                out->pairs[out->pair_count++] = (cssm_hull_pair){.a = p, .b = q};
    for (uint32_t k = 0; k < O; k++) {
        const gi_object *ob = &s->objects[k];
        float *pts = malloc((size_t)(ob->vertex_count ? ob->vertex_count : 1) * 3 * sizeof *pts);
        if (!pts)
            return oom(out, err, "the hulls");
        for (uint32_t v = 0; v < ob->vertex_count; v++)
            memcpy(&pts[3 * v], s->vertices[ob->first_vertex + v].position, 3 * sizeof(float));
        gi_result r = gi_hull_build(pts, ob->vertex_count, &out->hulls[k], err);
        free(pts);
        if (r != GI_OK) {
            char why[sizeof err->text];
            memcpy(why, err->text, sizeof why);
            snprintf(err->text, sizeof err->text, "cssm_hrc: object '%.100s': %.300s",
                     ob->name ? ob->name : "?", why);
            cssm_motion_free(out);
            return r;
        }
    }
    return GI_OK;
}

gi_result cssm_motion_init(const gi_scene *s, float t, const cssm_atlas *a, cssm_motion *out,
                           gi_error *err)
{
    memset(out, 0, sizeof *out);
    uint32_t K = 0;
    out->moving = cssm_motion_find(s, &K);
    out->object_count = s->object_count;
    out->mover_count = K;
    gi_result r = motion_alloc(a, s->object_count, K, out, err);
    if (r == GI_OK)
        r = motion_frames(s, t, out, err);
    if (r == GI_OK)
        r = motion_texels(s, a, out, err);
    if (r == GI_OK)
        r = motion_hulls(s, out, err);
    return r;
}

gi_result cssm_motion_build_maps(cssm_motion *m, const gi_gpu_scene *gs, const cssm_atlas *a,
                                 const uint32_t *order, uint32_t M, const gi_host *host,
                                 gi_error *err)
{
    unsigned char *elsewhere = malloc(a->count ? a->count : 1);
    if (!elsewhere)
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY,
                            "cssm_hrc: out of memory for the moving objects' maps");
    gi_result r = GI_OK;
    for (uint32_t k = 0; k < m->mover_count && r == GI_OK; k++) {
        cssm_mover *mv = &m->movers[k];
        /* the mover alone, in its frame: the eyes of its texels taken there;
         * every other texel "don't care" */
        for (uint32_t i = 0; i < a->count; i++)
            elsewhere[i] = m->object_of[i] != mv->object;
        cssm_build_opts o = {.only_object = mv->object + 1u,
                             .local = 1,
                             .eye_from_world = mv->T0inv,
                             .dont_care = elsewhere};
        r = cssm_maps_build_ex(gs, a, order, M, &o, host, &mv->self, err);
        if (r != GI_OK)
            break;
        gi_host_stage(host, "csm_render", 1);
        gi_csm_distant_desc d = {.M = 32, .n_theta = 32};
        r = gi_csm_distant_build(gs, mv->object, &d, &mv->csm, err);
        gi_host_stage(host, "csm_render", 0);
    }
    free(elsewhere);
    /* two or more movers: the static objects' CSMs, for the segments
     * between two movers */
    for (uint32_t k = 0; k < m->object_count && r == GI_OK && m->mover_count > 1; k++) {
        if (m->object_moves[k] || !gs->scene->objects[k].triangle_count)
            continue;
        gi_host_stage(host, "csm_render", 1);
        gi_csm_distant_desc d = {.M = 32, .n_theta = 32};
        r = gi_csm_distant_build(gs, k, &d, &m->static_csm[k], err);
        gi_host_stage(host, "csm_render", 0);
    }
    return r;
}

void cssm_motion_place(cssm_motion *m, const gi_scene *s, float t, cssm_atlas *a)
{
    for (uint32_t k = 0; k < m->mover_count; k++) {
        cssm_mover *mv = &m->movers[k];
        gi_scene_object_transform(s, mv->object, t, mv->T);
        if (!gi_mat4_invert(mv->Tinv, mv->T))
            gi_mat4_identity(mv->Tinv);
        mv->scale = transform_scale(mv->T);
    }
    for (uint32_t i = 0; i < a->count; i++)
        if (m->on_moving[i]) {
            const cssm_mover *mv = &m->movers[m->mover_of[m->object_of[i]]];
            a->texels[i].p = gi_mat4_point(mv->T, m->local_p[i]);
            a->texels[i].n = gi_v3_normalize(gi_mat4_dir(mv->T, m->local_n[i]));
        }
    for (uint32_t c = 0; c < a->chart_count; c++)
        if (a->charts[c].object < m->object_count && m->object_moves[a->charts[c].object]) {
            const cssm_mover *mv = &m->movers[m->mover_of[a->charts[c].object]];
            const cssm_chart *l = &m->local_charts[c];
            cssm_chart *w = &a->charts[c];
            w->origin = gi_mat4_point(mv->T, l->origin);
            w->u = gi_mat4_dir(mv->T, l->u);
            w->v = gi_mat4_dir(mv->T, l->v);
            w->normal = gi_v3_normalize(gi_mat4_dir(mv->T, l->normal));
        }
}

/* Mover A's hull shrunk about its vertices' centroid, then placed by T:
 * the transform into *TA and the placed box. */
static void shrunk_hull(const gi_hull *ha, const float T[16], float TA[16], gi_vec3 *lo,
                        gi_vec3 *hi)
{
    gi_vec3 c = gi_v3(0, 0, 0);
    for (uint32_t v = 0; v < ha->vertex_count; v++)
        c = gi_v3_add(c, ha->vertices[v]);
    c = gi_v3_scale(c, 1.0f / (float)(ha->vertex_count ? ha->vertex_count : 1));
    float S[16];
    gi_mat4_identity(S);
    S[0] = S[5] = S[10] = 1.0f - SHRINK;
    S[12] = SHRINK * c.x, S[13] = SHRINK * c.y, S[14] = SHRINK * c.z;
    gi_mat4_mul(TA, T, S);
    *lo = gi_v3(FLT_MAX, FLT_MAX, FLT_MAX), *hi = gi_v3(-FLT_MAX, -FLT_MAX, -FLT_MAX);
    for (uint32_t v = 0; v < ha->vertex_count; v++) {
        gi_vec3 q = gi_mat4_point(TA, ha->vertices[v]);
        *lo = gi_v3(fminf(lo->x, q.x), fminf(lo->y, q.y), fminf(lo->z, q.z));
        *hi = gi_v3(fmaxf(hi->x, q.x), fmaxf(hi->y, q.y), fmaxf(hi->z, q.z));
    }
}

/* 1 when a triangle of object k (at time t) lies in the placed hull (TA,
 * box lo..hi) of object A. */
static int reaches_into(const cssm_motion *m, const gi_scene *s, float t, uint32_t A,
                        const float TA[16], gi_vec3 lo, gi_vec3 hi, uint32_t k)
{
    const gi_object *ob = &s->objects[k];
    for (uint32_t tri = ob->first_triangle; tri < ob->first_triangle + ob->triangle_count; tri++) {
        gi_vec3 p[3];
        if (m->object_moves[k]) /* placed by the mover's transform (cssm_motion_place) */
            for (uint32_t c = 0; c < 3; c++)
                p[c] = gi_mat4_point(m->movers[m->mover_of[k]].T,
                                     gi_scene_vertex_position(s, s->indices[3 * tri + c], t));
        else
            gi_scene_triangle_world(s, tri, t, p);
        if (fmaxf(p[0].x, fmaxf(p[1].x, p[2].x)) < lo.x ||
            fminf(p[0].x, fminf(p[1].x, p[2].x)) > hi.x ||
            fmaxf(p[0].y, fmaxf(p[1].y, p[2].y)) < lo.y ||
            fminf(p[0].y, fminf(p[1].y, p[2].y)) > hi.y ||
            fmaxf(p[0].z, fmaxf(p[1].z, p[2].z)) < lo.z ||
            fminf(p[0].z, fminf(p[1].z, p[2].z)) > hi.z)
            continue;
        gi_hull th = {.vertices = p, .vertex_count = 3};
        if (gi_hull_overlap(&m->hulls[A], TA, &th, NULL, 0.0f))
            return 1;
    }
    return 0;
}

uint32_t cssm_motion_check(cssm_motion *m, const gi_scene *s, float t)
{
    m->overlaps = m->intrusions = 0;
    m->what[0] = 0;
    for (uint32_t p = 0; p < m->pair_count; p++) {
        cssm_hull_pair *pr = &m->pairs[p];
        /* the mover of the pair (the first one when both move) shrunk */
        const uint32_t A = m->object_moves[pr->a] ? pr->a : pr->b, B = A == pr->a ? pr->b : pr->a;
        float TA[16], TB[16], TBs[16];
        gi_vec3 lo, hi, blo, bhi;
        shrunk_hull(&m->hulls[A], m->movers[m->mover_of[A]].T, TA, &lo, &hi);
        if (m->object_moves[B])
            memcpy(TB, m->movers[m->mover_of[B]].T, sizeof TB);
        else
            gi_scene_object_transform(s, B, t, TB);
        pr->overlap = (unsigned char)gi_hull_overlap(&m->hulls[A], TA, &m->hulls[B], TB, 0.0f);
        pr->intrusion = 0;
        if (!pr->overlap)
            continue;
        m->overlaps++;
        /* the condition the look-ups need: no surface of one inside a mover's hull */
        uint32_t into = A, from = B;
        if (reaches_into(m, s, t, A, TA, lo, hi, B)) {
            pr->intrusion = 1;
        } else if (m->object_moves[B]) {
            shrunk_hull(&m->hulls[B], m->movers[m->mover_of[B]].T, TBs, &blo, &bhi);
            if (reaches_into(m, s, t, B, TBs, blo, bhi, A))
                pr->intrusion = 1, into = B, from = A;
        }
        if (!pr->intrusion)
            continue;
        if (!m->intrusions)
            snprintf(m->what, sizeof m->what,
                     "object '%.60s' reaches into the convex hull of the moving '%.60s'",
                     s->objects[from].name ? s->objects[from].name : "?",
                     s->objects[into].name ? s->objects[into].name : "?");
        m->intrusions++;
    }
    return m->intrusions;
}

gi_vec3 cssm_motion_eye(const cssm_motion *m, const cssm_maps *maps, uint32_t j)
{
    if (!m || !m->on_moving[j])
        return maps->eye[j];
    const cssm_mover *mv = &m->movers[m->mover_of[m->object_of[j]]];
    return gi_mat4_point(mv->T, mv->self.eye[j]);
}

uint32_t cssm_motion_mover1(const cssm_motion *m, const gi_scene *s, uint32_t tri)
{
    if (tri >= s->triangle_count)
        return 0;
    uint32_t o = s->vertices[s->indices[3 * tri]].object;
    return o < m->object_count ? (uint32_t)(m->mover_of[o] + 1) : 0u;
}

int32_t cssm_motion_proxy(const cssm_motion *m, const gi_scene *s, const cssm_atlas *a,
                          uint32_t tri, gi_vec3 p, gi_vec3 n)
{
    if (tri >= s->triangle_count)
        return -1;
    uint32_t o = s->vertices[s->indices[3 * tri]].object;
    int32_t best = -1;
    float bd = FLT_MAX;
    for (uint32_t k = m->obj_first[o]; k < m->obj_first[o + 1]; k++) {
        uint32_t i = m->obj_texels[k];
        const cssm_texel *x = &a->texels[i];
        if (gi_v3_dot(x->n, n) < 0.5f)
            continue;
        gi_vec3 d = gi_v3_sub(x->p, p);
        float dd = gi_v3_dot(d, d);
        if (dd < bd)
            bd = dd, best = (int32_t)i;
    }
    return best;
}

/* Whether a mover other than skip1, skip2 blocks the segment p-q (world):
 * its CSM through its T^-1. */
static float other_movers(const cssm_motion *m, float v, gi_vec3 p, gi_vec3 q, int32_t skip1,
                          int32_t skip2, float bias)
{
    for (uint32_t k = 0; k < m->mover_count && v > 0.0f; k++) {
        if ((int32_t)k == skip1 || (int32_t)k == skip2)
            continue;
        const cssm_mover *mv = &m->movers[k];
        const float lb = bias / (mv->scale > 0.0f ? mv->scale : 1.0f);
        if (gi_csm_distant_blocks(&mv->csm, gi_mat4_point(mv->Tinv, p), gi_mat4_point(mv->Tinv, q),
                                  lb))
            v = 0.0f;
    }
    return v;
}

/* Whether a static object blocks the segment p-q between two movers
 * (world): its CSM, for the objects whose hull holds neither end (an
 * object whose hull holds an end is left out: motion.h). */
static float static_objects(const cssm_motion *m, float v, gi_vec3 p, gi_vec3 q, float bias)
{
    for (uint32_t k = 0; k < m->object_count && v > 0.0f; k++) {
        if (m->object_moves[k] || !m->static_csm[k].data.offsets)
            continue;
        const float *Ti = &m->static_Tinv[16 * (size_t)k];
        gi_vec3 pl = gi_mat4_point(Ti, p), ql = gi_mat4_point(Ti, q);
        if (gi_hull_contains(&m->hulls[k], pl, 0.0f) || gi_hull_contains(&m->hulls[k], ql, 0.0f))
            continue;
        const float lb = bias / (m->static_scale[k] > 0.0f ? m->static_scale[k] : 1.0f);
        if (gi_csm_distant_blocks(&m->static_csm[k], pl, ql, lb))
            v = 0.0f;
    }
    return v;
}

float cssm_visible_rc(const cssm_maps *maps, uint32_t j, const cssm_receiver *rc, float bias,
                      int pcf)
{
    const cssm_motion *m = maps->motion;
    if (!m)
        return cssm_visible(maps, j, rc->x, bias, pcf);
    const int32_t r = rc->self >= 0 ? rc->self : (int32_t)rc->proxy1 - 1;
    /* the movers of the two ends, -1 for S */
    const int32_t gx =
        rc->self >= 0 ? m->mover_of[m->object_of[rc->self]] : (int32_t)rc->moving - 1;
    const int32_t gj = m->mover_of[m->object_of[j]];
    const cssm_mover *B = gx >= 0 ? &m->movers[gx] : NULL;
    const float bbias = B ? bias / (B->scale > 0.0f ? B->scale : 1.0f) : bias;
    float v;
    gi_vec3 pj;
    if (gj >= 0) {
        const cssm_mover *A = &m->movers[gj];
        /* D T^-1: the receiver in A's frame, looked up in A's CSSM at j */
        v = cssm_visible(&A->self, j, gi_mat4_point(A->Tinv, rc->x),
                         bias / (A->scale > 0.0f ? A->scale : 1.0f), pcf);
        if (v <= 0.0f || gx == gj)
            return v;
        pj = gi_mat4_point(A->T, A->self.eye[j]);
        if (!B) {
            /* S between j and a receiver on S: the receiver's (proxy's) static CSSM toward j */
            if (r >= 0 && !m->on_moving[r])
                v *= cssm_visible(maps, (uint32_t)r, pj, bias, pcf);
        } else {
            /* two movers: the receiver's own test toward j, then S by its objects' CSMs */
            if (rc->self >= 0)
                v *= cssm_visible(&B->self, (uint32_t)rc->self, gi_mat4_point(B->Tinv, pj), bbias,
                                  pcf);
            else if (gi_csm_distant_blocks(&B->csm, gi_mat4_point(B->Tinv, pj),
                                           gi_mat4_point(B->Tinv, rc->x), bbias))
                v = 0.0f;
            if (v > 0.0f)
                v = static_objects(m, v, pj, rc->x, bias);
        }
        return v > 0.0f ? other_movers(m, v, pj, rc->x, gj, gx, bias) : v;
    }
    v = cssm_visible(maps, j, rc->x, bias, pcf);
    if (v <= 0.0f)
        return v;
    pj = maps->eye[j];
    if (B) {
        /* B between j and a texel of B: that texel's CSSM toward j; a pixel on B: B's CSM */
        if (rc->self >= 0)
            v *= cssm_visible(&B->self, (uint32_t)rc->self, gi_mat4_point(B->Tinv, pj), bbias, pcf);
        else if (gi_csm_distant_blocks(&B->csm, gi_mat4_point(B->Tinv, pj),
                                       gi_mat4_point(B->Tinv, rc->x), bbias))
            return 0.0f;
        if (v <= 0.0f)
            return v;
    }
    /* the other movers between two points outside their hulls: their CSMs */
    return other_movers(m, v, pj, rc->x, -1, gx, bias);
}
