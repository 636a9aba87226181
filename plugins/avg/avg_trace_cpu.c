/* Exact VPL tracing on the CPU (the paper's Fig. 6 reference: "VPLs traced
 * on the CPU"): the same quasi-random light paths as shaders/avg_trace.comp,
 * with the same light choice, the same numbers for every decision and the
 * same slot layout, but rays intersected with the real triangles by Embree
 * (gi/raytrace.h) instead of marched through the AVG. A hit's VPL lies on
 * the surface, with the triangle's geometric normal turned toward the ray
 * and the material's albedo (texture looked up at the hit). */
#include "avg.h"

#include "gi/raytrace.h"
#include "gi/rng.h"
#include "gi/sampling.h"
#include "gi/sequences.h"
#include "gi/algo/cubemap.h"
#include "gi/lights.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

struct avg_exact {
    gi_rt *rt;
    gi_gpu_emitter *emitters;
    uint32_t emitter_count;
    gi_gpu_light lights[AVG_MAX_PUNCTUAL];
    uint32_t light_count;
};

/* Kensler's hash permutation of [0, mask] (mask = 2^k - 1): twin of
 * avg_vpl.glsl's avg_permute, which says why it replaced an XOR. */
static uint32_t avg_permute(uint32_t i, uint32_t mask, uint32_t p)
{
    uint32_t w = mask;
    i ^= p;
    i *= 0xe170893du;
    i ^= p >> 16;
    i ^= (i & w) >> 4;
    i ^= p >> 8;
    i *= 0x0929eb3fu;
    i ^= p >> 23;
    i ^= (i & w) >> 1;
    i *= 1u | (p >> 27);
    i *= 0x6935fa69u;
    i ^= (i & w) >> 11;
    i *= 0x74dcb303u;
    i ^= (i & w) >> 2;
    i *= 0x9e501cc3u;
    i ^= (i & w) >> 2;
    i *= 0xc860a3dfu;
    i &= w;
    i ^= i >> 5;
    return (i + p) & w;
}

void avg_qr(uint32_t i, uint32_t pair, uint32_t mask, uint32_t seed, float out[2])
{
    uint32_t j = avg_permute(i, mask,
                             gi_pcg_hash(pair * 0x9E3779B9u + 0x632BE5ABu) ^ gi_pcg_hash(seed) ^
                                 gi_pcg_hash(1u));
    out[0] = gi_radical_inverse2(j);
    out[1] = gi_sobol2(j);
}

avg_exact *avg_exact_create(const gi_gpu_scene *gs, gi_error *err)
{
    avg_exact *x = calloc(1, sizeof *x);
    if (!x) {
        gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "avg: out of memory");
        return NULL;
    }
    if (gi_rt_create(gs->scene, gs->time, &x->rt, err) != GI_OK) {
        free(x);
        return NULL;
    }
    return x;
}

void avg_exact_free(avg_exact *x)
{
    if (!x)
        return;
    gi_rt_free(x->rt);
    free(x->emitters);
    free(x);
}

static gi_vec3 vertex(const float *pos, uint32_t v)
{
    return gi_v3(pos[3 * v], pos[3 * v + 1], pos[3 * v + 2]);
}

static gi_vec3 material_albedo(const gi_scene *s, uint32_t tri, float bu, float bv)
{
    const gi_vertex *v0 = &s->vertices[s->indices[3 * tri]];
    const gi_material *m = &s->materials[v0->material];
    gi_vec3 a = gi_v3(m->albedo[0], m->albedo[1], m->albedo[2]);
    if (m->albedo_texture < 0)
        return a;
    const gi_vertex *v1 = &s->vertices[s->indices[3 * tri + 1]],
                    *v2 = &s->vertices[s->indices[3 * tri + 2]];
    float u = (1 - bu - bv) * v0->uv[0] + bu * v1->uv[0] + bv * v2->uv[0];
    float v = (1 - bu - bv) * v0->uv[1] + bu * v1->uv[1] + bv * v2->uv[1];
    const gi_texture *t = &s->textures[m->albedo_texture];
    u -= floorf(u);
    v -= floorf(v);
    uint32_t col = (uint32_t)(u * (float)t->width), row = (uint32_t)(v * (float)t->height);
    col = col < t->width ? col : t->width - 1;
    row = row < t->height ? row : t->height - 1;
    const float *px = &t->rgba[4 * ((size_t)row * t->width + col)];
    return gi_v3(a.x * px[0], a.y * px[1], a.z * px[2]);
}

