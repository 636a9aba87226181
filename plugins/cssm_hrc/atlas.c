/* The illumination atlas of cssm_hrc (§3.2.3, Fig. 5) and its coherent
 * traversals (Fig. 6/7). Charts are built here rather than taken from the
 * meshes' uvs: the shipped scenes' uvs are texture coordinates, not
 * non-overlapping atlases (README). */
#include "cssm.h"

#include "gi/rng.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MAX_GROUPS_PER_OBJECT 256u
#define MIN_CHART_TEXELS 4.0

typedef struct group {
    uint32_t object;
    gi_vec3 n;
    float d;
    double area;
    uint32_t first_tri; /* linked list through next_tri */
    int chart;
} group;

static float tri_area(const gi_vec3 p[3], gi_vec3 *n)
{
    gi_vec3 c = gi_v3_cross(gi_v3_sub(p[1], p[0]), gi_v3_sub(p[2], p[0]));
    float l = gi_v3_length(c);
    *n = l > 0.0f ? gi_v3_scale(c, 1.0f / l) : gi_v3(0, 1, 0);
    return 0.5f * l;
}

/* The material of texel x on triangle tri (world corners p): albedo
 * factor x texture at the texel's centre (the mesh uvs interpolated
 * there, gi_scene_albedo), emission and Phong lobe. */
static void material_of(const gi_scene *s, uint32_t tri, const gi_vec3 p[3], cssm_texel *x)
{
    cssm_texel_material(s, tri, p, x);
}

void cssm_texel_material(const gi_scene *s, uint32_t tri, const gi_vec3 p[3], cssm_texel *x)
{
    const uint32_t *idx = &s->indices[3 * (size_t)tri];
    const uint32_t mat = s->vertices[idx[0]].material;
    const gi_material *m = &s->materials[mat];
    /* barycentric coordinates of x->p in the triangle (clamped inside) */
    gi_vec3 e1 = gi_v3_sub(p[1], p[0]), e2 = gi_v3_sub(p[2], p[0]), d = gi_v3_sub(x->p, p[0]);
    float a = gi_v3_dot(e1, e1), b = gi_v3_dot(e1, e2), c = gi_v3_dot(e2, e2);
    float f = gi_v3_dot(d, e1), g = gi_v3_dot(d, e2), den = a * c - b * b;
    float u = den > 0.0f ? (c * f - b * g) / den : 0.0f,
          v = den > 0.0f ? (a * g - b * f) / den : 0.0f;
    u = fminf(fmaxf(u, 0.0f), 1.0f), v = fminf(fmaxf(v, 0.0f), 1.0f - u);
    float uv[2];
    for (int k = 0; k < 2; k++)
        uv[k] = (1.0f - u - v) * s->vertices[idx[0]].uv[k] + u * s->vertices[idx[1]].uv[k] +
                v * s->vertices[idx[2]].uv[k];
    gi_scene_albedo(s, mat, uv, x->albedo);
    memcpy(x->emission, m->emission, sizeof x->emission);
    memcpy(x->ks, m->ks, sizeof x->ks);
    x->exponent = m->exponent;
}

/* 2D point-in-triangle (barycentric signs, inclusive). */
static int inside(float px, float py, const float t[6])
{
    float d1 = (px - t[2]) * (t[1] - t[3]) - (t[0] - t[2]) * (py - t[3]);
    float d2 = (px - t[4]) * (t[3] - t[5]) - (t[2] - t[4]) * (py - t[5]);
    float d3 = (px - t[0]) * (t[5] - t[1]) - (t[4] - t[0]) * (py - t[1]);
    int neg = d1 < 0 || d2 < 0 || d3<0, pos = d1> 0 || d2 > 0 || d3 > 0;
    return !(neg && pos);
}

typedef struct rect {
    uint32_t w, h, g; /* size in texels, group */
} rect;

static int rect_cmp(const void *a, const void *b)
{
    const rect *x = a, *y = b;
    if (x->h != y->h)
        return x->h < y->h ? 1 : -1;
    return x->g < y->g ? -1 : (x->g > y->g);
}

/* Skyline packing, tallest first, 1 texel gutter: each chart goes where
 * it sits lowest (leftmost on ties); 1 when all fit. */
