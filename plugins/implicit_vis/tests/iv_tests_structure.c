/* The implicit_vis tests of the data structures (README "Tests"): the
 * cube-map bins (Sec. 4.2.2), the geometric hierarchy (Sec. 4.1, 4.2.1)
 * and the links, brute force and hierarchical, before and after
 * refinement (Sec. 4.2.2-4.2.4). */
#include "iv_tests.h"

#include "gi/mesh.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static uint64_t lcg(uint64_t *st)
{
    *st = *st * 6364136223846793005ull + 1442695040888963407ull;
    return *st >> 11;
}
static float urand(uint64_t *st)
{
    return (float)((double)lcg(st) / 9007199254740992.0);
}

/* ---------------------------------------------------------------- bins */

void iv_test_bins(void)
{
    for (uint32_t n = 1; n <= 16; n++) {
        double sum = 0.0;
        int bad = 0;
        for (uint32_t b = 0; b < 6 * n * n; b++) {
            sum += iv_bin_solid_angle(b, n);
            bad += iv_bin_of(iv_bin_centre(b, n), n) != b;
        }
        EXPECT(bad == 0, "n = %u: %d bin centres map to another bin", n, bad);
        CHECK_NEAR(sum, 4.0 * GI_PI, 1e-4);
    }
    uint64_t st = 1;
    int bad = 0;
    for (int i = 0; i < 100000; i++) {
        gi_vec3 d = gi_v3(urand(&st) * 2 - 1, urand(&st) * 2 - 1, urand(&st) * 2 - 1);
        if (gi_v3_length(d) < 1e-3f)
            continue;
        uint32_t n = 1 + (uint32_t)(urand(&st) * 16.0f);
        uint32_t b = iv_bin_of(d, n);
        /* the direction lies within the bin: closer to its centre than the
         * bin's angular diagonal */
        float half = 2.0f * sqrtf(iv_bin_solid_angle(b, n));
        bad += acosf(fminf(1.0f, gi_v3_dot(gi_v3_normalize(d), iv_bin_centre(b, n)))) > half;
        bad += iv_bin_of(gi_v3_scale(d, 3.5f), n) != b;
    }
    EXPECT(bad == 0, "%d random directions fall outside their bin", bad);
}

/* ----------------------------------------------------------- hierarchy */

/* Every element in exactly one leaf; each node's area and position from
 * its children's; the roots' area the scene's surface (within area_tol);
 * each leaf on its surface point placed at t. */