static void set_v3(float *dst, gi_vec3 v)
{
    dst[0] = v.x;
    dst[1] = v.y;
    dst[2] = v.z;
}

/* A path's light vertex: the VPL of slot 0 and the path's first ray. */
typedef struct path_start {
    avg_vpl v;
    gi_vec3 origin, dir, flux;
} path_start;

/* On the area lights: a point on the emitter triangle that ue picks, its
 * VPL, and a cosine-distributed ray about the triangle's normal (for a
 * double-sided emitter, about the face path i's parity picks). 0 for a
 * degenerate triangle or emitter. */
static int start_on_emitter(const avg_exact *x, const gi_scene *s, float ue, float pl, float N,
                            uint32_t i, const float q0[2], const float q1[2], float eps,
                            path_start *ps)
{
    const float *pos = gi_rt_positions(x->rt);
    const gi_gpu_emitter *em = &x->emitters[gi_emitter_find_cpu(x->emitters, x->emitter_count, ue)];
    uint32_t tri = em->triangle;
    gi_vec3 p0 = vertex(pos, s->indices[3 * tri]), p1 = vertex(pos, s->indices[3 * tri + 1]),
            p2 = vertex(pos, s->indices[3 * tri + 2]);
    float bc[3];
    gi_sample_uniform_triangle(q0[0], q0[1], bc);
    gi_vec3 ng = gi_v3_cross(gi_v3_sub(p1, p0), gi_v3_sub(p2, p0));
    float area = 0.5f * gi_v3_length(ng);
    if (!(area > 0.0f) || !(em->pdf > 0.0f))
        return 0;
    const gi_material *m = &s->materials[s->vertices[s->indices[3 * tri]].material];
    gi_vec3 axis = gi_v3_scale(ng, 1.0f / (2.0f * area));
    float pdf_area = pl * em->pdf / area;
    gi_vec3 y = gi_v3_add(gi_v3_add(gi_v3_scale(p0, bc[0]), gi_v3_scale(p1, bc[1])),
                          gi_v3_scale(p2, bc[2]));
    set_v3(ps->v.position, y);
    ps->v.kind = AVG_VPL_DIFFUSE | (m->double_sided ? 0x10000u : 0u);
    ps->flux =
        gi_v3_scale(gi_v3(m->emission[0], m->emission[1], m->emission[2]), GI_PI / (pdf_area * N));
    if (m->double_sided) { /* both faces emit: the path's parity picks one, at twice the power */
        ps->flux = gi_v3_scale(ps->flux, 2.0f);
        if (i & 1u)
            axis = gi_v3_scale(axis, -1.0f);
    }
    set_v3(ps->v.normal, axis);
    set_v3(ps->v.power, ps->flux);
    ps->dir = gi_to_world(gi_sample_cosine_hemisphere(q1[0], q1[1]), axis);
    ps->origin = gi_v3_add(y, gi_v3_scale(axis, eps));
    return 1;
}

/* At point or spot light L (entry l): its VPL and a ray uniform in the
 * spot's cone or over the sphere. */