static int pack(rect *r, uint32_t n, uint32_t R, uint32_t *x0, uint32_t *y0)
{
    qsort(r, n, sizeof *r, rect_cmp);
    uint32_t *sky = calloc(R, sizeof *sky);
    if (!sky)
        return 0;
    int ok = 1;
    for (uint32_t i = 0; i < n && ok; i++) {
        uint32_t w = r[i].w, best_x = 0, best_y = UINT32_MAX;
        if (w > R) {
            ok = 0;
            break;
        }
        for (uint32_t x = 0; x + w <= R; x++) {
            uint32_t y = 0;
            for (uint32_t k = x; k < x + w; k++)
                y = sky[k] > y ? sky[k] : y;
            if (y < best_y)
                best_y = y, best_x = x;
        }
        if (best_y == UINT32_MAX || best_y + r[i].h > R) {
            ok = 0;
            break;
        }
        x0[r[i].g] = best_x;
        y0[r[i].g] = best_y;
        for (uint32_t k = best_x; k < best_x + w + 1 && k < R; k++)
            sky[k] = best_y + r[i].h + 1;
    }
    free(sky);
    return ok;
}

/* What cssm_atlas_build works with between its steps: the scene's
 * triangles in world space, their planar groups, the charts' frames and
 * packing, the surface samples per object. */
typedef struct atlas_build {
    const gi_scene *s;
    uint32_t T;                    /* triangles */
    gi_vec3 *P, *Nf;               /* world corners (3 per triangle), unit normals */
    float *A;                      /* triangle areas */
    int32_t *tri_group, *next_tri; /* per triangle: its group (-1: none), the group's next */
    group *g;                      /* planar groups */
    uint32_t ng, cap;
    rect *rects;          /* the charts' rectangles (sorted by pack) */
    uint32_t nr;          /* charts */
    uint32_t *x0, *y0;    /* per group: its chart's corner in the atlas */
    gi_vec3 *U, *V;       /* per group: the chart's axes */
    float *umin;          /* per group: 2, the smallest coordinates along U and V */
    float h;              /* texel edge */
    double chart_area;    /* of the groups with a chart */
    double *rest;         /* per object: area left to surface samples */
    uint32_t *per_object; /* per object: its surface samples */
    uint32_t samples;     /* surface samples in all */
    uint32_t cap_texels;  /* texels allocated */
} atlas_build;

static void atlas_build_free(atlas_build *b)
{
    free(b->rest), free(b->per_object);
    free(b->rects), free(b->x0), free(b->y0), free(b->U), free(b->V), free(b->umin);
    free(b->P), free(b->Nf), free(b->A), free(b->tri_group), free(b->next_tri), free(b->g);
}

/* The triangles at time t in world space: corners, normals, areas; the
 * surface area and the diameter of the scene. */
static gi_result atlas_triangles(atlas_build *b, float t, cssm_atlas *out, gi_error *err)
{
    const uint32_t T = b->T;
    b->P = malloc((size_t)T * 3 * sizeof *b->P), b->Nf = malloc((size_t)T * sizeof *b->Nf);
    b->A = malloc((size_t)T * sizeof *b->A);
    b->tri_group = malloc((size_t)T * sizeof *b->tri_group),
    b->next_tri = malloc((size_t)T * sizeof *b->next_tri);
    if (!b->P || !b->Nf || !b->A || !b->tri_group || !b->next_tri)
        return GI_ERR_OUT_OF_MEMORY;
    gi_vec3 *P = b->P;
    float lo[3] = {FLT_MAX, FLT_MAX, FLT_MAX}, hi[3] = {-FLT_MAX, -FLT_MAX, -FLT_MAX};
    for (uint32_t i = 0; i < T; i++) {
        gi_scene_triangle_world(b->s, i, t, &P[3 * i]);
        b->A[i] = tri_area(&P[3 * i], &b->Nf[i]);
        out->surface_area += b->A[i];
        for (int k = 0; k < 3; k++) {
            float q[3] = {P[3 * i + k].x, P[3 * i + k].y, P[3 * i + k].z};
            for (int j = 0; j < 3; j++)
                lo[j] = fminf(lo[j], q[j]), hi[j] = fmaxf(hi[j], q[j]);
        }
    }
    if (!(out->surface_area > 0.0))
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                            "cssm_hrc: the scene has no surface area to build an atlas on");
    out->diameter = gi_v3_length(gi_v3(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]));
    return GI_OK;
}

/* Planar groups per object: the triangles of one object in one plane
 * (normal and offset within tolerance); an object of more than
 * MAX_GROUPS_PER_OBJECT planes gets none. */
