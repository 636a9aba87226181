/* The implicit_vis plugin's CPU stages against independent computations
 * (the plugin's iv_core.c is compiled in; plugins/implicit_vis/README.md
 * "Tests"):
 *
 *   iv_tests bins       direction -> bin -> the bin's centre lies in the bin;
 *                       the bins' solid angles sum to 4 pi;
 *   iv_tests hierarchy  every element in exactly one leaf; each node's area
 *                       the sum of its children's, its position their
 *                       area-weighted mean; the roots' areas sum to the
 *                       scene's surface area; leaves follow rigid motion
 *                       and morph targets (cornell_moving, cornell_deform);
 *   iv_tests links      every stored link lies in the bin of its direction;
 *                       brute force keeps in each bin exactly the nearest of
 *                       all elements in that bin (checked against a plain
 *                       scan); after refinement no leaf keeps a link longer
 *                       than one on its path to the root in the same bin;
 *   iv_tests furnace    closed emitting sphere (tests/data/conformance):
 *                       Le sum_{k <= n + 1} rho^k within 2 % for n = 0..3;
 *   iv_tests direct     Cornell box, direct light per element against Embree
 *                       (shadow rays to the area light): the method's error
 *                       must be at most half of the better trivial answer's
 *                       (black, or unshadowed); discs Embree sees fully
 *                       hidden from the light mostly get no light link;
 *   iv_tests brute      hierarchical and brute-force links give irradiance
 *                       within a stated tolerance on a small scene;
 *   iv_tests leak       Fig. 10(d): the share of the environment light the
 *                       792-vertex teapot blocks from the ground (Embree)
 *                       that the method lets through, with and without
 *                       splatting, the model as it is and re-meshed;
 *   iv_tests gpu        the GPU gather and pull-up (iv_gpu.c, Sec. 4.3.1)
 *                       against iv_illuminate on the same links: Cornell
 *                       box, furnace, environment, punctual lights, the
 *                       coverage modes; and the furnace through the GPU. */
#include "iv.h"
#include "iv_gpu.h"

#include "gi/gpu.h"
#include "gi/lights.h"
#include "gi/mesh.h"
#include "gi/raytrace.h"
#include "gi/sampling.h"
#include "gi/shader.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#define EXPECT CHECK_MSG

extern const gi_shader_source gi_implicit_vis_shaders[];

/* The GL context of the `gpu` part (NULL elsewhere). */
static gi_gpu *g_gpu = NULL;

/* The GPU illumination of the links in l (the scene uploaded and its
 * punctual lights bound at t = 0): irradiance in iv_illuminate's layout.
 * Returns 0 (and counts a failure) when a step fails. */
static int gpu_illuminate(const gi_scene *s, const iv_hier *h, const iv_links *l, uint32_t bounces, float *E)
{
    gi_error err;
    gi_gpu_scene *gs = gi_gpu_scene_upload(g_gpu, s, &err);
    EXPECT(gs != NULL, "upload: %s", err.text);
    if (!gs)
        return 0;
    gi_gpu_scene_set_time(gs, 0.0f);
    gi_gpu_scene_bind(gs);
    iv_gpu *g = iv_gpu_create(h, l, s->envmap, &err);
    EXPECT(g != NULL, "GPU illumination: %s", err.text);
    int ok = g != NULL;
    if (g) {
        gi_result r = iv_gpu_illuminate(g, l, h, bounces, s->light_count, &err);
        EXPECT(r == GI_OK, "GPU illumination: %s", err.text);
        ok = r == GI_OK;
        if (ok)
            iv_gpu_read(g, E);
    }
    iv_gpu_free(g);
    gi_gpu_scene_free(gs);
    return ok;
}

static gi_scene *load(const char *path)
{
    gi_error err;
    gi_scene *s = gi_scene_load(path, &err);
    EXPECT(s != NULL, "cannot load %s: %s", path, err.text);
    return s;
}

static uint64_t lcg(uint64_t *st)
{
    *st = *st * 6364136223846793005ull + 1442695040888963407ull;
    return *st >> 11;
}
static float urand(uint64_t *st) { return (float)((double)lcg(st) / 9007199254740992.0); }

/* Link modes of the next frame_run / furnace_mean (the plugin's defaults:
 * one bin per link, Eq. 5 covering); the environment (IV_BILINEAR 0 or 1,
 * IV_COVERAGE a share) overrides them, for exploring. */
