/* The avg method's debug buffers (plugin ABI 1.3, issue 33): the two data
 * structures Approximate Visibility Grids (Bashford-Rogers et al. 2011)
 * rest on, seen from the camera.
 *
 *   vpls    the virtual point lights of the last frame (§III-B: light paths
 *           traced through the grid, a VPL at each hit), each splatted as
 *           one pixel at its projection, adding its flux (RGB, watts); not
 *           occluded by the scene, so a VPL behind a wall shows too.
 *   voxels  the approximate visibility grid (§III-A): per pixel, the mean
 *           albedo of the first occupied voxel the camera ray meets, black
 *           where the ray leaves the grid through empty voxels; shows what
 *           the tracer's rays hit instead of the triangles.
 *
 * Both are computed on the CPU from what render() keeps: the compacted VPLs
 * (avg.cpu_vpls) and the grid's colour texture read back. */
#include "avg.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

const gi_debug_buffer_desc avg_debug_buffers[] = {
    {"vpls", "the frame's VPLs, each one pixel at its projection adding its flux (W), unoccluded",
     GI_DEBUG_SCREEN},
    {"voxels", "mean albedo of the first occupied grid voxel along the camera ray (Sec. III-A)",
     GI_DEBUG_SCREEN},
    {NULL, NULL, 0},
};

/* Column-major m times (x, y, z, 1). */
static void transform(const float m[16], const float p[3], float out[4])
{
    for (int i = 0; i < 4; i++)
        out[i] = m[i] * p[0] + m[4 + i] * p[1] + m[8 + i] * p[2] + m[12 + i];
}

static void splat_vpls(const avg *a, const gi_view *v, gi_image *img)
{
    for (uint32_t i = 0; i < a->vpl_count; i++) {
        const avg_vpl *l = &a->cpu_vpls[i];
        float c[4];
        transform(v->view_proj, l->position, c);
        if (c[3] <= 0)
            continue;
        float x = (c[0] / c[3] * 0.5f + 0.5f) * (float)v->width;
        float y = (0.5f - c[1] / c[3] * 0.5f) * (float)v->height; /* row 0 at the top */
        if (!(x >= 0 && y >= 0 && x < (float)v->width && y < (float)v->height))
            continue;
        float *px = img->rgba + 4 * ((size_t)y * v->width + (size_t)x);
        for (int k = 0; k < 3; k++)
            px[k] += l->power[k];
    }
}

/* The camera ray through the centre of pixel (x, y), row 0 at the top. */
static void pixel_ray(const gi_view *v, uint32_t x, uint32_t y, float o[3], float d[3])
{
    float ndc[3] = {((float)x + 0.5f) / (float)v->width * 2 - 1,
                    1 - ((float)y + 0.5f) / (float)v->height * 2, 1};
    float far[4];
    transform(v->inv_view_proj, ndc, far);
    float len = 0;
    o[0] = v->eye.x, o[1] = v->eye.y, o[2] = v->eye.z;
    for (int k = 0; k < 3; k++) {
        d[k] = far[k] / far[3] - o[k];
        len += d[k] * d[k];
    }
    for (int k = 0; k < 3; k++)
        d[k] /= sqrtf(len);
}

/* Marches the ray in steps of a quarter voxel through the grid's cube and
 * returns the first occupied voxel's (x fastest) index, or -1. */
static long first_voxel(const avg_grid *g, const float *grid, const float o[3], const float d[3])
{
    float t0 = 0, t1 = INFINITY, size = g->h * (float)g->n;
    for (int k = 0; k < 3; k++) {
        float lo = g->origin[k], hi = lo + size;
        if (fabsf(d[k]) < 1e-12f) {
            if (o[k] < lo || o[k] > hi)
                return -1;
            continue;
        }
        float ta = (lo - o[k]) / d[k], tb = (hi - o[k]) / d[k];
        t0 = fmaxf(t0, fminf(ta, tb));
        t1 = fminf(t1, fmaxf(ta, tb));
    }
    for (float t = t0; t <= t1; t += 0.25f * g->h) {
        long idx = 0, stride = 1;
        for (int k = 0; k < 3; k++) {
            long c = (long)floorf((o[k] + t * d[k] - g->origin[k]) / g->h);
            if (c < 0 || c >= (long)g->n)
                goto next;
            idx += c * stride;
            stride *= (long)g->n;
        }
        if (grid[4 * idx + 3] > 0)
            return idx;
    next:;
    }
    return -1;
}

static gi_result view_voxels(avg *a, const gi_view *v, gi_image *img)
{
    float *grid = avg_grid_read(a->grid, 1);
    if (!grid)
        return gi_kit_fail(&a->kit, GI_ERR_OUT_OF_MEMORY, "avg: out of memory reading the grid");
    for (uint32_t y = 0; y < v->height; y++)
        for (uint32_t x = 0; x < v->width; x++) {
            float o[3], d[3];
            pixel_ray(v, x, y, o, d);
            long idx = first_voxel(a->grid, grid, o, d);
            float *px = img->rgba + 4 * ((size_t)y * v->width + x);
            for (int k = 0; k < 3 && idx >= 0; k++)
                px[k] = grid[4 * idx + k] / grid[4 * idx + 3];
        }
    free(grid);
    return GI_OK;
}

gi_result avg_debug_buffer(void *inst, const char *name, const gi_view *view, gi_image **out)
{
    avg *a = inst;
    *out = NULL;
    if (!a->grid || !a->kit.scene)
        return gi_kit_fail(&a->kit, GI_ERR_INVALID_ARGUMENT,
                           "avg: debug buffer '%s' needs a render() first", name);
    gi_image *img = gi_image_create(view->width, view->height);
    if (!img)
        return gi_kit_fail(&a->kit, GI_ERR_OUT_OF_MEMORY, "avg: out of memory for a debug buffer");
    gi_result r = GI_OK;
    if (!strcmp(name, "vpls"))
        splat_vpls(a, view, img);
    else
        r = view_voxels(a, view, img);
    if (r != GI_OK) {
        gi_image_free(img);
        return r;
    }
    *out = img;
    return GI_OK;
}