static gi_result atlas_group_planes(atlas_build *b, float diameter)
{
    const gi_scene *s = b->s;
    const gi_vec3 *P = b->P, *Nf = b->Nf;
    int32_t *tri_group = b->tri_group, *next_tri = b->next_tri;
    for (uint32_t o = 0; o < s->object_count; o++) {
        const gi_object *ob = &s->objects[o];
        uint32_t first_group = b->ng;
        int overflow = 0;
        for (uint32_t i = ob->first_triangle; i < ob->first_triangle + ob->triangle_count; i++) {
            tri_group[i] = -1;
            next_tri[i] = -1;
            if (!(b->A[i] > 0.0f) || overflow)
                continue;
            float d = gi_v3_dot(Nf[i], P[3 * i]);
            uint32_t k = first_group;
            for (; k < b->ng; k++)
                if (gi_v3_dot(b->g[k].n, Nf[i]) > 0.9999f &&
                    fabsf(b->g[k].d - d) < 1e-4f * diameter)
                    break;
            if (k == b->ng) {
                if (b->ng - first_group >= MAX_GROUPS_PER_OBJECT) {
                    overflow = 1; /* a curved mesh: surface samples for the whole object */
                    continue;
                }
                if (b->ng == b->cap) {
                    b->cap = b->cap ? 2 * b->cap : 64;
                    group *ng_ = realloc(b->g, b->cap * sizeof *b->g);
                    if (!ng_)
                        return GI_ERR_OUT_OF_MEMORY;
                    b->g = ng_;
                }
                b->g[b->ng] = (group){.object = o,
                                      .n = Nf[i],
                                      .d = d,
                                      .area = 0,
                                      .first_tri = UINT32_MAX,
                                      .chart = -1};
                b->ng++;
            }
            b->g[k].area += b->A[i];
            next_tri[i] = (int32_t)b->g[k].first_tri;
            b->g[k].first_tri = i;
            tri_group[i] = (int32_t)k;
        }
        if (overflow)
            for (uint32_t i = ob->first_triangle; i < ob->first_triangle + ob->triangle_count; i++)
                tri_group[i] = -1;
        if (overflow)
            b->ng = first_group;
    }
    return GI_OK;
}

/* Each group's chart axes (an orthonormal basis of its plane) and the
 * smallest coordinates of its corners along them. */
static gi_result atlas_chart_frames(atlas_build *b)
{
    const uint32_t ng = b->ng;
    b->rects = malloc((ng ? ng : 1) * sizeof *b->rects);
    b->x0 = malloc((ng ? ng : 1) * sizeof *b->x0), b->y0 = malloc((ng ? ng : 1) * sizeof *b->y0);
    b->U = malloc((ng ? ng : 1) * sizeof *b->U), b->V = malloc((ng ? ng : 1) * sizeof *b->V);
    b->umin = malloc((ng ? ng : 1) * 2 * sizeof *b->umin);
    if (!b->rects || !b->x0 || !b->y0 || !b->U || !b->V || !b->umin)
        return GI_ERR_OUT_OF_MEMORY;
    for (uint32_t k = 0; k < ng; k++) {
        gi_onb(b->g[k].n, &b->U[k], &b->V[k]);
        float a0 = FLT_MAX, b0 = FLT_MAX;
        for (int32_t i = (int32_t)b->g[k].first_tri; i >= 0; i = b->next_tri[i])
            for (int j = 0; j < 3; j++)
                a0 = fminf(a0, gi_v3_dot(b->P[3 * i + j], b->U[k])),
                b0 = fminf(b0, gi_v3_dot(b->P[3 * i + j], b->V[k]));
        b->umin[2 * k] = a0, b->umin[2 * k + 1] = b0;
    }
    return GI_OK;
}

/* The texel size: start at 90 % fill and grow until the charts (groups
 * of at least MIN_CHART_TEXELS texels) pack into the R x R atlas. */