void iv_test_check_hierarchy(const iv_hier *h, const gi_scene *s, float t, const char *what,
                             double area_tol)
{
    uint32_t *seen = calloc(h->elem_count, sizeof *seen);
    int bad_area = 0, bad_pos = 0, bad_tree = 0;
    for (uint32_t i = 0; i < h->node_count; i++) {
        if (iv_is_leaf(h, i)) {
            bad_tree += h->node_elem[i] < 0;
            if (h->node_elem[i] >= 0)
                seen[h->node_elem[i]]++;
            continue;
        }
        double a = 0.0, p[3] = {0, 0, 0};
        for (uint32_t k = 0; k < h->child_count[i]; k++) {
            uint32_t c = h->first_child[i] + k;
            bad_tree += c <= i || h->parent[c] != (int32_t)i;
            a += h->area[c];
            for (int j = 0; j < 3; j++)
                p[j] += h->area[c] * h->pos[3 * c + j];
        }
        bad_area += fabs(a - h->area[i]) > 1e-4 * a + 1e-9;
        for (int j = 0; j < 3; j++)
            bad_pos += a > 0.0 &&
                       fabs(p[j] / a - h->pos[3 * i + j]) > 1e-4 * (1.0 + fabs(h->pos[3 * i + j]));
    }
    int bad_elem = 0;
    for (uint32_t e = 0; e < h->elem_count; e++)
        bad_elem += seen[e] != 1;
    free(seen);
    EXPECT(bad_tree == 0 && bad_elem == 0,
           "%s: %d bad links in the tree, %d elements not in exactly one leaf", what, bad_tree,
           bad_elem);
    EXPECT(bad_area == 0 && bad_pos == 0,
           "%s: %d nodes' areas and %d positions differ from their children's", what, bad_area,
           bad_pos);
    double roots = 0.0, tris = 0.0;
    for (uint32_t r = 0; r < h->root_count; r++)
        roots += h->area[r];
    float *ta = malloc((s->triangle_count + 1) * sizeof(float));
    gi_mesh_triangle_areas(s, t, ta);
    for (uint32_t i = 0; i < s->triangle_count; i++)
        tris += ta[i];
    free(ta);
    EXPECT(fabs(roots - tris) <= area_tol * tris, "%s: roots' area %.6g, scene surface %.6g", what,
           roots, tris);
    /* leaves sit on their model vertex, placed at t */
    int bad_leaf = 0;
    for (uint32_t e = 0; e < h->elem_count; e++) {
        uint32_t si = h->elem_rep[e], tr = h->samp_tri[si];
        gi_vec3 c[3];
        gi_scene_triangle_world(s, tr, t, c);
        float b1 = h->samp_b[2 * si], b2 = h->samp_b[2 * si + 1];
        gi_vec3 p = gi_v3_add(gi_v3_scale(c[0], 1.0f - b1 - b2),
                              gi_v3_add(gi_v3_scale(c[1], b1), gi_v3_scale(c[2], b2)));
        bad_leaf += gi_v3_length(gi_v3_sub(p, gi_v3_load(&h->pos[3 * h->elem_node[e]]))) > 1e-4f;
    }
    EXPECT(bad_leaf == 0, "%s: %d leaves off their vertex", what, bad_leaf);
    printf("%s: %u elements, %u nodes, %u segments, depth %u\n", what, h->elem_count, h->node_count,
           h->root_count, h->depth);
}

void iv_test_hierarchy(void)
{
    const char *scenes[] = {GI_SOURCE_DIR "/scenes/cornell_box.gltf",
                            GI_SOURCE_DIR "/scenes/cornell_moving.gltf",
                            GI_SOURCE_DIR "/scenes/cornell_deform.gltf"};
    for (int k = 0; k < 3; k++) {
        gi_scene *s = iv_test_load(scenes[k]);
        if (!s)
            continue;
        gi_error err;
        iv_hier *h = iv_hier_create(s, 0.0f, IV_REMESH_GRID, &err);
        EXPECT(h != NULL, "%s: %s", scenes[k], err.text);
        if (h) {
            float ts[2] = {0.0f, s->animation_length > 0.0f ? 0.6f * s->animation_length : 0.0f};
            for (int i = 0; i < 2; i++) {
                iv_hier_update(h, s, ts[i]);
                char what[600];
                snprintf(what, sizeof what, "%s t=%.2f", strrchr(scenes[k], '/') + 1, ts[i]);
                iv_test_check_hierarchy(h, s, ts[i], what, 1e-4);
            }
        }
        iv_hier_free(h);
        gi_scene_free(s);
    }
}

/* --------------------------------------------------------------- links */