static int g_bilinear = 0;
static float g_coverage = 0.0f;
static void iv_test_modes(iv_links *l)
{
    const char *b = getenv("IV_BILINEAR"), *c = getenv("IV_COVERAGE");
    l->bilinear = b ? atoi(b) : g_bilinear;
    l->coverage = c ? (float)atof(c) : g_coverage;
}

/* ---------------------------------------------------------------- bins */

static void test_bins(void)
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

static void check_hierarchy(const iv_hier *h, const gi_scene *s, float t, const char *what)
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
            bad_pos += a > 0.0 && fabs(p[j] / a - h->pos[3 * i + j]) > 1e-4 * (1.0 + fabs(h->pos[3 * i + j]));
    }
    int bad_elem = 0;
    for (uint32_t e = 0; e < h->elem_count; e++)
        bad_elem += seen[e] != 1;
    free(seen);
    EXPECT(bad_tree == 0 && bad_elem == 0, "%s: %d bad links in the tree, %d elements not in exactly one leaf", what,
           bad_tree, bad_elem);
    EXPECT(bad_area == 0 && bad_pos == 0, "%s: %d nodes' areas and %d positions differ from their children's", what,
           bad_area, bad_pos);
    double roots = 0.0, tris = 0.0;
    for (uint32_t r = 0; r < h->root_count; r++)
        roots += h->area[r];
    float *ta = malloc((s->triangle_count + 1) * sizeof(float));
    gi_mesh_triangle_areas(s, t, ta);
    for (uint32_t i = 0; i < s->triangle_count; i++)
        tris += ta[i];
    free(ta);
    EXPECT(fabs(roots - tris) <= 1e-4 * tris, "%s: roots' area %.6g, scene surface %.6g", what, roots, tris);
    /* leaves sit on their model vertex, placed at t */
    int bad_leaf = 0;
    for (uint32_t e = 0; e < h->elem_count; e++) {
        uint32_t si = h->elem_rep[e], tr = h->samp_tri[si];
        gi_vec3 c[3];
        gi_scene_triangle_world(s, tr, t, c);
        float b1 = h->samp_b[2 * si], b2 = h->samp_b[2 * si + 1];
        gi_vec3 p = gi_v3_add(gi_v3_scale(c[0], 1.0f - b1 - b2), gi_v3_add(gi_v3_scale(c[1], b1), gi_v3_scale(c[2], b2)));
        bad_leaf += gi_v3_length(gi_v3_sub(p, gi_v3_load(&h->pos[3 * h->elem_node[e]]))) > 1e-4f;
    }
    EXPECT(bad_leaf == 0, "%s: %d leaves off their vertex", what, bad_leaf);
    printf("%s: %u elements, %u nodes, %u segments, depth %u\n", what, h->elem_count, h->node_count, h->root_count,
           h->depth);
}

static void test_hierarchy(void)
{
    const char *scenes[] = {GI_SOURCE_DIR "/scenes/cornell_box.gltf", GI_SOURCE_DIR "/scenes/cornell_moving.gltf",
                            GI_SOURCE_DIR "/scenes/cornell_deform.gltf"};
    for (int k = 0; k < 3; k++) {
        gi_scene *s = load(scenes[k]);
        if (!s)
            continue;
        gi_error err;
        iv_hier *h = iv_hier_create(s, 0.0f, &err);
        EXPECT(h != NULL, "%s: %s", scenes[k], err.text);
        if (h) {
            float ts[2] = {0.0f, s->animation_length > 0.0f ? 0.6f * s->animation_length : 0.0f};
            for (int i = 0; i < 2; i++) {
                iv_hier_update(h, s, ts[i]);
                char what[600];
                snprintf(what, sizeof what, "%s t=%.2f", strrchr(scenes[k], '/') + 1, ts[i]);
                check_hierarchy(h, s, ts[i], what);
            }
        }
        iv_hier_free(h);
        gi_scene_free(s);
    }
}

/* --------------------------------------------------------------- links */