static gi_result atlas_pack_charts(atlas_build *b, uint32_t R, double surface_area, gi_error *err)
{
    group *g = b->g;
    float h = (float)sqrt(surface_area / (0.9 * (double)R * (double)R));
    for (int attempt = 0; attempt < 400; attempt++, h *= 1.02f) {
        b->nr = 0;
        b->chart_area = 0.0;
        for (uint32_t k = 0; k < b->ng; k++) {
            g[k].chart = -1;
            if (g[k].area / ((double)h * h) < MIN_CHART_TEXELS)
                continue;
            float a1 = -FLT_MAX, b1 = -FLT_MAX;
            for (int32_t i = (int32_t)g[k].first_tri; i >= 0; i = b->next_tri[i])
                for (int j = 0; j < 3; j++)
                    a1 = fmaxf(a1, gi_v3_dot(b->P[3 * i + j], b->U[k])),
                    b1 = fmaxf(b1, gi_v3_dot(b->P[3 * i + j], b->V[k]));
            b->rects[b->nr].w = (uint32_t)ceilf((a1 - b->umin[2 * k]) / h);
            b->rects[b->nr].h = (uint32_t)ceilf((b1 - b->umin[2 * k + 1]) / h);
            b->rects[b->nr].g = k;
            g[k].chart = (int)b->nr;
            b->chart_area += g[k].area;
            b->nr++;
        }
        if (pack(b->rects, b->nr, R, b->x0, b->y0))
            break;
        if (attempt == 399)
            return gi_error_set(err, GI_ERR_INVALID_ARGUMENT,
                                "cssm_hrc: the charts do not pack into a %u x %u atlas", R, R);
    }
    b->h = h;
    return GI_OK;
}

/* The atlas' grid and charts allocated, and the surface samples of each
 * object: its area outside charts at the charts' density. */
static gi_result atlas_sample_counts(atlas_build *b, cssm_atlas *out)
{
    const gi_scene *s = b->s;
    const uint32_t R = out->R;
    const float h = b->h;
    out->grid = malloc((size_t)R * R * sizeof *out->grid);
    out->charts = calloc(b->nr ? b->nr : 1, sizeof *out->charts);
    /* sample counts of the objects without charts */
    b->rest = calloc(s->object_count ? s->object_count : 1, sizeof *b->rest);
    b->samples = 0;
    if (!out->grid || !out->charts || !b->rest)
        return GI_ERR_OUT_OF_MEMORY;
    for (uint32_t i = 0; i < b->T; i++)
        if (b->tri_group[i] < 0 || b->g[b->tri_group[i]].chart < 0)
            b->rest[s->vertices[s->indices[3 * i]].object] += b->A[i];
    b->per_object = calloc(s->object_count ? s->object_count : 1, sizeof *b->per_object);
    if (!b->per_object)
        return GI_ERR_OUT_OF_MEMORY;
    for (uint32_t o = 0; o < s->object_count; o++) {
        b->per_object[o] =
            b->rest[o] > 0.0 ? (uint32_t)fmax(1.0, floor(b->rest[o] / ((double)h * h) + 0.5)) : 0u;
        b->samples += b->per_object[o];
    }
    for (size_t i = 0; i < (size_t)R * R; i++)
        out->grid[i] = -1;
    b->cap_texels = b->samples + 1024;
    out->texels = malloc(b->cap_texels * sizeof *out->texels);
    if (!out->texels)
        return GI_ERR_OUT_OF_MEMORY;
    return GI_OK;
}

/* Group k's chart rasterised: a texel whose centre lies in a triangle of
 * the chart; the texel areas add up to the group's. */
static gi_result atlas_rasterise_chart(atlas_build *b, uint32_t k, cssm_atlas *out)
{
    const group *g = b->g;
    const gi_vec3 *P = b->P, *U = b->U, *V = b->V;
    const float *umin = b->umin;
    const float h = b->h;
    const uint32_t R = out->R;
    cssm_chart *c = &out->charts[g[k].chart];
    uint32_t ci = (uint32_t)g[k].chart;
    c->object = g[k].object;
    c->x0 = b->x0[k], c->y0 = b->y0[k];
    for (uint32_t q = 0; q < b->nr; q++)
        if (b->rects[q].g == k)
            c->w = b->rects[q].w, c->h = b->rects[q].h;
    c->normal = g[k].n;
    c->u = gi_v3_scale(U[k], h);
    c->v = gi_v3_scale(V[k], h);
    /* the plane point at (umin, vmin) */
    c->origin =
        gi_v3_add(gi_v3_scale(g[k].n, g[k].d),
                  gi_v3_add(gi_v3_scale(U[k], umin[2 * k]), gi_v3_scale(V[k], umin[2 * k + 1])));
    uint32_t first = out->count;
    for (uint32_t yy = 0; yy < c->h; yy++)
        for (uint32_t xx = 0; xx < c->w; xx++) {
            float pu = ((float)xx + 0.5f) * h, pv = ((float)yy + 0.5f) * h;
            int32_t hit = -1;
            for (int32_t i = (int32_t)g[k].first_tri; i >= 0 && hit < 0; i = b->next_tri[i]) {
                float tr[6];
                for (int j = 0; j < 3; j++) {
                    tr[2 * j] = gi_v3_dot(P[3 * i + j], U[k]) - umin[2 * k];
                    tr[2 * j + 1] = gi_v3_dot(P[3 * i + j], V[k]) - umin[2 * k + 1];
                }
                if (inside(pu, pv, tr))
                    hit = i;
            }
            if (hit < 0)
                continue;
            if (out->count == b->cap_texels) {
                b->cap_texels *= 2;
                cssm_texel *nt = realloc(out->texels, b->cap_texels * sizeof *nt);
                if (!nt)
                    return GI_ERR_OUT_OF_MEMORY;
                out->texels = nt;
            }
            cssm_texel *x = &out->texels[out->count];
            memset(x, 0, sizeof *x);
            x->p = gi_v3_add(c->origin, gi_v3_add(gi_v3_scale(U[k], pu), gi_v3_scale(V[k], pv)));
            x->n = g[k].n;
            x->chart = (int32_t)ci;
            x->x = c->x0 + xx, x->y = c->y0 + yy;
            x->triangle = (uint32_t)hit;
            material_of(b->s, (uint32_t)hit, &P[3 * (size_t)hit], x);
            out->grid[(size_t)x->y * R + x->x] = (int32_t)out->count;
            out->count++;
        }
    uint32_t n_in = out->count - first;
    out->covered_area += (double)n_in * h * h;
    for (uint32_t i = first; i < out->count; i++)
        out->texels[i].area = (float)(g[k].area / (n_in ? n_in : 1));
    /* a chart without a texel centre inside: its area is lost (reported by coverage) */
    return GI_OK;
}

