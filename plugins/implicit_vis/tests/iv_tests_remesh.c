/* The implicit_vis tests of the re-meshing (Sec. 5.1; README "Tests"):
 * CGAL's isotropic re-meshing (gi/algo/remesh.h) with every new vertex on
 * its embedding, the edge-length spread before and after, and the
 * hierarchy and display grid of the re-meshed Cornell boxes. */
#include "iv_tests.h"

#include "gi/algo/remesh.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The surface the elements span: triangles, elements, edge length mean
 * and spread (coefficient of variation). */
static void edge_line(const char *what, const iv_hier *h, const gi_scene *s, double *mean,
                      double *cv)
{
    iv_hier_edge_stats(h, s, mean, cv);
    printf("%-34s %7u triangles, %6u elements, edge mean %.4f, spread (sd / mean) %.3f\n", what,
           h->surf_count, h->elem_count, *mean, *cv);
}

/* 1. gi_remesh_isotropic on the 792-vertex teapot alone: every new
 * vertex lies where its embedding (original triangle, barycentric
 * weights) puts it; bad input is refused with a message */
static void remesh_teapot_alone(const gi_scene *s)
{
    gi_error err;
    uint32_t obj = s->vertices[s->indices[0]].object;
    const gi_object *o = &s->objects[obj];
    float *p = malloc((size_t)o->vertex_count * 3 * sizeof(float));
    uint32_t *ix = malloc((size_t)o->triangle_count * 3 * sizeof(uint32_t));
    for (uint32_t v = 0; v < o->vertex_count; v++)
        memcpy(&p[3 * v], s->vertices[o->first_vertex + v].position, 3 * sizeof(float));
    for (uint32_t t = 0; t < 3 * o->triangle_count; t++)
        ix[t] = s->indices[3 * (size_t)o->first_triangle + t] - o->first_vertex;
    float mn[3] = {1e30f, 1e30f, 1e30f}, mx[3] = {-1e30f, -1e30f, -1e30f};
    for (uint32_t v = 0; v < 3 * o->vertex_count; v++) {
        mn[v % 3] = fminf(mn[v % 3], p[v]);
        mx[v % 3] = fmaxf(mx[v % 3], p[v]);
    }
    float ext = fmaxf(mx[0] - mn[0], fmaxf(mx[1] - mn[1], mx[2] - mn[2]));
    gi_remeshed *r =
        gi_remesh_isotropic(p, o->vertex_count, ix, o->triangle_count, 0.02f * ext, 3, &err);
    EXPECT(r != NULL, "teapot: %s", err.text);
    if (r) {
        int bad = 0;
        for (uint32_t v = 0; v < r->vertex_count; v++) {
            const float *w = &r->bary[3 * v];
            const uint32_t *c = &ix[3 * r->face[v]];
            bad += !(w[0] >= 0.0f && w[1] >= 0.0f && w[2] >= 0.0f &&
                     fabsf(w[0] + w[1] + w[2] - 1.0f) < 1e-4f);
            double d2 = 0.0;
            for (int k = 0; k < 3; k++) {
                double q = w[0] * p[3 * c[0] + k] + w[1] * p[3 * c[1] + k] + w[2] * p[3 * c[2] + k];
                d2 += (q - r->positions[3 * v + k]) * (q - r->positions[3 * v + k]);
            }
            bad += sqrt(d2) > 1e-4 * ext;
        }
        printf("teapot alone: %u triangles -> %u (edge 0.02 x its size), %u vertices, %d off their "
               "embedding\n",
               o->triangle_count, r->triangle_count, r->vertex_count, bad);
        EXPECT(bad == 0, "teapot: %d re-meshed vertices off their embedding", bad);
        EXPECT(r->triangle_count > 4 * o->triangle_count,
               "teapot: only %u triangles after re-meshing", r->triangle_count);
        gi_remeshed_free(r);
    }
    ix[5] = o->vertex_count + 7;
    gi_error e2 = {{0}};
    EXPECT(gi_remesh_isotropic(p, o->vertex_count, ix, o->triangle_count, 0.02f * ext, 3, &e2) ==
                   NULL &&
               strstr(e2.text, "out of range"),
           "an index out of range is not refused: '%s'", e2.text);
    EXPECT(gi_remesh_isotropic(p, o->vertex_count, ix, o->triangle_count, 0.0f, 3, &e2) == NULL &&
               e2.text[0],
           "a zero target edge is not refused");
    free(p), free(ix);
}

/* 2. triangle count and edge-length spread before and after, the
 * teapot on its ground plane at edge 0.08: isotropic re-meshing evens
 * the edges out (spread below half the model's and below the grid's),
 * its mean edge near the target */