static void test_links(void)
{
    gi_scene *s = load(GI_SOURCE_DIR "/scenes/cornell_box_coarse.gltf");
    if (!s)
        return;
    gi_error err;
    iv_hier *h = iv_hier_create(s, 0.0f, &err);
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
            if (f != e && r > 1e-10f) {
                uint32_t b = iv_bin_of(d, n);
                best[b] = fminf(best[b], r);
            }
        }
        for (uint32_t b = 0; b < l->bins; b++) {
            int32_t o = l->other[(size_t)A * l->bins + b];
            if (o < 0) {
                not_nearest += best[b] != FLT_MAX;
                continue;
            }
            gi_vec3 d = gi_v3_sub(gi_v3_load(&h->pos[3 * o]), pa);
            wrong_bin += iv_bin_of(d, n) != b;
            not_nearest += fabsf(gi_v3_length(d) - best[b]) > 1e-5f * best[b];
        }
    }
    EXPECT(wrong_bin == 0 && not_nearest == 0, "brute force: %d links in a wrong bin, %d bins without the nearest",
           wrong_bin, not_nearest);
    /* hierarchical: links in the right bin; after refinement nothing longer
     * than a link on the path to the root */
    iv_links_build(l, h, 1.0f, 0, 0);
    wrong_bin = 0;
    for (uint32_t A = 0; A < h->node_count; A++)
        for (uint32_t b = 0; b < l->bins; b++) {
            int32_t o = l->other[(size_t)A * l->bins + b];
            if (o >= 0) {
                gi_vec3 d = gi_v3_sub(gi_v3_load(&h->pos[3 * o]), gi_v3_load(&h->pos[3 * A]));
                wrong_bin += iv_bin_of(d, n) != b;
            }
        }
    size_t cells = (size_t)l->bins * h->node_count;
    float *before = malloc(cells * sizeof(float));
    memcpy(before, l->dist, cells * sizeof(float));
    iv_links_refine_push(l, h);
    int longer = 0, lost = 0;
    for (uint32_t e = 0; e < h->elem_count; e++) {
        uint32_t x = h->elem_node[e];
        for (uint32_t b = 0; b < l->bins; b++) {
            float shortest = FLT_MAX;
            for (int32_t a = (int32_t)x; a >= 0; a = h->parent[a])
                shortest = fminf(shortest, before[(size_t)a * l->bins + b]);
            float got = l->dist[(size_t)x * l->bins + b];
            longer += got > shortest;
            lost += shortest < FLT_MAX && l->other[(size_t)x * l->bins + b] < 0;
        }
        /* the receiving list holds one link per filled bin, in bin order */
        for (uint32_t j = l->leaf_off[e]; j + 1 < l->leaf_off[e + 1]; j++)
            longer += l->leaf_bin[j] >= l->leaf_bin[j + 1];
    }
    free(before);
    EXPECT(wrong_bin == 0, "hierarchical: %d links in a wrong bin", wrong_bin);
    EXPECT(longer == 0 && lost == 0, "refinement: %d leaf bins keep a longer link (or repeat a bin), %d lost one",
           longer, lost);
    printf("links: %llu pairs tried, %llu bin entries, %llu receiving links at %u leaves\n",
           (unsigned long long)l->tries, (unsigned long long)l->created, (unsigned long long)l->receiving,
           h->elem_count);
    iv_links_free(l);
    iv_hier_free(h);
    gi_scene_free(s);
}

/* ------------------------------------------------------------ furnace */

/* Mean radiance (area-weighted) the inside of the sphere shows its centre,
 * for bounces 0..3 (one link structure, four gathers). */
static int furnace_means(const char *path, uint32_t N, double mean[4], double *rho_out, double *le_out)
{
    gi_scene *s = load(path);
    if (!s)
        return 0;
    gi_error err;
    iv_hier *h = iv_hier_create(s, 0.0f, &err);
    EXPECT(h != NULL, "%s: %s", path, err.text);
    if (h) {
        iv_hier_update(h, s, 0.0f);
        iv_links *l = iv_links_create(h, N);
        iv_test_modes(l);
        float *E = malloc((size_t)h->elem_count * 6 * sizeof(float));
        iv_links_build(l, h, 1.0f, 0, 1);
        iv_links_refine_push(l, h);
        iv_lights li = {s, 0.0f, NULL};
        for (uint32_t n = 0; n <= 3; n++) {
            if (g_gpu)
                gpu_illuminate(s, h, l, n, E);
            else
                iv_illuminate(l, h, &li, n, E);
            double sum = 0.0, area = 0.0;
            for (uint32_t e = 0; e < h->elem_count; e++) {
                uint32_t x = h->elem_node[e];
                gi_vec3 p = gi_v3_load(&h->pos[3 * x]), nn = gi_v3_load(&h->nrm[3 * x]);
                int front = gi_v3_dot(nn, gi_v3_scale(p, -1.0f)) >= 0.0f; /* the side facing the centre */
                double Le = front || h->elem_two_sided_emit[e] ? h->elem_emit[3 * e] : 0.0;
                double L = Le + h->elem_albedo[3 * e] / GI_PI * E[6 * e + (front ? 0 : 3)];
                sum += h->area[x] * L;
                area += h->area[x];
            }
            mean[n] = sum / area;
        }
        *rho_out = h->elem_albedo[0];
        *le_out = h->elem_emit[0];
        free(E);
        iv_links_free(l);
        iv_hier_free(h);
    }
    gi_scene_free(s);
    return h != NULL;
}