/* Every chart rasterised, then each triangle's chart (-1: none). */
static gi_result atlas_rasterise_charts(atlas_build *b, cssm_atlas *out)
{
    out->chart_count = b->nr;
    for (uint32_t k = 0; k < b->ng; k++) {
        if (b->g[k].chart < 0)
            continue;
        gi_result r = atlas_rasterise_chart(b, k, out);
        if (r != GI_OK)
            return r;
    }
    out->chart_texels = out->count;
    out->tri_chart = malloc((size_t)b->T * sizeof *out->tri_chart);
    if (!out->tri_chart)
        return GI_ERR_OUT_OF_MEMORY;
    for (uint32_t i = 0; i < b->T; i++)
        out->tri_chart[i] = b->tri_group[i] >= 0 ? b->g[b->tri_group[i]].chart : -1;
    return GI_OK;
}

/* Surface samples: systematic sampling of each object's remaining area
 * (§3.2.3, last paragraph). */
static gi_result atlas_surface_samples(atlas_build *b, cssm_atlas *out)
{
    const gi_scene *s = b->s;
    if (out->count + b->samples > b->cap_texels) {
        cssm_texel *nt = realloc(out->texels, (out->count + b->samples + 1) * sizeof *nt);
        if (!nt)
            return GI_ERR_OUT_OF_MEMORY;
        out->texels = nt;
    }
    for (uint32_t o = 0; o < s->object_count; o++) {
        const uint32_t want = b->per_object[o];
        if (!want)
            continue;
        const gi_object *ob = &s->objects[o];
        uint32_t rng = gi_rng_init(o, 0, 0xa71a5u);
        double step = b->rest[o] / want, acc = 0.0, target = step * gi_rng_next_float(&rng);
        uint32_t made = 0;
        for (uint32_t i = ob->first_triangle;
             i < ob->first_triangle + ob->triangle_count && made < want; i++) {
            if (b->tri_group[i] >= 0 && b->g[b->tri_group[i]].chart >= 0)
                continue;
            acc += b->A[i];
            while (target < acc && made < want) {
                float u1 = gi_rng_next_float(&rng), u2 = gi_rng_next_float(&rng);
                if (u1 + u2 > 1.0f)
                    u1 = 1.0f - u1, u2 = 1.0f - u2;
                cssm_texel *x = &out->texels[out->count++];
                memset(x, 0, sizeof *x);
                gi_vec3 *p = &b->P[3 * i];
                x->p = gi_v3_add(p[0], gi_v3_add(gi_v3_scale(gi_v3_sub(p[1], p[0]), u1),
                                                 gi_v3_scale(gi_v3_sub(p[2], p[0]), u2)));
                x->n = b->Nf[i];
                x->area = (float)step;
                x->chart = -1;
                x->x = x->y = CSSM_NO_XY;
                x->triangle = i;
                material_of(s, i, &b->P[3 * (size_t)i], x);
                made++;
                target += step;
            }
        }
        out->covered_area += step * made;
    }
    return GI_OK;
}