static void start_at_light(const gi_gpu_light *L, uint32_t l, float pl, float N, const float q1[2],
                           path_start *ps)
{
    gi_vec3 I =
        gi_v3_scale(gi_v3(L->intensity[0], L->intensity[1], L->intensity[2]), 1.0f / (pl * N));
    gi_vec3 ldir = gi_v3(L->direction[0], L->direction[1], L->direction[2]);
    memcpy(ps->v.position, L->position, sizeof ps->v.position);
    ps->v.range = L->range;
    memcpy(ps->v.spot_dir, L->direction, sizeof ps->v.spot_dir);
    int spot = L->type == GI_LIGHT_SPOT;
    ps->v.kind = spot ? AVG_VPL_SPOT : AVG_VPL_POINT;
    ps->v.cos_inner = L->cos_inner;
    ps->v.cos_outer = L->cos_outer;
    /* the light's intensity and entry, as avg_trace.comp (avg.c's
     * punctual_parts gives the VPL its cover and share) */
    set_v3(ps->v.normal, spot ? ldir : gi_v3(0, 1, 0));
    memcpy(ps->v.power, L->intensity, sizeof ps->v.power);
    ps->v.kind |= l << 24;
    if (spot) {
        ps->dir = gi_to_world(gi_sample_uniform_cone(q1[0], q1[1], L->cos_outer), ldir);
        ps->flux =
            gi_v3_scale(I, gi_spot_falloff(gi_v3_dot(ps->dir, ldir), L->cos_inner, L->cos_outer) /
                               gi_uniform_cone_pdf(L->cos_outer));
    } else {
        ps->dir = gi_sample_uniform_sphere(q1[0], q1[1]);
        ps->flux = gi_v3_scale(I, 1.0f / gi_uniform_sphere_pdf());
    }
    ps->origin = gi_v3_load(L->position);
}

static void trace_path(const avg_exact *x, const gi_scene *s, const avg_light_table *lt,
                       const avg_trace_desc *d, uint32_t mask, float eps, uint32_t i,
                       avg_vpl *slots)
{
    float N = (float)d->paths;
    float u = ((float)i + 0.5f) / N;
    uint32_t l = 0;
    while (l + 1 < lt->count && lt->cdf[l] <= u)
        l++;
    float pl = lt->pdf[l];
    if (!(pl > 0.0f))
        return;
    float lo = l > 0 ? lt->cdf[l - 1] : 0.0f;
    float q0[2], q1[2];
    avg_qr(i, 0, mask, d->seed, q0);
    avg_qr(i, 1, mask, d->seed, q1);
    path_start ps;
    memset(&ps.v, 0, sizeof ps.v);
    if (l == 0) {
        float ue = (u - lo) / pl;
        ue = ue < 0.0f ? 0.0f : (ue > GI_ONE_MINUS_EPSILON ? GI_ONE_MINUS_EPSILON : ue);
        if (!start_on_emitter(x, s, ue, pl, N, i, q0, q1, eps, &ps))
            return;
    } else {
        start_at_light(&x->lights[l - 1], l, pl, N, q1, &ps);
    }
    slots[0] = ps.v;
    gi_vec3 origin = ps.origin, dir = ps.dir, flux = ps.flux;

    for (uint32_t k = 1; k <= d->bounces; k++) {
        gi_rt_hit hit;
        if (!gi_rt_intersect(x->rt, origin, dir, 0.0f, INFINITY, &hit))
            return;
        float qp[2];
        avg_qr(i, 2 * k + 1, mask, d->seed, qp);
        gi_vec3 c = material_albedo(s, hit.triangle, hit.u, hit.v);
        gi_vec3 n = hit.ng;
        if (gi_v3_dot(n, dir) > 0.0f)
            n = gi_v3_scale(n, -1.0f);
        avg_vpl h;
        memset(&h, 0, sizeof h);
        set_v3(h.position, hit.position);
        h.kind = AVG_VPL_DIFFUSE | (k << 8);
        set_v3(h.normal, n);
        set_v3(h.power, gi_v3_mul(flux, c));
        slots[k] = h;
        if (k == d->bounces)
            return;
        float q = fminf(fmaxf(c.x, fmaxf(c.y, c.z)), 1.0f);
        if (!(qp[1] < q))
            return;
        flux = gi_v3_scale(gi_v3_mul(flux, c), 1.0f / q);
        float qd[2];
        avg_qr(i, 2 * k, mask, d->seed, qd);
        dir = gi_to_world(gi_sample_cosine_hemisphere(qd[0], qd[1]), n);
        origin = gi_v3_add(hit.position, gi_v3_scale(n, eps));
    }
}

