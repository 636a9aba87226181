/* avg_tests voxel and deform: the GPU voxelisation of the AVG (Bashford-
 * Rogers et al. 2011 §III-A; all three voxelisers) against a CPU
 * triangle-box overlap voxelisation of the same scene at the same time:
 * every overlapped voxel filled, false positives and per-voxel triangle
 * counts reported; the single-pass voxeliser also against the per-slice
 * conservative one. deform: the grid follows morph targets. */
#include "avg_tests.h"
#include "shaders/avg_bindings.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* EXPECT(cond, fmt, ...): CHECK_MSG of the unit tests' check.h, which
 * counts failures in gi_test_failed (this file's). */
#include "check.h"
#define EXPECT CHECK_MSG

/* ---- voxel: CPU triangle-box overlap by clipping ---- */

/* Does triangle p (grid space) meet the box [lo, hi]? Clips the triangle
 * against the box's six planes (Sutherland-Hodgman); anything left means
 * overlap. Independent of the GPU's separating-axis test. */
static int tri_box_clip(const gi_vec3 p[3], gi_vec3 lo, gi_vec3 hi)
{
    gi_vec3 a[16], b[16];
    int n = 3;
    for (int i = 0; i < 3; i++)
        a[i] = p[i];
    for (int plane = 0; plane < 6 && n > 0; plane++) {
        int axis = plane / 2;
        float s = plane % 2 ? -1.0f : 1.0f; /* keep s * x <= s * c */
        float c = plane % 2 ? (&lo.x)[axis] : (&hi.x)[axis];
        int m = 0;
        for (int i = 0; i < n; i++) {
            gi_vec3 u = a[i], w = a[(i + 1) % n];
            float du = s * ((&u.x)[axis] - c), dw = s * ((&w.x)[axis] - c);
            if (du <= 0.0f)
                b[m++] = u;
            if ((du < 0.0f && dw > 0.0f) || (du > 0.0f && dw < 0.0f)) {
                float t = du / (du - dw);
                b[m++] = gi_v3_add(u, gi_v3_scale(gi_v3_sub(w, u), t));
            }
        }
        n = m;
        memcpy(a, b, sizeof(gi_vec3) * (size_t)n);
    }
    return n > 0;
}

/* CPU counts of triangles overlapping each voxel, boxes grown by `grow`;
 * with `colour`, also the sum of the overlapping triangles' material
 * albedos (the test scenes have no textures). */
static uint32_t *cpu_voxelise(const gi_scene *s, float t, const avg_grid *g, float grow,
                              float *colour)
{
    uint32_t n = g->n;
    uint32_t *count = calloc((size_t)n * n * n, sizeof *count);
    for (uint32_t tri = 0; tri < s->triangle_count; tri++) {
        gi_vec3 w[3], p[3];
        gi_scene_triangle_world(s, tri, t, w);
        gi_vec3 lo = gi_v3(FLT_MAX, FLT_MAX, FLT_MAX), hi = gi_v3(-FLT_MAX, -FLT_MAX, -FLT_MAX);
        for (int i = 0; i < 3; i++) {
            p[i] = gi_v3_scale(gi_v3_sub(w[i], gi_v3_load(g->origin)), 1.0f / g->h);
            lo = gi_v3(fminf(lo.x, p[i].x), fminf(lo.y, p[i].y), fminf(lo.z, p[i].z));
            hi = gi_v3(fmaxf(hi.x, p[i].x), fmaxf(hi.y, p[i].y), fmaxf(hi.z, p[i].z));
        }
        gi_vec3 e1 = gi_v3_sub(p[1], p[0]), e2 = gi_v3_sub(p[2], p[0]);
        if (gi_v3_length(gi_v3_cross(e1, e2)) == 0.0f)
            continue; /* degenerate: the rasteriser draws nothing either */
        int i0[3], i1[3];
        for (int a = 0; a < 3; a++) {
            i0[a] = (int)floorf((&lo.x)[a] - grow) - 1;
            i1[a] = (int)floorf((&hi.x)[a] + grow) + 1;
            i0[a] = i0[a] < 0 ? 0 : i0[a];
            i1[a] = i1[a] > (int)n - 1 ? (int)n - 1 : i1[a];
        }
        for (int z = i0[2]; z <= i1[2]; z++)
            for (int y = i0[1]; y <= i1[1]; y++)
                for (int x = i0[0]; x <= i1[0]; x++) {
                    gi_vec3 blo = gi_v3((float)x - grow, (float)y - grow, (float)z - grow);
                    gi_vec3 bhi =
                        gi_v3((float)x + 1 + grow, (float)y + 1 + grow, (float)z + 1 + grow);
                    if (tri_box_clip(p, blo, bhi)) {
                        size_t v = ((size_t)z * n + y) * n + x;
                        count[v]++;
                        if (colour)
                            for (int c = 0; c < 3; c++)
                                colour[3 * v + c] +=
                                    s->materials[s->vertices[s->indices[3 * tri]].material]
                                        .albedo[c];
                    }
                }
    }
    return count;
}

static const char *mode_names[] = {"conservative", "paper", "single"};

/* The CPU voxelisations of one time: triangle counts with the boxes shrunk
 * (inner), exact (with the colour sums) and grown (outer) by 1e-3 voxel
 * edges. */
typedef struct cpu_grids {
    uint32_t *inner, *exact, *outer;
    float *colour;
    size_t total;  /* voxels */
    size_t filled; /* of them, filled by the exact voxelisation */
} cpu_grids;

/* One voxeliser's grid (nrm: summed normals, col: summed colours, the
 * count in w) against the CPU voxelisations: printed, and held to what
 * that voxeliser promises. */
static void check_voxeliser(const char *scene_path, float t, uint32_t n, int mode, const float *nrm,
                            const float *col, const cpu_grids *cg)
{
    const uint32_t *inner = cg->inner, *exact = cg->exact, *outer = cg->outer;
    const float *colour = cg->colour;
    size_t total = cg->total, filled_cpu = cg->filled;
    size_t misses = 0, fp = 0, filled = 0, count_equal = 0, colour_bad = 0, ambiguous = 0;
    for (size_t i = 0; i < total; i++) {
        float c = nrm[4 * i + 3];
        filled += c > 0.0f;
        misses += inner[i] > 0 && c == 0.0f;
        fp += outer[i] == 0 && c > 0.0f;
        /* The count equals the CPU's; a triangle that only touches the
         * voxel within 1e-3 voxel edges of its faces may count either way. */
        count_equal += (uint32_t)c >= inner[i] && (uint32_t)c <= outer[i];
        ambiguous += inner[i] != outer[i];
        if (c > 0.0f && fabsf(col[4 * i + 3] - c) > 0.0f)
            colour_bad++;
        /* Where the overlap is unambiguous, the colour sums agree too. */
        if (mode != AVG_VOX_PAPER && inner[i] == outer[i] && (uint32_t)c == exact[i])
            for (int k = 0; k < 3; k++)
                if (fabsf(col[4 * i + k] - colour[3 * i + k]) > 1e-4f * (1.0f + c))
                    colour_bad++;
    }
    printf("voxel %s t=%.2f n=%u %-12s: %zu filled (CPU %zu), %zu missed, %zu false "
           "positives (%.3f %%), "
           "triangle count different from the CPU's in %zu of %zu voxels (%zu voxels with "
           "a triangle within "
           "1e-3 of a face, counted either way)\n",
           strrchr(scene_path, '/') + 1, t, n, mode_names[mode], filled, filled_cpu, misses, fp,
           100.0 * (double)fp / (double)(filled ? filled : 1), total - count_equal, total,
           ambiguous);
    EXPECT(colour_bad == 0, "%zu voxels with different counts or colour sums", colour_bad);
    if (mode != AVG_VOX_PAPER) {
        EXPECT(misses == 0, "%s voxeliser missed %zu overlapped voxels", mode_names[mode], misses);
        EXPECT(fp == 0, "%s voxeliser filled %zu voxels no triangle overlaps", mode_names[mode],
               fp);
        EXPECT(count_equal == total, "triangle counts differ in %zu voxels", total - count_equal);
    }
    if (mode == AVG_VOX_PAPER) {
        /* The paper's voxeliser is not conservative at partly covered
         * voxels; it must still fill most of the surface voxels. */
        EXPECT(misses * 10 < filled_cpu, "paper voxeliser missed %zu of %zu voxels", misses,
               filled_cpu);
    }
}

/* The single pass against the per-slice conservative pass:
 * the same count in every voxel, the sums within the fixed
 * point's rounding (count / (2 AVG_VOX_FIXED) per component)
 * plus float summation error. */
static void check_single_against_slices(const char *scene_path, float t, uint32_t n, size_t total,
                                        const float *nrm, const float *col, const float *slices_nrm,
                                        const float *slices_col)
{
    size_t count_diff = 0, sum_bad = 0;
    double worst = 0.0;
    for (size_t i = 0; i < total; i++) {
        float c = slices_nrm[4 * i + 3];
        count_diff += nrm[4 * i + 3] != c;
        double bound = c / (2.0 * AVG_VOX_FIXED) + 1e-6 * (1.0 + c);
        for (int k = 0; k < 3; k++) {
            double dn = fabs(nrm[4 * i + k] - slices_nrm[4 * i + k]);
            double dc = fabs(col[4 * i + k] - slices_col[4 * i + k]);
            worst = fmax(worst, fmax(dn, dc));
            sum_bad += dn > bound || dc > bound;
        }
    }
    printf("voxel %s t=%.2f n=%u single vs conservative: counts differ in %zu of %zu "
           "voxels, largest sum "
           "difference %.3g (bound per voxel count / %.0f)\n",
           strrchr(scene_path, '/') + 1, t, n, count_diff, total, worst, 2.0 * AVG_VOX_FIXED);
    EXPECT(count_diff == 0, "single-pass counts differ from the per-slice ones in %zu voxels",
           count_diff);
    EXPECT(sum_bad == 0, "%zu sums beyond the fixed-point bound", sum_bad);
}

/* The GPU grid at each time of `ts` in turn (one scene upload and one grid,
 * as frames of an animation: moved and morphed vertices come from
 * gi_gpu_scene_set_time) against the CPU voxelisation of the scene at that
 * time (gi_scene_triangle_world: transforms and morph targets applied). */
static void voxel_case(gi_gpu *gpu, const char *scene_path, const float *ts, int nt, uint32_t n)
{
    gi_error err;
    avg_test_fixture fx;
    if (!avg_test_load_fixture(gpu, scene_path, &fx))
        return;
    const gi_scene *s = fx.s;
    gi_gpu_scene *gs = fx.gs;
    avg_grid *g = avg_grid_create(n, &err);
    if (!g) {
        EXPECT(0, "%s", err.text);
        return;
    }
    for (int ti = 0; ti < nt; ti++) {
        float t = ts[ti];
        gi_gpu_scene_set_time(gs, t);
        avg_grid_place(g, gs->bounds);
        cpu_grids cg;
        cg.colour = calloc((size_t)n * n * n * 3, sizeof *cg.colour);
        cg.inner = cpu_voxelise(s, t, g, -1e-3f, NULL);
        cg.exact = cpu_voxelise(s, t, g, 0.0f, cg.colour);
        cg.outer = cpu_voxelise(s, t, g, 1e-3f, NULL);
        cg.total = (size_t)n * n * n;
        cg.filled = 0;
        for (size_t i = 0; i < cg.total; i++)
            cg.filled += cg.exact[i] > 0;
        float *slices_nrm = NULL, *slices_col = NULL;
        for (int mode = 0; mode < 3; mode++) {
            EXPECT(avg_grid_voxelise(g, gs, (avg_vox_mode)mode, &err) == GI_OK, "%s", err.text);
            float *nrm = avg_grid_read(g, 0), *col = avg_grid_read(g, 1);
            check_voxeliser(scene_path, t, n, mode, nrm, col, &cg);
            if (mode == AVG_VOX_SINGLE && slices_nrm)
                check_single_against_slices(scene_path, t, n, cg.total, nrm, col, slices_nrm,
                                            slices_col);
            if (mode == AVG_VOX_CONSERVATIVE) {
                slices_nrm = nrm;
                slices_col = col;
            } else {
                free(nrm);
                free(col);
            }
        }
        free(slices_nrm);
        free(slices_col);
        free(cg.inner);
        free(cg.exact);
        free(cg.outer);
        free(cg.colour);
    }
    avg_grid_free(g);
    avg_test_free_fixture(&fx);
}

int avg_test_voxel(gi_gpu *gpu)
{
    voxel_case(gpu, GI_SOURCE_DIR "/scenes/cornell_box.gltf", (const float[]){0.0f}, 1, 32);
    voxel_case(gpu, GI_SOURCE_DIR "/scenes/cornell_moving.gltf", (const float[]){1.3f}, 1, 40);
    return gi_test_failed;
}

/* ---- deform: the grid follows morph targets ---- */

/* The short block morphing: rest, stretched, stretched and bulged, half
 * way back, bulged only; then the rest pose again. */
static void deform_case(gi_gpu *gpu)
{
    static const float ts[] = {0.0f, 1.0f, 2.0f, 2.5f, 3.0f, 0.0f};
    voxel_case(gpu, GI_SOURCE_DIR "/scenes/cornell_deform.gltf", ts,
               (int)(sizeof ts / sizeof ts[0]), 32);
    /* The poses differ in the grid (else the comparison above says nothing):
     * the CPU voxelisations at t = 0 and t = 2 differ in many voxels. */
    gi_error err;
    gi_scene *s = gi_scene_load(GI_SOURCE_DIR "/scenes/cornell_deform.gltf", &err);
    avg_grid *g = avg_grid_create(32, &err);
    if (!s || !g) {
        EXPECT(0, "%s", err.text);
        return;
    }
    avg_grid_place(g, s->bounds);
    uint32_t *a = cpu_voxelise(s, 0.0f, g, 0.0f, NULL), *b = cpu_voxelise(s, 2.0f, g, 0.0f, NULL);
    size_t differ = 0;
    for (size_t i = 0; i < (size_t)32 * 32 * 32; i++)
        differ += (a[i] > 0) != (b[i] > 0);
    printf("deform: %zu voxels filled at one pose and empty at the other (t = 0, 2)\n", differ);
    EXPECT(differ > 100, "only %zu voxels differ between the poses", differ);
    free(a);
    free(b);
    avg_grid_free(g);
    gi_scene_free(s);
}

int avg_test_deform(gi_gpu *gpu)
{
    deform_case(gpu);
    return gi_test_failed;
}