static int tri_double_sided(const gi_scene *s, uint32_t tri)
{
    return s->materials[s->vertices[s->indices[3 * (size_t)tri]].material].double_sided != 0;
}

/* The back sides of double-sided materials (glTF 2.0 doubleSided: back
 * faces are lit with reversed normals, an emitter emits from both sides).
 * A texel of the paper's atlas holds one position, one normal and one
 * radiance (§3.2.3: "3D position, normal, area, radiance and BRDF
 * parameters"), and the two sides of a sheet receive different light (a
 * panel lit from one side), so the back side gets texels of its own: a
 * copy of each front texel with the normal reversed, its own cube map
 * (the eye on the back side), its own radiance and leaf. The copies have
 * no chart (the atlas grid holds the front sides; a chart mirrored into
 * the grid would halve every chart's resolution): they are surface samples
 * (§3.2.3, last paragraph), walked greedily after the charts, and a pixel
 * on a back side gathers its light itself (cssm_side_chart). Single-sided
 * back faces get no texel: they do not exist (issue 28's one rule). */
static gi_result atlas_back_sides(const gi_scene *s, cssm_atlas *out)
{
    const uint32_t n = out->count;
    uint32_t extra = 0;
    for (uint32_t i = 0; i < n; i++)
        extra += (uint32_t)tri_double_sided(s, out->texels[i].triangle);
    if (!extra)
        return GI_OK;
    cssm_texel *nt = realloc(out->texels, ((size_t)n + extra) * sizeof *nt);
    if (!nt)
        return GI_ERR_OUT_OF_MEMORY;
    out->texels = nt;
    for (uint32_t i = 0; i < n; i++) {
        if (!tri_double_sided(s, nt[i].triangle))
            continue;
        cssm_texel *x = &nt[out->count++];
        *x = nt[i];
        x->n = gi_v3_scale(nt[i].n, -1.0f);
        x->chart = -1;
        x->x = x->y = CSSM_NO_XY;
    }
    out->back_texels = extra;
    return GI_OK;
}

int32_t cssm_side_chart(const cssm_atlas *a, uint32_t tri, gi_vec3 n)
{
    int32_t chart = a->tri_chart[tri];
    if (chart >= 0 && gi_v3_dot(a->charts[chart].normal, n) < 0.0f)
        return -1; /* the back side of a double-sided chart: its texels are surface samples */
    return chart;
}

gi_result cssm_atlas_build(const gi_scene *s, float t, uint32_t R, int samples_only,
                           cssm_atlas *out, gi_error *err)
{
    memset(out, 0, sizeof *out);
    out->R = R;
    atlas_build b = {.s = s, .T = s->triangle_count};
    gi_result r = atlas_triangles(&b, t, out, err);
    if (r == GI_OK)
        r = atlas_group_planes(&b, out->diameter);
    if (r == GI_OK)
        r = atlas_chart_frames(&b);
    if (r == GI_OK)
        r = atlas_pack_charts(&b, R, out->surface_area, err);
    if (r == GI_OK) {
        if (samples_only) { /* the charts' texel size, no parametrisation */
            for (uint32_t k = 0; k < b.ng; k++)
                b.g[k].chart = -1;
            b.nr = 0;
            b.chart_area = 0.0;
        }
        out->h = b.h;
        out->chart_area = b.chart_area;
        r = atlas_sample_counts(&b, out);
    }
    if (r == GI_OK)
        r = atlas_rasterise_charts(&b, out);
    if (r == GI_OK)
        r = atlas_surface_samples(&b, out);
    if (r == GI_OK)
        r = atlas_back_sides(s, out);
    atlas_build_free(&b);
    if (r != GI_OK) {
        if (r == GI_ERR_OUT_OF_MEMORY)
            gi_error_set(err, r, "cssm_hrc: out of memory for the atlas");
        cssm_atlas_free(out);
        return r;
    }
    if (!out->count) {
        cssm_atlas_free(out);
        return gi_error_set(err, GI_ERR_INVALID_ARGUMENT, "cssm_hrc: the atlas has no texel");
    }
    return GI_OK;
}

void cssm_atlas_free(cssm_atlas *a)
{
    if (!a)
        return;
    free(a->grid);
    free(a->texels);
    free(a->charts);
    free(a->tri_chart);
    memset(a, 0, sizeof *a);
}

static int32_t chart_texel(const cssm_atlas *a, const cssm_chart *c, uint32_t ci, int x, int y);

