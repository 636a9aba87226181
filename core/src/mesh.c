/* Mesh measurements the methods share (mesh.h): triangle areas at time t,
 * Ritter bounding spheres per object, and welded vertices with vertex ->
 * triangle adjacency and per-vertex areas, the implicit visibility surfels of
 * Dong et al. Sec. 4.1 (a vertex stands for a third of each adjacent face).
 */
#include "gi/mesh.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static float triangle_area(gi_vec3 a, gi_vec3 b, gi_vec3 c)
{
    return 0.5f * gi_v3_length(gi_v3_cross(gi_v3_sub(b, a), gi_v3_sub(c, a)));
}

void gi_mesh_triangle_areas(const gi_scene *s, float t, float *out)
{
    assert(s && (out || s->triangle_count == 0));
    for (uint32_t o = 0; o < s->object_count; o++) {
        const gi_object *obj = &s->objects[o];
        float m[16];
        gi_scene_object_transform(s, o, t, m);
        for (uint32_t tri = obj->first_triangle; tri < obj->first_triangle + obj->triangle_count;
             tri++) {
            const uint32_t *idx = s->indices + (size_t)tri * 3;
            gi_vec3 p[3];
            for (int k = 0; k < 3; k++)
                p[k] =
                    gi_mat4_point(m, obj->morph_count ? gi_scene_vertex_position(s, idx[k], t)
                                                      : gi_v3_load(s->vertices[idx[k]].position));
            out[tri] = triangle_area(p[0], p[1], p[2]);
        }
    }
}

/* ---- bounding spheres ---- */

static double dist2(const float *a, const double *b)
{
    double d0 = a[0] - b[0], d1 = a[1] - b[1], d2 = a[2] - b[2];
    return d0 * d0 + d1 * d1 + d2 * d2;
}

/* Index (in [first, first+n)) of the vertex farthest from p. */
static uint32_t farthest(const gi_scene *s, uint32_t first, uint32_t n, const double p[3])
{
    uint32_t best = first;
    double best_d = -1.0;
    for (uint32_t i = first; i < first + n; i++) {
        double d = dist2(s->vertices[i].position, p);
        if (d > best_d) {
            best_d = d;
            best = i;
        }
    }
    return best;
}

/* Ritter (1990): a sphere through the two far-apart points found from an
 * arbitrary start, then grown to take in every point outside it. */
void gi_mesh_object_sphere(const gi_scene *s, uint32_t object, float out[4])
{
    assert(s && object < s->object_count);
    const gi_object *o = &s->objects[object];
    memset(out, 0, 4 * sizeof(float));
    if (o->vertex_count == 0)
        return;
    const float *p0 = s->vertices[o->first_vertex].position;
    double start[3] = {p0[0], p0[1], p0[2]};
    const float *y = s->vertices[farthest(s, o->first_vertex, o->vertex_count, start)].position;
    double yd[3] = {y[0], y[1], y[2]};
    const float *z = s->vertices[farthest(s, o->first_vertex, o->vertex_count, yd)].position;
    double c[3], r = 0.5 * sqrt(dist2(z, yd));
    for (int k = 0; k < 3; k++)
        c[k] = 0.5 * ((double)y[k] + z[k]);
    for (uint32_t i = o->first_vertex; i < o->first_vertex + o->vertex_count; i++) {
        const float *p = s->vertices[i].position;
        double d = sqrt(dist2(p, c));
        if (d > r) { /* move the centre towards p so the new sphere touches p and the old one */
            double nr = 0.5 * (r + d);
            for (int k = 0; k < 3; k++)
                c[k] += (p[k] - c[k]) * (nr - r) / d;
            r = nr;
        }
    }
    for (int k = 0; k < 3; k++)
        out[k] = (float)c[k];
    out[3] = (float)r * (1.0f + 1e-6f); /* float rounding must not leave a vertex outside */
}

/* ---- welding ---- */

/* Grid cells of side `tol`, hashed with open addressing; each cell heads a
 * chain of welded vertices (next[]). With tol 0 the key is the exact
 * position, so only identical positions merge. */
typedef struct weld_grid {
    size_t capacity; /* power of two */
    int64_t (*keys)[3];
    int64_t *head; /* welded vertex at the head of the cell's chain, -1 = empty slot */
} weld_grid;