static void test_furnace(void)
{
    const char *paths[] = {GI_SOURCE_DIR "/tests/data/conformance/furnace_050.gltf",
                           GI_SOURCE_DIR "/tests/data/conformance/furnace_080.gltf"};
    uint32_t Ns[] = {8, 12};
    for (int mode = 0; mode < 2; mode++) {
        g_bilinear = mode;
        g_coverage = mode ? 0.7f : 0.0f;
        printf("links: bilinear %d, coverage %.2g, illumination on the %s\n", g_bilinear, (double)g_coverage,
               g_gpu ? "GPU" : "CPU");
        for (int k = 0; k < 2; k++)
            for (int in = 0; in < 2; in++) {
                double rho = 0.0, le = 0.0, got[4];
                if (!furnace_means(paths[k], Ns[in], got, &rho, &le))
                    continue;
                for (uint32_t n = 0; n <= 3; n++) {
                    double expect = 0.0;
                    for (uint32_t j = 0; j <= n + 1; j++)
                        expect += le * pow(rho, (double)j);
                    double dev = got[n] / expect - 1.0;
                    printf("furnace rho %.2f N %u bounces %u: %.4f, expected %.4f (%+.2f %%)\n", rho, Ns[in], n, got[n],
                           expect, 100.0 * dev);
                    EXPECT(fabs(dev) <= 0.02, "furnace rho %.2f N %u bounces %u: %+.2f %% (limit 2 %%)", rho, Ns[in], n,
                           100.0 * dev);
                }
            }
    }
    g_bilinear = 0;
    g_coverage = 0.0f;
}

/* ------------------------------------------------------ direct vs Embree */

typedef struct frame {
    gi_scene *s;
    iv_hier *h;
    iv_links *l;
    float *E;
} frame;

static int frame_run(frame *f, const char *path, float edge, uint32_t N, uint32_t bounces, int brute, int splat)
{
    memset(f, 0, sizeof *f);
    f->s = load(path);
    if (!f->s)
        return 0;
    gi_error err;
    f->h = iv_hier_create(f->s, edge, &err);
    EXPECT(f->h != NULL, "%s", err.text);
    if (!f->h)
        return 0;
    iv_hier_update(f->h, f->s, 0.0f);
    f->l = iv_links_create(f->h, N);
    iv_test_modes(f->l);
    f->E = malloc((size_t)f->h->elem_count * 6 * sizeof(float));
    iv_links_build(f->l, f->h, 1.0f, brute, splat);
    iv_links_refine_push(f->l, f->h);
    iv_lights li = {f->s, 0.0f, f->s->envmap};
    iv_illuminate(f->l, f->h, &li, bounces, f->E);
    return 1;
}

static void frame_free(frame *f)
{
    free(f->E);
    iv_links_free(f->l);
    iv_hier_free(f->h);
    gi_scene_free(f->s);
}

static double lum(const float *c) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }

/* Direct irradiance on the normal's side of disc e from the emissive
 * triangles, 8 x 8 stratified points on each, with and without Embree
 * shadow rays. */
static void exact_direct(const gi_scene *s, const gi_rt *rt, gi_vec3 p, gi_vec3 n, float eps, double *shadowed,
                         double *unshadowed)
{
    const int S = 8;
    *shadowed = *unshadowed = 0.0;
    for (uint32_t k = 0; k < s->emitter_count; k++) {
        uint32_t t = s->emitters[k];
        gi_vec3 c[3];
        gi_scene_triangle_world(s, t, 0.0f, c);
        gi_vec3 ng = gi_v3_cross(gi_v3_sub(c[1], c[0]), gi_v3_sub(c[2], c[0]));
        float area = 0.5f * gi_v3_length(ng);
        ng = gi_v3_normalize(ng);
        double le = lum(gi_scene_triangle_emission(s, t));
        int two = s->materials[s->vertices[s->indices[3 * t]].material].double_sided;
        for (int j = 0; j < S; j++)
            for (int i = 0; i < S; i++) {
                float u1 = ((float)i + 0.5f) / (float)S, u2 = ((float)j + 0.5f) / (float)S;
                float su = sqrtf(u1);
                gi_vec3 y = gi_v3_add(gi_v3_scale(c[0], 1.0f - su),
                                      gi_v3_add(gi_v3_scale(c[1], su * (1.0f - u2)), gi_v3_scale(c[2], su * u2)));
                gi_vec3 w = gi_v3_sub(y, p);
                float r = gi_v3_length(w);
                w = gi_v3_scale(w, 1.0f / r);
                float cx = gi_v3_dot(n, w), cy = gi_emitter_cos(ng, w, two);
                if (cx <= 0.0f || cy <= 0.0f)
                    continue;
                double g = le * cx * cy / (r * r) * area / (S * S);
                *unshadowed += g;
                if (!gi_rt_occluded(rt, gi_v3_add(p, gi_v3_scale(n, eps)), w, eps, r - 2.0f * eps))
                    *shadowed += g;
            }
    }
}