void cssm_chart_coords(const cssm_atlas *a, uint32_t chart, gi_vec3 p, float *u, float *v)
{
    const cssm_chart *c = &a->charts[chart];
    gi_vec3 d = gi_v3_sub(p, c->origin);
    float h2 = a->h * a->h;
    *u = gi_v3_dot(d, c->u) / h2;
    *v = gi_v3_dot(d, c->v) / h2;
}

static float bspline(float t)
{
    t = fabsf(t);
    if (t < 1.0f)
        return (4.0f - 6.0f * t * t + 3.0f * t * t * t) / 6.0f;
    if (t < 2.0f) {
        float s = 2.0f - t;
        return s * s * s / 6.0f;
    }
    return 0.0f;
}

int cssm_chart_bicubic(const cssm_atlas *a, uint32_t chart, float u, float v, const float *values,
                       float out[3])
{
    const cssm_chart *c = &a->charts[chart];
    float gx = u - 0.5f, gy = v - 0.5f, wsum = 0.0f;
    int x0 = (int)floorf(gx), y0 = (int)floorf(gy);
    out[0] = out[1] = out[2] = 0.0f;
    for (int j = -1; j <= 2; j++)
        for (int i = -1; i <= 2; i++) {
            int32_t t = chart_texel(a, c, chart, x0 + i, y0 + j);
            if (t < 0)
                continue;
            float w = bspline(gx - (float)(x0 + i)) * bspline(gy - (float)(y0 + j));
            for (int k = 0; k < 3; k++)
                out[k] += w * values[3 * t + k];
            wsum += w;
        }
    if (!(wsum > 0.0f))
        return 0;
    for (int k = 0; k < 3; k++)
        out[k] /= wsum;
    return 1;
}

const char *cssm_traversal_name(cssm_traversal how)
{
    return how == CSSM_GREEDY ? "greedy" : how == CSSM_ZIGZAG ? "zigzag" : "spiral";
}

static float dist2(gi_vec3 a, gi_vec3 b)
{
    gi_vec3 d = gi_v3_sub(a, b);
    return gi_v3_dot(d, d);
}

/* Greedy nearest-neighbour walk over the texels with visited[i] == 0,
 * starting nearest to `from` (or at the first one); appends to order. */
static void greedy_walk(const cssm_atlas *a, unsigned char *visited, const gi_vec3 *from,
                        uint32_t *order, uint32_t *n)
{
    uint32_t left = 0;
    for (uint32_t i = 0; i < a->count; i++)
        left += !visited[i];
    gi_vec3 at = from ? *from : gi_v3(0, 0, 0);
    int have = from != NULL;
    while (left) {
        uint32_t best = UINT32_MAX;
        float bd = FLT_MAX;
        for (uint32_t i = 0; i < a->count; i++) {
            if (visited[i])
                continue;
            if (!have) {
                best = i;
                break;
            }
            float d = dist2(at, a->texels[i].p);
            if (d < bd)
                bd = d, best = i;
        }
        visited[best] = 1;
        order[(*n)++] = best;
        at = a->texels[best].p;
        have = 1;
        left--;
    }
}

/* Texel of chart c at chart-local (x, y), -1 outside or not in the chart. */
static int32_t chart_texel(const cssm_atlas *a, const cssm_chart *c, uint32_t ci, int x, int y)
{
    if (x < 0 || y < 0 || x >= (int)c->w || y >= (int)c->h)
        return -1;
    int32_t t = a->grid[(size_t)(c->y0 + (uint32_t)y) * a->R + c->x0 + (uint32_t)x];
    return t >= 0 && a->texels[t].chart == (int32_t)ci ? t : -1;
}

/* First texel of a chart in scan order (zig-zag and spiral start there). */
static int32_t chart_first(const cssm_atlas *a, uint32_t ci, const unsigned char *visited)
{
    const cssm_chart *c = &a->charts[ci];
    for (int y = 0; y < (int)c->h; y++)
        for (int x = 0; x < (int)c->w; x++) {
            int32_t t = chart_texel(a, c, ci, x, y);
            if (t >= 0 && !visited[t])
                return t;
        }
    return -1;
}

static void zigzag_chart(const cssm_atlas *a, uint32_t ci, unsigned char *visited, uint32_t *order,
                         uint32_t *n)
{
    const cssm_chart *c = &a->charts[ci];
    for (int y = 0; y < (int)c->h; y++)
        for (int k = 0; k < (int)c->w; k++) {
            int x = (y & 1) ? (int)c->w - 1 - k : k;
            int32_t t = chart_texel(a, c, ci, x, y);
            if (t >= 0 && !visited[t]) {
                visited[t] = 1;
                order[(*n)++] = (uint32_t)t;
            }
        }
}