void iv_test_links(void)
{
    gi_scene *s = iv_test_load(GI_SOURCE_DIR "/scenes/cornell_box_coarse.gltf");
    if (!s)
        return;
    gi_error err;
    iv_hier *h = iv_hier_create(s, 0.0f, IV_REMESH_GRID, &err);
    EXPECT(h != NULL, "%s", err.text);
    if (!h) {
        gi_scene_free(s);
        return;
    }
    iv_hier_update(h, s, 0.0f);
    const uint32_t n = 4;
    iv_links *l = iv_links_create(h, n);
    /* brute force: each bin holds the nearest element in it */
    iv_links_build(l, h, 1.0f, 1, 0);
    int wrong_bin = 0, not_nearest = 0;
    for (uint32_t e = 0; e < h->elem_count; e++) {
        uint32_t A = h->elem_node[e];
        gi_vec3 pa = gi_v3_load(&h->pos[3 * A]);
        float best[6 * 4 * 4];
        for (uint32_t b = 0; b < l->bins; b++)
            best[b] = FLT_MAX;
        for (uint32_t f = 0; f < h->elem_count; f++) {
            gi_vec3 d = gi_v3_sub(gi_v3_load(&h->pos[3 * h->elem_node[f]]), pa);
            float r = gi_v3_length(d);
            /* the one rule for sides: a single-sided disc seen from behind is not there */
            gi_vec3 nf = gi_v3_load(&h->nrm[3 * h->elem_node[f]]);
            int behind = !h->elem_two_sided_emit[f] && gi_v3_dot(nf, d) > 0.0f;
            if (f != e && r > 1e-10f && !behind) {
                uint32_t b = iv_bin_of(d, n);
                best[b] = fminf(best[b], r);
            }
        }
        for (uint32_t b = 0; b < l->bins; b++) {
            int32_t o = l->cell[(size_t)A * l->bins + b].other;
            if (o < 0) {
                not_nearest += best[b] != FLT_MAX;
                continue;
            }
            gi_vec3 d = gi_v3_sub(gi_v3_load(&h->pos[3 * o]), pa);
            wrong_bin += iv_bin_of(d, n) != b;
            not_nearest += fabsf(gi_v3_length(d) - best[b]) > 1e-5f * best[b];
        }
    }
    EXPECT(wrong_bin == 0 && not_nearest == 0,
           "brute force: %d links in a wrong bin, %d bins without the nearest", wrong_bin,
           not_nearest);
    /* hierarchical: links in the right bin; after refinement nothing longer
     * than a link on the path to the root */
    iv_links_build(l, h, 1.0f, 0, 0);
    wrong_bin = 0;
    for (uint32_t A = 0; A < h->node_count; A++)
        for (uint32_t b = 0; b < l->bins; b++) {
            int32_t o = l->cell[(size_t)A * l->bins + b].other;
            if (o >= 0) {
                gi_vec3 d = gi_v3_sub(gi_v3_load(&h->pos[3 * o]), gi_v3_load(&h->pos[3 * A]));
                wrong_bin += iv_bin_of(d, n) != b;
            }
        }
    size_t cells = (size_t)l->bins * h->node_count;
    float *before = malloc(cells * sizeof(float));
    for (size_t i = 0; i < cells; i++)
        before[i] = l->cell[i].dist;
    iv_links_refine_push(l, h);
    int longer = 0, lost = 0;
    for (uint32_t e = 0; e < h->elem_count; e++) {
        uint32_t x = h->elem_node[e];
        for (uint32_t b = 0; b < l->bins; b++) {
            float shortest = FLT_MAX;
            for (int32_t a = (int32_t)x; a >= 0; a = h->parent[a])
                shortest = fminf(shortest, before[(size_t)a * l->bins + b]);
            float got = l->cell[(size_t)x * l->bins + b].dist;
            longer += got > shortest;
            lost += shortest < FLT_MAX && l->cell[(size_t)x * l->bins + b].other < 0;
        }
        /* the receiving list holds one link per filled bin, in bin order */
        for (uint32_t j = l->leaf_off[e]; j + 1 < l->leaf_off[e + 1]; j++)
            longer += l->leaf_bin[j] >= l->leaf_bin[j + 1];
    }
    free(before);
    EXPECT(wrong_bin == 0, "hierarchical: %d links in a wrong bin", wrong_bin);
    EXPECT(longer == 0 && lost == 0,
           "refinement: %d leaf bins keep a longer link (or repeat a bin), %d lost one", longer,
           lost);
    printf("links: %llu pairs tried, %llu bin entries, %llu receiving links at %u leaves\n",
           (unsigned long long)l->tries, (unsigned long long)l->created,
           (unsigned long long)l->receiving, h->elem_count);
    iv_links_free(l);
    iv_hier_free(h);
    gi_scene_free(s);
}
