/* Moving rigid objects (§3.3): per-object CSSM and CSM of the moving
 * object, D T^-1 look-ups, the convex-hull condition checked per frame
 * (motion.h). */
#include "motion.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define SHRINK                                                                                     \
    1e-3f /* A's hull shrunk by this about its centroid: resting contact is no intrusion */

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
    free(m->obj_first);
    free(m->obj_texels);
    cssm_maps_free(&m->self);
    gi_csm_distant_free(&m->csm);
    for (uint32_t k = 0; m->hulls && k < m->object_count; k++)
        gi_hull_free(&m->hulls[k]);
    free(m->hulls);
    memset(m, 0, sizeof *m);
    m->moving = -1;
}

static float transform_scale(const float T[16])
{
    float det = T[0] * (T[5] * T[10] - T[9] * T[6]) - T[4] * (T[1] * T[10] - T[9] * T[2]) +
                T[8] * (T[1] * T[6] - T[5] * T[2]);
    return cbrtf(fabsf(det));
}

gi_result cssm_motion_init(const gi_scene *s, float t, const cssm_atlas *a, int32_t moving,
                           cssm_motion *out, gi_error *err)
{
    memset(out, 0, sizeof *out);
    out->moving = moving;
    const uint32_t N = a->count, O = s->object_count;
    out->object_count = O;
    out->on_moving = calloc(N, 1);
    out->on_static = calloc(N, 1);
    out->local_p = calloc(N, sizeof *out->local_p);
    out->local_n = calloc(N, sizeof *out->local_n);
    out->local_charts = calloc(a->chart_count ? a->chart_count : 1, sizeof *out->local_charts);
    out->object_of = calloc(N, sizeof *out->object_of);
    out->object_moves = calloc(O ? O : 1, 1);
    out->obj_first = calloc(O + 1, sizeof *out->obj_first);
    out->obj_texels = calloc(N ? N : 1, sizeof *out->obj_texels);
    out->hulls = calloc(O, sizeof *out->hulls);
    if (!out->on_moving || !out->on_static || !out->local_p || !out->local_n ||
        !out->local_charts || !out->object_of || !out->object_moves || !out->obj_first || !out->obj_texels ||
        !out->hulls) {
        cssm_motion_free(out);
        snprintf(err->text, sizeof err->text, "cssm_hrc: out of memory for the moving object");
        return GI_ERR_OUT_OF_MEMORY;
    }
    float T0[16];
    gi_scene_object_transform(s, (uint32_t)moving, t, T0);
    if (!gi_mat4_invert(out->T0inv, T0)) {
        cssm_motion_free(out);
        snprintf(err->text, sizeof err->text,
                 "cssm_hrc: the moving object '%s' has a singular transform",
                 s->objects[moving].name ? s->objects[moving].name : "?");
        return GI_ERR_INVALID_ARGUMENT;
    }
    out->object_moves[moving] = 1;
    memcpy(out->T, T0, sizeof out->T);
    memcpy(out->Tinv, out->T0inv, sizeof out->Tinv);
    out->scale = transform_scale(T0);
    for (uint32_t i = 0; i < N; i++) {
        const cssm_texel *x = &a->texels[i];
        uint32_t o = s->vertices[s->indices[3 * x->triangle]].object;
        out->object_of[i] = o;
        out->obj_first[o + 1]++;
        out->on_moving[i] = o == (uint32_t)moving;
        out->on_static[i] = !out->on_moving[i];
        out->local_p[i] = gi_mat4_point(out->T0inv, x->p);
        out->local_n[i] = gi_v3_normalize(gi_mat4_dir(out->T0inv, x->n));
    }
    for (uint32_t k = 0; k < O; k++)
        out->obj_first[k + 1] += out->obj_first[k];
    uint32_t *fill = calloc(O ? O : 1, sizeof *fill);
    if (!fill) {
        cssm_motion_free(out);
        snprintf(err->text, sizeof err->text, "cssm_hrc: out of memory for the moving object");
        return GI_ERR_OUT_OF_MEMORY;
    }
    for (uint32_t i = 0; i < N; i++) {
        uint32_t o = out->object_of[i];
        out->obj_texels[out->obj_first[o] + fill[o]++] = i;
    }
    free(fill);
    for (uint32_t c = 0; c < a->chart_count; c++) {
        cssm_chart ch = a->charts[c];
        ch.origin = gi_mat4_point(out->T0inv, ch.origin);
        ch.u = gi_mat4_dir(out->T0inv, ch.u);
        ch.v = gi_mat4_dir(out->T0inv, ch.v);
        ch.normal = gi_v3_normalize(gi_mat4_dir(out->T0inv, ch.normal));
        out->local_charts[c] = ch;
    }
    /* the convex hull of each object's vertices, local frame, once */
    for (uint32_t k = 0; k < O; k++) {
        const gi_object *ob = &s->objects[k];
        float *pts = malloc((size_t)ob->vertex_count * 3 * sizeof *pts);
        if (!pts) {
            cssm_motion_free(out);
            snprintf(err->text, sizeof err->text, "cssm_hrc: out of memory for the hulls");
            return GI_ERR_OUT_OF_MEMORY;
        }
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

gi_result cssm_motion_build_maps(cssm_motion *m, const gi_gpu_scene *gs, const cssm_atlas *a,
                                 const uint32_t *order, uint32_t M, const gi_host *host,
                                 gi_error *err)
{
    /* A alone, in its frame: the eyes of its texels taken there */
    cssm_build_opts o = {.only_object = (uint32_t)m->moving + 1u,
                         .local = 1,
                         .eye_from_world = m->T0inv,
                         .dont_care = m->on_static};
    gi_result r = cssm_maps_build_ex(gs, a, order, M, &o, host, &m->self, err);
    if (r != GI_OK)
        return r;
    if (host)
        host->stage_begin(host, "csm_render");
    gi_csm_distant_desc d = {.M = 32, .n_theta = 32};
    r = gi_csm_distant_build(gs, (uint32_t)m->moving, &d, &m->csm, err);
    if (host)
        host->stage_end(host, "csm_render");
    return r;
}

void cssm_motion_place(cssm_motion *m, const gi_scene *s, float t, cssm_atlas *a)
{
    gi_scene_object_transform(s, (uint32_t)m->moving, t, m->T);
    if (!gi_mat4_invert(m->Tinv, m->T))
        gi_mat4_identity(m->Tinv);
    m->scale = transform_scale(m->T);
    for (uint32_t i = 0; i < a->count; i++)
        if (m->on_moving[i]) {
            a->texels[i].p = gi_mat4_point(m->T, m->local_p[i]);
            a->texels[i].n = gi_v3_normalize(gi_mat4_dir(m->T, m->local_n[i]));
        }
    for (uint32_t c = 0; c < a->chart_count; c++)
        if (a->charts[c].object == (uint32_t)m->moving) {
            const cssm_chart *l = &m->local_charts[c];
            cssm_chart *w = &a->charts[c];
            w->origin = gi_mat4_point(m->T, l->origin);
            w->u = gi_mat4_dir(m->T, l->u);
            w->v = gi_mat4_dir(m->T, l->v);
            w->normal = gi_v3_normalize(gi_mat4_dir(m->T, l->normal));
        }
}

uint32_t cssm_motion_check(cssm_motion *m, const gi_scene *s, float t)
{
    const uint32_t A = (uint32_t)m->moving;
    const gi_hull *ha = &m->hulls[A];
    /* A's hull shrunk about its vertices' centroid, then placed */
    gi_vec3 c = gi_v3(0, 0, 0);
    for (uint32_t v = 0; v < ha->vertex_count; v++)
        c = gi_v3_add(c, ha->vertices[v]);
    c = gi_v3_scale(c, 1.0f / (float)(ha->vertex_count ? ha->vertex_count : 1));
    float S[16], TA[16];
    gi_mat4_identity(S);
    S[0] = S[5] = S[10] = 1.0f - SHRINK;
    S[12] = SHRINK * c.x, S[13] = SHRINK * c.y, S[14] = SHRINK * c.z;
    gi_mat4_mul(TA, m->T, S);
    /* the placed hull's box: triangles outside it need no GJK */
    gi_vec3 lo = gi_v3(FLT_MAX, FLT_MAX, FLT_MAX), hi = gi_v3(-FLT_MAX, -FLT_MAX, -FLT_MAX);
    for (uint32_t v = 0; v < ha->vertex_count; v++) {
        gi_vec3 q = gi_mat4_point(TA, ha->vertices[v]);
        lo = gi_v3(fminf(lo.x, q.x), fminf(lo.y, q.y), fminf(lo.z, q.z));
        hi = gi_v3(fmaxf(hi.x, q.x), fmaxf(hi.y, q.y), fmaxf(hi.z, q.z));
    }
    m->overlaps = m->intrusions = 0;
    m->what[0] = 0;
    for (uint32_t k = 0; k < s->object_count; k++) {
        if (k == A)
            continue;
        float Tk[16];
        gi_scene_object_transform(s, k, t, Tk);
        if (!gi_hull_overlap(ha, TA, &m->hulls[k], Tk, 0.0f))
            continue;
        m->overlaps++;
        /* the condition the look-ups need: no surface of k inside A's hull */
        const gi_object *ob = &s->objects[k];
        for (uint32_t tri = ob->first_triangle; tri < ob->first_triangle + ob->triangle_count;
             tri++) {
            gi_vec3 p[3];
            gi_scene_triangle_world(s, tri, t, p);
            if (fmaxf(p[0].x, fmaxf(p[1].x, p[2].x)) < lo.x ||
                fminf(p[0].x, fminf(p[1].x, p[2].x)) > hi.x ||
                fmaxf(p[0].y, fmaxf(p[1].y, p[2].y)) < lo.y ||
                fminf(p[0].y, fminf(p[1].y, p[2].y)) > hi.y ||
                fmaxf(p[0].z, fmaxf(p[1].z, p[2].z)) < lo.z ||
                fminf(p[0].z, fminf(p[1].z, p[2].z)) > hi.z)
                continue;
            gi_hull th = {.vertices = p, .vertex_count = 3};
            if (gi_hull_overlap(ha, TA, &th, NULL, 0.0f)) {
                if (!m->intrusions)
                    snprintf(m->what, sizeof m->what,
                             "object '%s' reaches into the convex hull of the moving '%s'",
                             ob->name ? ob->name : "?",
                             s->objects[A].name ? s->objects[A].name : "?");
                m->intrusions++;
                break;
            }
        }
    }
    return m->intrusions;
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

float cssm_visible_rc(const cssm_maps *maps, uint32_t j, const cssm_receiver *rc, float bias,
                      int pcf)
{
    const cssm_motion *m = maps->motion;
    if (!m)
        return cssm_visible(maps, j, rc->x, bias, pcf);
    const int32_t r = rc->self >= 0 ? rc->self : (int32_t)rc->proxy1 - 1;
    const int rmov = rc->self >= 0 ? m->on_moving[rc->self] : rc->moving;
    const float lbias = bias / (m->scale > 0.0f ? m->scale : 1.0f);
    if (m->on_moving[j]) {
        /* D T^-1: the receiver in A's frame, looked up in A's CSSM at j */
        float v = cssm_visible(&m->self, j, gi_mat4_point(m->Tinv, rc->x), lbias, pcf);
        if (v <= 0.0f || rmov)
            return v;
        /* S between j and a receiver on S: the receiver's (proxy's) static CSSM toward j */
        if (r >= 0 && !m->on_moving[r])
            v *= cssm_visible(maps, (uint32_t)r, gi_mat4_point(m->T, m->self.eye[j]), bias, pcf);
        return v;
    }
    float v = cssm_visible(maps, j, rc->x, bias, pcf);
    if (v <= 0.0f)
        return v;
    gi_vec3 pj = gi_mat4_point(m->Tinv, maps->eye[j]), xl = gi_mat4_point(m->Tinv, rc->x);
    if (rmov && rc->self >= 0) /* A between j and a texel of A: that texel's CSSM toward j */
        return v * cssm_visible(&m->self, (uint32_t)r, pj, lbias, pcf);
    /* A between j and a pixel on A, or between two points outside its
     * hull: A's CSM */
    return gi_csm_distant_blocks(&m->csm, pj, xl, lbias) ? 0.0f : v;
}