static uint64_t hash_key(const int64_t k[3])
{
    uint64_t h = (uint64_t)k[0] * 0x9E3779B97F4A7C15ull;
    h ^= (uint64_t)k[1] * 0xC2B2AE3D27D4EB4Full + (h << 6) + (h >> 2);
    h ^= (uint64_t)k[2] * 0x165667B19E3779F9ull + (h << 6) + (h >> 2);
    return h ^ (h >> 31);
}

/* Slot of cell k: where it is, or the empty slot where it would go. */
static size_t grid_slot(const weld_grid *g, const int64_t k[3])
{
    size_t i = (size_t)hash_key(k) & (g->capacity - 1);
    while (g->head[i] >= 0 && memcmp(g->keys[i], k, sizeof g->keys[i]) != 0)
        i = (i + 1) & (g->capacity - 1);
    return i;
}

static void cell_of(const float p[3], float tol, int64_t k[3])
{
    for (int a = 0; a < 3; a++) {
        if (tol > 0.0f) {
            double c = floor((double)p[a] / tol);
            c = c < -1e15 ? -1e15 : (c > 1e15 ? 1e15 : c); /* keeps the cast defined */
            k[a] = (int64_t)c;
        } else {
            float v = p[a] == 0.0f ? 0.0f : p[a]; /* -0 and +0 weld */
            int32_t bits;
            memcpy(&bits, &v, sizeof bits);
            k[a] = bits;
        }
    }
}

typedef struct weld_state {
    gi_welded *w;
    weld_grid grid;
    int64_t *next; /* chain of welded vertices in a cell */
    float tol;
} weld_state;

/* Welded vertex within tol of p (searching the 27 cells around it), or -1. */
static int64_t find_near(const weld_state *st, const float p[3], const int64_t k[3])
{
    int reach = st->tol > 0.0f ? 1 : 0;
    double tol2 = (double)st->tol * st->tol;
    for (int dx = -reach; dx <= reach; dx++)
        for (int dy = -reach; dy <= reach; dy++)
            for (int dz = -reach; dz <= reach; dz++) {
                int64_t nk[3] = {k[0] + dx, k[1] + dy, k[2] + dz};
                size_t slot = grid_slot(&st->grid, nk);
                for (int64_t v = st->grid.head[slot]; v >= 0; v = st->next[v]) {
                    const float *q = &st->w->positions[v * 3];
                    double dd = 0.0;
                    for (int a = 0; a < 3; a++)
                        dd += ((double)q[a] - p[a]) * ((double)q[a] - p[a]);
                    if (dd <= tol2)
                        return v;
                }
            }
    return -1;
}

static void weld_object(weld_state *st, const gi_scene *s, uint32_t object)
{
    const gi_object *o = &s->objects[object];
    gi_welded *w = st->w;
    for (size_t i = 0; i < st->grid.capacity; i++)
        st->grid.head[i] = -1;
    for (uint32_t i = o->first_vertex; i < o->first_vertex + o->vertex_count; i++) {
        const gi_vertex *v = &s->vertices[i];
        int64_t k[3];
        cell_of(v->position, st->tol, k);
        int64_t found = find_near(st, v->position, k);
        if (found < 0) {
            found = w->vertex_count++;
            memcpy(&w->positions[found * 3], v->position, 3 * sizeof(float));
            memset(&w->normals[found * 3], 0, 3 * sizeof(float));
            w->object[found] = object;
            size_t slot = grid_slot(&st->grid, k);
            if (st->grid.head[slot] < 0)
                memcpy(st->grid.keys[slot], k, sizeof st->grid.keys[slot]);
            st->next[found] = st->grid.head[slot];
            st->grid.head[slot] = found;
        }
        w->remap[i] = (uint32_t)found;
        for (int a = 0; a < 3; a++)
            w->normals[found * 3 + a] += v->normal[a];
    }
}

/* Averaged normals; where they cancel out, the first merged vertex's. */
static void finish_normals(gi_welded *w, const gi_scene *s)
{
    for (uint32_t i = s->vertex_count; i-- > 0;) { /* last write wins: the first vertex */
        float *n = &w->normals[w->remap[i] * 3];
        float l = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (!(l > 1e-6f) || !isfinite(l))
            memcpy(n, s->vertices[i].normal, 3 * sizeof(float));
    }
    for (uint32_t v = 0; v < w->vertex_count; v++) {
        float *n = &w->normals[v * 3];
        gi_v3_store(gi_v3_normalize(gi_v3_load(n)), n);
    }
}

