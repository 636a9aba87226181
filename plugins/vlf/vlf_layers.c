/* Layers of a direction's face order for the portable raster path
 * (propagate = raster, raster_sync = barrier; plugins/vlf/README.md
 * "Propagation by the rasteriser"). The paper (§3.2, §3.3) draws the
 * depth-ordered faces one after another into the radiance interface, each
 * reading what the faces before it left there. GL 4.5 core lets a fragment
 * read a texture it renders into only when each texel is read and written
 * at most once between two glTextureBarrier calls (GL 4.5 §9.3.1). So the
 * order is cut into layers in which no two entries cover the same pixel:
 * an entry's layer is 1 + the highest layer of the earlier entries it
 * overlaps, found on a coarse grid of the projection (the entries'
 * bounding boxes, a pixel wider: conservative). Entries of one face that
 * follow each other in the order (a polygon's fan, the pieces of a split
 * triangle, the triangles of a planar face) do not overlap one another
 * and share a layer. Drawing the layers in turn, a barrier between, each
 * pixel meets its faces in the depth order; the sweep along -w draws the
 * layers in reverse. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "vlf_gpu.h"

enum { GRID_MAX = 64 };

/* Entry e's corner c in VLF coordinates and its face (bit 31: the twin's
 * side), as shaders/vlf_raster.vert reads them. */
static gi_vec3 corner(const vlf_field *f, const vlf_psf *p, uint32_t e, uint32_t c)
{
    uint32_t idx = e & 0x3fffffffu;
    if (e & 0x40000000u) {
        gi_vec3 q;
        memcpy(&q, p->rextra + 12 * (size_t)idx + 4 * c, sizeof q);
        return q;
    }
    return f->sort_p[3 * (size_t)idx + c];
}

static uint32_t face_key(const vlf_field *f, const vlf_psf *p, uint32_t e)
{
    uint32_t idx = e & 0x3fffffffu;
    uint32_t face = (e & 0x40000000u) ? p->rextra[12 * (size_t)idx + 3] : f->sort_face[idx];
    return face | (e & 0x80000000u);
}

/* The grid cells entry e may cover: x0, y0, x1, y1 inclusive (G cells a
 * side over the tile of NS pixels; the box a pixel wider all round, so
 * that the rasteriser's rounding stays inside). */
static void cells(const vlf_field *f, const vlf_psf *p, uint32_t e, uint32_t NS, uint32_t G,
                  int box[4])
{
    float lo[2] = {1e30f, 1e30f}, hi[2] = {-1e30f, -1e30f};
    for (uint32_t c = 0; c < 3; c++) {
        gi_vec3 q = corner(f, p, e, c);
        float a[2] = {q.x * p->u.x + q.y * p->u.y + q.z * p->u.z,
                      q.x * p->v.x + q.y * p->v.y + q.z * p->v.z};
        for (int k = 0; k < 2; k++) {
            lo[k] = a[k] < lo[k] ? a[k] : lo[k];
            hi[k] = a[k] > hi[k] ? a[k] : hi[k];
        }
    }
    for (int k = 0; k < 2; k++) {
        /* pixels as the vertex shader maps the tile: (a + 1) / 2 * NS */
        float p0 = floorf((lo[k] + 1.0f) * 0.5f * (float)NS) - 1.0f;
        float p1 = floorf((hi[k] + 1.0f) * 0.5f * (float)NS) + 1.0f;
        int c0 = (int)(p0 < 0.0f ? 0.0f : p0) * (int)G / (int)NS;
        int c1 = (int)(p1 > (float)(NS - 1) ? (float)(NS - 1) : p1) * (int)G / (int)NS;
        box[k] = c0 < 0 ? 0 : c0;
        box[k + 2] = c1 > (int)G - 1 ? (int)G - 1 : c1;
    }
}

/* The highest layer + 1 stored under the box (0: none), or with set the
 * box filled with v. */