static void direct_case(const char *scene, float edge_frac, int required)
{
    frame f;
    uint32_t N = 12;
    if (!frame_run(&f, scene, edge_frac * 5.592f, N, 0, getenv("IV_BRUTE") ? 1 : 0, 1)) {
        EXPECT(0, "set-up failed");
        frame_free(&f);
        return;
    }
    gi_rt *rt = NULL;
    gi_error err;
    EXPECT(gi_rt_create(f.s, 0.0f, &rt, &err) == GI_OK, "%s", err.text);
    if (!rt) {
        frame_free(&f);
        return;
    }
    float ext = 0.0f;
    for (int i = 0; i < 3; i++)
        ext = fmaxf(ext, f.s->bounds[3 + i] - f.s->bounds[i]);
    double ref_sum = 0.0, m_err = 0.0, u_err = 0.0;
    long hidden = 0, hidden_dark = 0, lit = 0, lit_dark = 0;
    const iv_hier *h = f.h;
    for (uint32_t e = 0; e < h->elem_count; e++) {
        if (lum(&h->elem_emit[3 * e]) > 0.0)
            continue; /* the light's own discs */
        uint32_t x = h->elem_node[e];
        double sh, un;
        exact_direct(f.s, rt, gi_v3_load(&h->pos[3 * x]), gi_v3_load(&h->nrm[3 * x]), 1e-4f * ext, &sh, &un);
        double m = lum(&f.E[6 * e]), a = h->area[x];
        ref_sum += a * sh;
        m_err += a * fabs(m - sh);
        u_err += a * fabs(un - sh);
        if (un > 0.0 && sh == 0.0) {
            hidden++;
            hidden_dark += m == 0.0;
            if (m != 0.0 && getenv("IV_DEBUG") && hidden - hidden_dark < 8) {
                gi_vec3 pp = gi_v3_load(&h->pos[3 * x]), nn = gi_v3_load(&h->nrm[3 * x]);
                printf("  lit but hidden: disc %u at (%.3f %.3f %.3f) n (%.2f %.2f %.2f) E %.4g of unshadowed %.4g, area %.4g\n", e,
                       pp.x, pp.y, pp.z, nn.x, nn.y, nn.z, m, un, h->area[x]);
                for (uint32_t j = f.l->light_off[e]; j < f.l->light_off[e + 1]; j++) {
                    uint32_t src = f.l->light_src[j];
                    printf("    light link bin %u to node %u at dist %.3f (leaf %d) cover %.3f\n", f.l->light_bin[j], src,
                           f.l->dist[(size_t)x * f.l->bins + f.l->light_bin[j]], iv_is_leaf(h, src),
                           f.l->cover[(size_t)x * f.l->bins + f.l->light_bin[j]] / f.l->bin_omega[f.l->light_bin[j]]);
                }
            }
        } else if (sh > 0.5 * un && un > 0.0) {
            lit++;
            lit_dark += m == 0.0;
        }
    }
    double me = m_err / ref_sum, ue = u_err / ref_sum, be = 1.0;
    printf("direct light per disc against Embree (%s, N = %u, bilinear %d, coverage %.2g, re-mesh edge %.3g x 5.592, "
           "%u discs): relative L1 error method %.3f, unshadowed %.3f, black %.3f\n",
           strrchr(scene, '/') + 1, N, f.l->bilinear, (double)f.l->coverage, edge_frac, h->elem_count, me, ue, be);
    printf("discs hidden from the light (Embree): %ld, of them without light from the method %ld (%.1f %%); "
           "discs mostly lit: %ld, of them dark %ld\n",
           hidden, hidden_dark, 100.0 * (double)hidden_dark / (double)(hidden ? hidden : 1), lit, lit_dark);
    if (required == 1) {
        /* the occluder test: a disc Embree sees hidden from the light gets no light link */
        EXPECT(hidden >= 100, "only %ld hidden discs: the scene does not test occlusion", hidden);
        EXPECT(hidden_dark >= 0.9 * hidden, "%ld of %ld hidden discs get light", hidden - hidden_dark, hidden);
    } else if (required == 2) {
        /* margin: the method removes at least half of black's error (it does not beat the
         * unshadowed answer per disc on this scene: README "Tests") */
        EXPECT(me <= 0.5 * be, "method error %.3f > half of black's %.3f", me, be);
        EXPECT(lit_dark <= 0.05 * lit, "%ld of %ld lit discs get no light", lit_dark, lit);
    }
    gi_rt_free(rt);
    frame_free(&f);
}