/* Left-hand walk along the border of the unvisited region (§3.2.3). */
static void spiral_chart(const cssm_atlas *a, uint32_t ci, unsigned char *visited, uint32_t *order,
                         uint32_t *n, uint32_t *stack)
{
    const cssm_chart *c = &a->charts[ci];
    int32_t start;
    while ((start = chart_first(a, ci, visited)) >= 0) {
        uint32_t sp = 0;
        int dx = 1, dy = 0;
        int32_t cur = start;
        visited[cur] = 1;
        order[(*n)++] = (uint32_t)cur;
        stack[sp++] = (uint32_t)cur;
        while (sp) {
            int x = (int)(a->texels[cur].x - c->x0), y = (int)(a->texels[cur].y - c->y0);
            /* left, straight, right, back (left of (dx, dy) is (dy, -dx)) */
            int cand[4][2] = {{dy, -dx}, {dx, dy}, {-dy, dx}, {-dx, -dy}};
            int32_t next = -1;
            for (int k = 0; k < 4 && next < 0; k++) {
                int32_t t = chart_texel(a, c, ci, x + cand[k][0], y + cand[k][1]);
                if (t >= 0 && !visited[t]) {
                    next = t;
                    dx = cand[k][0], dy = cand[k][1];
                }
            }
            if (next < 0) { /* step back until a free neighbour shows */
                sp--;
                if (sp)
                    cur = (int32_t)stack[sp - 1];
                continue;
            }
            visited[next] = 1;
            order[(*n)++] = (uint32_t)next;
            stack[sp++] = (uint32_t)next;
            cur = next;
        }
    }
}

uint32_t *cssm_traverse(const cssm_atlas *a, cssm_traversal how)
{
    uint32_t *order = malloc((a->count ? a->count : 1) * sizeof *order);
    unsigned char *visited = calloc(a->count ? a->count : 1, 1);
    unsigned char *chart_done = calloc(a->chart_count ? a->chart_count : 1, 1);
    uint32_t *stack = malloc((a->count ? a->count : 1) * sizeof *stack);
    if (!order || !visited || !chart_done || !stack) {
        free(order), free(visited), free(chart_done), free(stack);
        return NULL;
    }
    uint32_t n = 0;
    if (how == CSSM_GREEDY) {
        greedy_walk(a, visited, NULL, order, &n);
    } else {
        gi_vec3 at = gi_v3(0, 0, 0);
        for (uint32_t done = 0; done < a->chart_count; done++) {
            /* nearest chart (its first texel) to the last texel visited */
            uint32_t best = 0;
            float bd = FLT_MAX;
            for (uint32_t ci = 0; ci < a->chart_count; ci++) {
                if (chart_done[ci])
                    continue;
                int32_t f = chart_first(a, ci, visited);
                float d = f < 0 ? 0.0f : (done ? dist2(at, a->texels[f].p) : (float)ci);
                if (d < bd)
                    bd = d, best = ci;
            }
            chart_done[best] = 1;
            if (how == CSSM_ZIGZAG)
                zigzag_chart(a, best, visited, order, &n);
            else
                spiral_chart(a, best, visited, order, &n, stack);
            if (n)
                at = a->texels[order[n - 1]].p;
        }
        greedy_walk(a, visited, n ? &at : NULL, order, &n);
    }
    free(visited), free(chart_done), free(stack);
    return order;
}

void cssm_traversal_measures(const cssm_atlas *a, const uint32_t *order, cssm_traversal_measure *m)
{
    memset(m, 0, sizeof *m);
    double total = 0.0, jumped = 0.0;
    const double h = a->h > 0.0f ? a->h : 1.0;
    for (uint32_t i = 1; order && i < a->count; i++) {
        const cssm_texel *p = &a->texels[order[i - 1]], *q = &a->texels[order[i]];
        double d = sqrt((double)dist2(p->p, q->p)) / h;
        total += d;
        if (d > 2.0) {
            m->jumps++;
            jumped += d;
        }
        if (gi_v3_dot(p->n, q->n) < 0.999f ||
            fabsf(gi_v3_dot(p->n, gi_v3_sub(q->p, p->p))) > 1e-3f * h)
            m->plane_changes++;
    }
    m->step_mean = a->count > 1 ? total / (a->count - 1) : 0.0;
    m->jump_length_share = total > 0.0 ? jumped / total : 0.0;
}