static void remesh_edge_spread(const gi_scene *s)
{
    gi_error err;
    double m0, c0, mg, cg, mi, ci;
    iv_hier *h0 = iv_hier_create(s, 0.0f, IV_REMESH_GRID, &err);
    iv_hier *hg = iv_hier_create(s, 0.08f, IV_REMESH_GRID, &err);
    iv_hier *hi = iv_hier_create(s, 0.08f, IV_REMESH_ISOTROPIC, &err);
    EXPECT(h0 && hg && hi, "teapot_plane: %s", err.text);
    if (h0 && hg && hi) {
        edge_line("teapot_plane as it is:", h0, s, &m0, &c0);
        edge_line("teapot_plane, grid, edge 0.08:", hg, s, &mg, &cg);
        edge_line("teapot_plane, isotropic, edge 0.08:", hi, s, &mi, &ci);
        EXPECT(hi->surf_count > 4 * h0->surf_count, "isotropic: %u triangles from %u",
               hi->surf_count, h0->surf_count);
        EXPECT(ci < 0.5 * c0 && ci < cg,
               "isotropic edge spread %.3f, the model's %.3f, the grid's %.3f", ci, c0, cg);
        EXPECT(mi > 0.6 * 0.08 && mi < 1.4 * 0.08, "isotropic mean edge %.4f, target 0.08", mi);
    }
    iv_hier_free(h0), iv_hier_free(hg), iv_hier_free(hi);
    /* an edge far too short is refused before CGAL runs, with a message */
    gi_error e3 = {{0}};
    iv_hier *tiny = iv_hier_create(s, 1e-5f, IV_REMESH_ISOTROPIC, &e3);
    EXPECT(tiny == NULL && strstr(e3.text, "raise it"), "edge 1e-5 is not refused: '%s'", e3.text);
    iv_hier_free(tiny);
}

/* The display grid of h (placed at t = 0): per grid point, weights that
 * are not non-negative summing to 1 (bad_w), and the grid point more
 * than tol off where its three elements' blend puts it (bad_p); worst:
 * the largest distance. */
static void check_display_grid(const iv_hier *h, const gi_scene *s, float tol, int *bad_w,
                               int *bad_p, float *worst)
{
    for (uint32_t t = 0; t < s->triangle_count; t++) {
        uint32_t kk = h->tri_k[t];
        gi_vec3 c3[3];
        gi_scene_triangle_world(s, t, 0.0f, c3);
        for (uint32_t j = 0; j <= kk; j++)
            for (uint32_t i = 0; i + j <= kk; i++) {
                uint32_t d = h->tri_grid[t] + iv_grid_index(kk, i, j);
                const float *w = &h->disp_w[3 * d];
                int bw = !(fabsf(w[0] + w[1] + w[2] - 1.0f) < 1e-4f && w[0] >= 0.0f &&
                           w[1] >= 0.0f && w[2] >= 0.0f);
                *bad_w += bw;
                float b1 = (float)i / (float)kk, b2 = (float)j / (float)kk;
                gi_vec3 want = gi_v3_add(gi_v3_scale(c3[0], 1.0f - b1 - b2),
                                         gi_v3_add(gi_v3_scale(c3[1], b1), gi_v3_scale(c3[2], b2)));
                gi_vec3 got = gi_v3(0, 0, 0);
                for (int q = 0; q < 3; q++)
                    got = gi_v3_add(
                        got,
                        gi_v3_scale(gi_v3_load(&h->pos[3 * h->elem_node[h->disp_elem[3 * d + q]]]),
                                    w[q]));
                float off = gi_v3_length(gi_v3_sub(got, want));
                *worst = fmaxf(*worst, off);
                *bad_p += off > tol;
            }
    }
}

/* 3. the hierarchy of a re-meshed Cornell box (k: 0 still, 1 moving, 2
 * deforming: the embedding carries rigid motion and morph targets), and
 * the display grid: weights summing to 1, each grid point where its
 * three elements' blend puts it (flat walls: exactly) */
static void remesh_cornell(const char *path, int k)
{
    gi_error err;
    gi_scene *s = iv_test_load(path);
    if (!s)
        return;
    iv_hier *h = iv_hier_create(s, 0.3f, IV_REMESH_ISOTROPIC, &err);
    EXPECT(h != NULL, "%s: %s", path, err.text);
    if (h) {
        double m, c;
        edge_line(strrchr(path, '/') + 1, h, s, &m, &c);
        float ts[2] = {0.0f, s->animation_length > 0.0f ? 0.6f * s->animation_length : 0.0f};
        for (int i = 0; i < 2; i++) {
            iv_hier_update(h, s, ts[i]);
            char what[600];
            snprintf(what, sizeof what, "%s isotropic t=%.2f", strrchr(path, '/') + 1, ts[i]);
            iv_test_check_hierarchy(h, s, ts[i], what,
                                    1e-2); /* chords of curved parts: about e^2 / 8R */
        }
        int bad_w = 0, bad_p = 0;
        /* flat walls and blocks: exactly; the bunny of cornell_moving,
         * re-meshed far coarser than its own triangles: within half an
         * edge (a chord's sagitta) */
        float worst = 0.0f, tol = k == 1 ? 0.5f * 0.3f : 1e-3f;
        iv_hier_update(h, s, 0.0f);
        check_display_grid(h, s, tol, &bad_w, &bad_p, &worst);
        printf("%s: display grid points at most %.3g off their place\n", strrchr(path, '/') + 1,
               (double)worst);
        EXPECT(bad_w == 0 && bad_p == 0,
               "%s: display grid: %d bad weights, %d points off their place by more than %g", path,
               bad_w, bad_p, (double)tol);
    }
    iv_hier_free(h);
    gi_scene_free(s);
}

void iv_test_remesh(void)
{
    gi_scene *s = iv_test_load(GI_SOURCE_DIR "/scenes/teapot_plane.glb");
    if (!s)
        return;
    remesh_teapot_alone(s);
    remesh_edge_spread(s);
    gi_scene_free(s);
    const char *scenes[] = {GI_SOURCE_DIR "/scenes/cornell_box.gltf",
                            GI_SOURCE_DIR "/scenes/cornell_moving.gltf",
                            GI_SOURCE_DIR "/scenes/cornell_deform.gltf"};
    for (int k = 0; k < 3; k++)
        remesh_cornell(scenes[k], k);
}