static void test_direct(void)
{
    const char *e = getenv("IV_TEST_EDGE");
    const char *sc = getenv("IV_TEST_SCENE");
    if (e || sc) {
        direct_case(sc ? sc : GI_SOURCE_DIR "/scenes/cornell_box.gltf", e ? (float)atof(e) : 0.0f, 0);
        return;
    }
    /* defaults (Eq. 5): the Cornell box's light lies flush under the ceiling */
    direct_case(GI_SOURCE_DIR "/scenes/cornell_box.gltf", 0.0f, 1);
    direct_case(GI_SOURCE_DIR "/scenes/teapot_area.glb", 0.0f, 0);
    /* bilinear links and full coverage: the small area light's energy right */
    g_bilinear = 1;
    g_coverage = 1.0f;
    direct_case(GI_SOURCE_DIR "/scenes/cornell_box.gltf", 0.0f, 0);
    direct_case(GI_SOURCE_DIR "/scenes/teapot_area.glb", 0.0f, 2);
    g_bilinear = 0;
    g_coverage = 0.0f;
}

/* -------------------------------------------- hierarchical vs brute force */

static void test_brute(void)
{
    const char *paths[] = {GI_SOURCE_DIR "/tests/data/conformance/furnace_080.gltf",
                           GI_SOURCE_DIR "/tests/data/conformance/one_object_area_point.gltf"};
    for (int k = 0; k < 2; k++) {
        frame a, b;
        int ok = frame_run(&a, paths[k], 0.0f, 8, 1, 0, 1) && frame_run(&b, paths[k], 0.0f, 8, 1, 1, 1);
        EXPECT(ok, "set-up failed for %s", paths[k]);
        if (ok) {
            double diff = 0.0, sum = 0.0;
            for (uint32_t e = 0; e < a.h->elem_count; e++) {
                double w = a.h->area[a.h->elem_node[e]];
                for (int side = 0; side < 2; side++) {
                    diff += w * fabs(lum(&a.E[6 * e + 3 * side]) - lum(&b.E[6 * e + 3 * side]));
                    sum += w * lum(&b.E[6 * e + 3 * side]);
                }
            }
            double rel = sum > 0.0 ? diff / sum : 0.0;
            printf("%s: hierarchical %llu tries, brute force %llu; irradiance differs by %.3f (relative L1)\n",
                   strrchr(paths[k], '/') + 1, (unsigned long long)a.l->tries, (unsigned long long)b.l->tries, rel);
            EXPECT(sum > 0.0, "%s: no light at all", paths[k]);
            EXPECT(rel <= 0.10, "%s: hierarchical and brute force differ by %.3f (limit 0.10)", paths[k], rel);
        }
        frame_free(&a);
        frame_free(&b);
    }
}

/* ------------------------------------------- Fig. 10(d): the teapot's leak */

/* Ground discs of teapot_plane (object 1) that the teapot shadows from the
 * environment (Embree: 256 cosine-weighted rays keep less than 80 % of the
 * unshadowed irradiance): the share of the blocked irradiance the method
 * lets through (its direct irradiance above the exact one), for the model
 * as it is and re-meshed to edge `edge`. Returns the leaked share. */