static uint32_t grid_max(uint32_t *grid, uint32_t G, const int box[4], int set, uint32_t v)
{
    uint32_t m = 0;
    for (int y = box[1]; y <= box[3]; y++)
        for (int x = box[0]; x <= box[2]; x++) {
            uint32_t *g = grid + (size_t)y * G + (size_t)x;
            if (set)
                *g = v;
            else
                m = *g > m ? *g : m;
        }
    return m;
}

/* One direction: each entry's layer into lay[], the count returned. */
static uint32_t layer_direction(const vlf_field *f, const vlf_psf *p, uint32_t NS, uint32_t G,
                                uint32_t *grid, uint32_t *lay)
{
    memset(grid, 0, (size_t)G * G * sizeof *grid);
    uint32_t n = p->rorder_count, layers = 0;
    for (uint32_t a = 0; a < n;) {
        uint32_t key = face_key(f, p, p->rorder[a]), b = a + 1;
        while (b < n && face_key(f, p, p->rorder[b]) == key)
            b++;
        uint32_t m = 0;
        int box[4];
        for (uint32_t k = a; k < b; k++) {
            cells(f, p, p->rorder[k], NS, G, box);
            uint32_t q = grid_max(grid, G, box, 0, 0);
            m = q > m ? q : m;
        }
        for (uint32_t k = a; k < b; k++) {
            cells(f, p, p->rorder[k], NS, G, box);
            grid_max(grid, G, box, 1, m + 1);
            lay[k] = m;
        }
        layers = m + 1 > layers ? m + 1 : layers;
        a = b;
    }
    return layers;
}

gi_result vlf_raster_layers(vlf_raster *r, const vlf_field *f, uint32_t *order, gi_error *err)
{
    uint32_t l = f->prm.l, NS = f->prm.N * f->prm.S;
    uint32_t G = NS < GRID_MAX ? NS : GRID_MAX, maxn = 1;
    for (uint32_t i = 0; i < l; i++)
        maxn = f->psf[i].rorder_count > maxn ? f->psf[i].rorder_count : maxn;
    uint32_t *grid = malloc((size_t)G * G * sizeof *grid);
    uint32_t *lay = malloc((size_t)maxn * sizeof *lay);
    uint32_t *cnt = calloc((size_t)maxn + 1, sizeof *cnt);
    free(r->layer_first), free(r->layer_start);
    r->layer_first = calloc((size_t)l + 1, sizeof *r->layer_first);
    size_t cap = (size_t)l * 4 + 16, used = 0;
    r->layer_start = malloc(cap * sizeof *r->layer_start);
    int ok = grid && lay && cnt && r->layer_first && r->layer_start;
    r->max_layers = 0;
    r->layer_total = 0;
    for (uint32_t i = 0; ok && i < l; i++) {
        const vlf_psf *p = &f->psf[i];
        uint32_t L = p->rorder_count ? layer_direction(f, p, NS, G, grid, lay) : 0;
        if (used + L + 1 > cap) {
            size_t nc = (used + L + 1) * 2;
            uint32_t *ns = realloc(r->layer_start, nc * sizeof *ns);
            if (!ns) {
                ok = 0;
                break;
            }
            r->layer_start = ns, cap = nc;
        }
        /* a stable counting sort of the entries by layer */
        memset(cnt, 0, ((size_t)L + 1) * sizeof *cnt);
        for (uint32_t k = 0; k < p->rorder_count; k++)
            cnt[lay[k] + 1]++;
        for (uint32_t k = 0; k < L; k++)
            cnt[k + 1] += cnt[k];
        r->layer_first[i] = (uint32_t)used;
        memcpy(r->layer_start + used, cnt, ((size_t)L + 1) * sizeof *cnt);
        used += L + 1;
        uint32_t *out = order + r->order_first[i];
        for (uint32_t k = 0; k < p->rorder_count; k++)
            out[cnt[lay[k]]++] = p->rorder[k];
        r->max_layers = L > r->max_layers ? L : r->max_layers;
        r->layer_total += L;
    }
    r->layer_first[l] = (uint32_t)used;
    free(grid), free(lay), free(cnt);
    if (!ok)
        return gi_error_set(err, GI_ERR_OUT_OF_MEMORY,
                            "vlf: out of memory layering the raster propagation");
    return GI_OK;
}