/* Welded corners of triangle t, with repeats (degenerate welds) set to -1. */
static void distinct_corners(const gi_welded *w, const gi_scene *s, uint32_t t, int64_t c[3])
{
    for (int k = 0; k < 3; k++)
        c[k] = w->remap[s->indices[(size_t)t * 3 + k]];
    if (c[1] == c[0])
        c[1] = -1;
    if (c[2] == c[0] || c[2] == c[1])
        c[2] = -1;
}

static int build_adjacency(gi_welded *w, const gi_scene *s)
{
    w->tri_offsets = calloc((size_t)w->vertex_count + 1, sizeof(uint32_t));
    w->areas = calloc(w->vertex_count ? w->vertex_count : 1, sizeof(float));
    if (!w->tri_offsets || !w->areas)
        return 0;
    for (uint32_t t = 0; t < s->triangle_count; t++) {
        int64_t c[3];
        distinct_corners(w, s, t, c);
        for (int k = 0; k < 3; k++)
            if (c[k] >= 0)
                w->tri_offsets[c[k] + 1]++;
    }
    for (uint32_t v = 0; v < w->vertex_count; v++)
        w->tri_offsets[v + 1] += w->tri_offsets[v];
    w->tri_list = malloc((w->tri_offsets[w->vertex_count] + 1) * sizeof(uint32_t));
    uint32_t *fill = malloc(((size_t)w->vertex_count + 1) * sizeof(uint32_t));
    if (!w->tri_list || !fill) {
        free(fill);
        return 0;
    }
    memcpy(fill, w->tri_offsets, (size_t)w->vertex_count * sizeof(uint32_t));
    for (uint32_t t = 0; t < s->triangle_count; t++) {
        const uint32_t *idx = s->indices + (size_t)t * 3;
        float a = triangle_area(gi_v3_load(s->vertices[idx[0]].position),
                                gi_v3_load(s->vertices[idx[1]].position),
                                gi_v3_load(s->vertices[idx[2]].position));
        int64_t c[3];
        distinct_corners(w, s, t, c);
        for (int k = 0; k < 3; k++) {
            w->areas[w->remap[idx[k]]] += a / 3.0f; /* per corner: areas sum to the total */
            if (c[k] >= 0)
                w->tri_list[fill[c[k]]++] = t;
        }
    }
    free(fill);
    return 1;
}

static float scene_size(const gi_scene *s)
{
    const float *b = s->bounds;
    float d = gi_v3_length(gi_v3_sub(gi_v3_load(b + 3), gi_v3_load(b)));
    return isfinite(d) ? d : 0.0f;
}

gi_welded *gi_mesh_weld(const gi_scene *s, float eps)
{
    assert(s);
    size_t n = s->vertex_count ? s->vertex_count : 1, largest = 1;
    for (uint32_t o = 0; o < s->object_count; o++)
        largest = s->objects[o].vertex_count > largest ? s->objects[o].vertex_count : largest;
    gi_welded *w = calloc(1, sizeof *w);
    weld_state st = {w, {16, NULL, NULL}, NULL, eps > 0.0f ? eps * scene_size(s) : 0.0f};
    while (st.grid.capacity < 2 * largest)
        st.grid.capacity *= 2;
    if (w) {
        w->positions = malloc(n * 3 * sizeof(float));
        w->normals = malloc(n * 3 * sizeof(float));
        w->object = malloc(n * sizeof(uint32_t));
        w->remap = malloc(n * sizeof(uint32_t));
    }
    st.grid.keys = malloc(st.grid.capacity * sizeof *st.grid.keys);
    st.grid.head = malloc(st.grid.capacity * sizeof *st.grid.head);
    st.next = malloc(n * sizeof *st.next);
    int ok = w && w->positions && w->normals && w->object && w->remap && st.grid.keys &&
             st.grid.head && st.next;
    for (uint32_t o = 0; ok && o < s->object_count; o++)
        weld_object(&st, s, o);
    free(st.grid.keys);
    free(st.grid.head);
    free(st.next);
    if (ok) {
        finish_normals(w, s);
        ok = build_adjacency(w, s);
    }
    if (!ok) {
        gi_welded_free(w);
        return NULL;
    }
    return w;
}

void gi_welded_free(gi_welded *w)
{
    if (!w)
        return;
    free(w->positions);
    free(w->normals);
    free(w->object);
    free(w->remap);
    free(w->tri_offsets);
    free(w->tri_list);
    free(w->areas);
    free(w);
}