static double leak_case(float edge, uint32_t N, int splat, uint32_t *discs)
{
    frame f;
    double leaked = -1.0;
    if (!frame_run(&f, GI_SOURCE_DIR "/scenes/teapot_plane.glb", edge, N, 0, 0, splat) || !f.s->envmap) {
        EXPECT(0, "set-up failed (teapot_plane with its environment)");
        frame_free(&f);
        return -1.0;
    }
    gi_rt *rt = NULL;
    gi_error err;
    EXPECT(gi_rt_create(f.s, 0.0f, &rt, &err) == GI_OK, "%s", err.text);
    if (!rt) {
        frame_free(&f);
        return -1.0;
    }
    const iv_hier *h = f.h;
    double blocked = 0.0, through = 0.0;
    uint32_t n = 0;
    const int M = 16;
    for (uint32_t e = 0; e < h->elem_count; e++) {
        uint32_t si = h->elem_rep[e], x = h->elem_node[e];
        if (f.s->vertices[f.s->indices[3 * h->samp_tri[si]]].object != 1)
            continue;
        gi_vec3 p = gi_v3_load(&h->pos[3 * x]), nn = gi_v3_load(&h->nrm[3 * x]);
        if (p.x * p.x + p.z * p.z > 9.0f)
            continue; /* only near the teapot */
        double un = 0.0, sh = 0.0;
        for (int j = 0; j < M; j++)
            for (int i = 0; i < M; i++) {
                gi_vec3 w = gi_to_world(gi_sample_cosine_hemisphere(((float)i + 0.5f) / M, ((float)j + 0.5f) / M), nn);
                float L[3];
                gi_envmap_eval(f.s->envmap, w, L);
                double l = lum(L) * GI_PI / (M * M);
                un += l;
                if (!gi_rt_occluded(rt, gi_v3_add(p, gi_v3_scale(nn, 1e-3f)), w, 1e-3f, 1e30f))
                    sh += l;
            }
        if (!(sh < 0.8 * un))
            continue;
        double m = lum(&f.E[6 * e]), a = h->area[x];
        n++;
        blocked += a * (un - sh);
        through += a * fmax(0.0, fmin(m, un) - sh);
    }
    leaked = blocked > 0.0 ? through / blocked : 0.0;
    printf("teapot_plane, N = %u, splat %d, re-mesh edge %.3g: %u shadowed ground discs near the teapot (%u discs in all); "
           "the method lets through %.1f %% of the irradiance the teapot blocks\n",
           N, splat, (double)edge, n, h->elem_count, 100.0 * leaked);
    *discs = n;
    gi_rt_free(rt);
    frame_free(&f);
    return leaked;
}

static void test_leak(void)
{
    uint32_t n0 = 0, n1 = 0, n2 = 0, n3 = 0;
    double literal = leak_case(0.0f, 12, 0, &n2);
    double literal_fine = leak_case(0.08f, 12, 0, &n3);
    double coarse = leak_case(0.0f, 12, 1, &n0);
    double fine = leak_case(0.08f, 12, 1, &n1);
    EXPECT(n0 >= 50 && n1 >= 50 && n2 >= 50 && n3 >= 50, "too few shadowed ground discs (%u, %u, %u, %u)", n0, n1, n2,
           n3);
    /* the paper's Fig. 10(d): the coarse teapot leaks, re-meshed it leaks less */
    EXPECT(literal_fine < 0.5 * literal, "without splatting, re-meshing leaks %.3f, the model %.3f", literal_fine,
           literal);
    /* splatting near discs closes the leak (measured 0.8 % and 0.3 %) */
    EXPECT(coarse <= 0.05 && fine <= 0.05, "with splatting the teapot lets %.3f / %.3f through", coarse, fine);
}

/* ------------------------------------------------ GPU against the CPU */

/* One scene: the same links gathered by iv_illuminate and by the GPU
 * passes; their relative L1 difference (area-weighted, both sides, every
 * channel) must stay within `limit` (float summation order), and be far
 * below the difference one bounce makes, so that a missing or extra gather
 * could not pass. */