gi_result avg_exact_trace(avg_exact *x, const gi_gpu_scene *gs, const avg_light_table *lt,
                          const avg_trace_desc *d, avg_vpl *slots, gi_error *err)
{
    if (gi_rt_time(x->rt) != gs->time && gi_rt_set_time(x->rt, gs->time, err) != GI_OK)
        return GI_ERR_INVALID_ARGUMENT;
    /* The light records as the GPU has them at this time. */
    if (x->emitter_count != gs->emitter_count) {
        free(x->emitters);
        x->emitters = calloc(gs->emitter_count ? gs->emitter_count : 1, sizeof *x->emitters);
        if (!x->emitters)
            return gi_error_set(err, GI_ERR_OUT_OF_MEMORY, "avg: out of memory");
        x->emitter_count = gs->emitter_count;
    }
    if (x->emitter_count)
        glGetNamedBufferSubData(gs->ssbo_emitters, 0,
                                (GLsizeiptr)(x->emitter_count * sizeof(gi_gpu_emitter)),
                                x->emitters);
    x->light_count = gs->light_count < AVG_MAX_PUNCTUAL ? gs->light_count : AVG_MAX_PUNCTUAL;
    if (x->light_count)
        glGetNamedBufferSubData(gs->ssbo_lights, 0,
                                (GLsizeiptr)(x->light_count * sizeof(gi_gpu_light)), x->lights);
    memset(slots, 0, (size_t)d->paths * (d->bounces + 1) * sizeof *slots);
    for (size_t s = 0; s < (size_t)d->paths * (d->bounces + 1); s++)
        slots[s].normal[1] = 1.0f;
    if (lt->count == 0)
        return GI_OK;
    float ext = 0.0f;
    for (int a = 0; a < 3; a++)
        ext = fmaxf(ext, gs->bounds[3 + a] - gs->bounds[a]);
    float eps = 1e-4f * (ext > 0.0f ? ext : 1.0f);
    uint32_t mask = 1;
    while (mask < d->paths)
        mask <<= 1;
    mask -= 1;
    for (uint32_t i = 0; i < d->paths; i++)
        trace_path(x, gs->scene, lt, d, mask, eps, i, slots + (size_t)i * (d->bounces + 1));
    return GI_OK;
}

void avg_vpl_contribution(const avg_vpl *v, const float x[3], const float n[3], float dmin2,
                          float out[3])
{
    out[0] = out[1] = out[2] = 0.0f;
    gi_vec3 d = gi_v3_sub(gi_v3_load(v->position), gi_v3_load(x));
    float d2 = gi_v3_dot(d, d);
    if (!(d2 > 0.0f))
        return;
    gi_vec3 w = gi_v3_scale(d, 1.0f / sqrtf(d2));
    float cos_x = gi_v3_dot(gi_v3_load(n), w);
    float cos_v = -gi_v3_dot(gi_v3_load(v->normal), w);
    if (cos_x <= 0.0f)
        return;
    uint32_t kind = v->kind & 0xFFu;
    float f;
    if (kind == AVG_VPL_DIFFUSE) {
        if (cos_v <= 0.0f)
            return;
        f = cos_v * GI_INV_PI * cos_x / fmaxf(d2, dmin2);
    } else {
        /* a hemisphere about the normal, or the cube face whose axis it is */
        float o[3] = {-w.x, -w.y, -w.z};
        if ((v->kind & AVG_VPL_FACE)
                ? gi_cube_face(gi_v3_load(o)) != gi_cube_face(gi_v3_load(v->normal))
                : cos_v <= 0.0f)
            return;
        f = cos_x / fmaxf(d2, dmin2) * gi_range_window(sqrtf(d2), v->range);
        if (kind == AVG_VPL_SPOT)
            f *=
                gi_spot_falloff(-gi_v3_dot(w, gi_v3_load(v->spot_dir)), v->cos_inner, v->cos_outer);
    }
    for (int c = 0; c < 3; c++)
        out[c] = v->power[c] * f;
}