static void gpu_case(const char *path, uint32_t N, uint32_t bounces, int bilinear, float coverage, double limit)
{
    g_bilinear = bilinear;
    g_coverage = coverage;
    frame f;
    int ok = frame_run(&f, path, 0.0f, N, bounces, 0, 1);
    EXPECT(ok, "set-up failed for %s", path);
    float *G = ok ? malloc((size_t)f.h->elem_count * 6 * sizeof(float)) : NULL;
    float *P = ok ? malloc((size_t)f.h->elem_count * 6 * sizeof(float)) : NULL;
    if (ok && G && P && gpu_illuminate(f.s, f.h, f.l, bounces, G)) {
        iv_lights li = {f.s, 0.0f, f.s->envmap};
        if (bounces > 0)
            iv_illuminate(f.l, f.h, &li, bounces - 1, P); /* one gather fewer: the answer to tell apart */
        else
            memset(P, 0, (size_t)f.h->elem_count * 6 * sizeof(float));
        double diff = 0.0, fewer = 0.0, sum = 0.0, worst = 0.0;
        for (uint32_t e = 0; e < f.h->elem_count; e++) {
            double a = f.h->area[f.h->elem_node[e]];
            for (int c = 0; c < 6; c++) {
                double d = fabs((double)G[6 * e + c] - f.E[6 * e + c]);
                diff += a * d;
                fewer += a * fabs((double)P[6 * e + c] - f.E[6 * e + c]);
                sum += a * fabs((double)f.E[6 * e + c]);
                worst = fmax(worst, d / (fabs((double)f.E[6 * e + c]) + 1e-3));
            }
        }
        double rel = sum > 0.0 ? diff / sum : 1.0, rel_fewer = sum > 0.0 ? fewer / sum : 0.0;
        printf("%s (N %u, %u bounces, bilinear %d, coverage %.2g, %u discs): GPU against CPU relative L1 %.2e "
               "(limit %.0e), worst disc %.2e; one bounce fewer on the CPU %.2e\n",
               strrchr(path, '/') + 1, N, bounces, bilinear, (double)coverage, f.h->elem_count, rel, limit, worst,
               rel_fewer);
        EXPECT(sum > 0.0, "%s: no light at all", path);
        EXPECT(rel <= limit, "%s: GPU and CPU differ by %.2e (limit %.0e)", path, rel, limit);
        EXPECT(rel_fewer >= 10.0 * limit, "%s: one bounce fewer differs by only %.2e: the test cannot tell", path,
               rel_fewer);
    }
    free(G);
    free(P);
    frame_free(&f);
    g_bilinear = 0;
    g_coverage = 0.0f;
}

static void test_gpu(void)
{
    gi_error err;
    g_gpu = gi_gpu_create(NULL, &err);
    EXPECT(g_gpu != NULL, "no GL context: %s", err.text);
    if (!g_gpu)
        return;
    EXPECT(gi_shader_register(gi_implicit_vis_shaders, &err) == GI_OK, "shaders: %s", err.text);
    printf("GL renderer: %s\n", gi_gpu_renderer(g_gpu));
    const double limit = 1e-4;
    gpu_case(GI_SOURCE_DIR "/scenes/cornell_box.gltf", 12, 3, 0, 0.0f, limit);
    gpu_case(GI_SOURCE_DIR "/scenes/cornell_box.gltf", 8, 1, 1, 0.7f, limit);
    gpu_case(GI_SOURCE_DIR "/tests/data/conformance/furnace_050.gltf", 12, 3, 0, 0.0f, limit);
    gpu_case(GI_SOURCE_DIR "/tests/data/conformance/furnace_080.gltf", 8, 2, 0, 0.0f, limit);
    gpu_case(GI_SOURCE_DIR "/tests/data/conformance/one_object_area_point.gltf", 8, 2, 0, 0.0f, limit);
    gpu_case(GI_SOURCE_DIR "/scenes/teapot_plane.glb", 8, 1, 0, 0.0f, limit);
    /* the furnace through the GPU passes: Le sum rho^k within 2 % */
    test_furnace();
    gi_gpu_destroy(g_gpu);
    g_gpu = NULL;
}

int main(int argc, char **argv)
{
    const char *part = argc > 1 ? argv[1] : "all";
    int all = !strcmp(part, "all"), known = 0;
    if (all || !strcmp(part, "bins"))
        test_bins(), known = 1;
    if (all || !strcmp(part, "hierarchy"))
        test_hierarchy(), known = 1;
    if (all || !strcmp(part, "links"))
        test_links(), known = 1;
    if (all || !strcmp(part, "furnace"))
        test_furnace(), known = 1;
    if (all || !strcmp(part, "direct"))
        test_direct(), known = 1;
    if (all || !strcmp(part, "leak"))
        test_leak(), known = 1;
    if (all || !strcmp(part, "brute"))
        test_brute(), known = 1;
    if (all || !strcmp(part, "gpu"))
        test_gpu(), known = 1;
    if (!known) {
        fprintf(stderr, "iv_tests: unknown part '%s'\n", part);
        return 2;
    }
    if (gi_test_failed)
        fprintf(stderr, "%d failure(s)\n", gi_test_failed);
    return gi_test_failed ? 1 : 0;
}
