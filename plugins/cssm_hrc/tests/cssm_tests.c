/* Tests of the cssm_hrc plugin's parts (plugins/cssm_hrc/README.md "Tests"),
 * with its sources compiled in:
 *   traversal   every traversal visits every texel exactly once (Cornell
 *               box charts, the furnace sphere's surface samples); zig-zag
 *               and spiral steps stay between neighbouring texels of a
 *               chart except at a stated few jumps
 *   tree        the skip-pointer traversal equals a recursive depth-first
 *               traversal, for full traversals and for selective ones
 *               with pseudo-random refine decisions; spheres hold their
 *               texels, areas add up
 *   visibility  CSSM visibility against Embree occlusion between random
 *               Cornell-box texel / surface-point pairs, against the
 *               always-visible and never-visible answers
 *   furnace     inside a closed emitting sphere (Le = 1, rho = 0.5) the
 *               atlas holds Le sum_{k<=n} rho^k and a final gather
 *               Le sum_{k<=n+1} rho^k, within 2 %, for n = 1, 2, 3
 *   hull        the core's convex hulls (qhull) and their overlap test
 *               (GJK): overlapping pairs found, separated and near-touching
 *               ones (gap 1e-3) not, against the closed-form answers of
 *               boxes and against the bounding spheres of point clouds
 *   motion      §3.3: the moving Cornell box (the bunny moves), maps made
 *               at t = 0, the bunny moved to t = 1.5 s (D T^-1, nothing
 *               made again): visibility against Embree on the moved scene
 *               for pairs near the bunny, against always / never visible
 *               and the unmoved scene's visibility
 *   compact     the compact nodes of §4.2.1: random round trips within the
 *               stated bounds, conservative spheres and cones on the
 *               Cornell box tree, exact pointers, equal traversals, the
 *               packed pull against the float pull
 *   compact_furnace  the furnace with nodes=compact
 *   compact_limit    65 535 nodes pack, 65 537 are refused
 *   escape      env=cssm (§4.7 with the texels' own maps): on bunny_env
 *               and teapot_plane the escape test of a texel's cube map
 *               against Embree occlusion for random texel / direction
 *               pairs (against always / never escapes), the per-texel
 *               environment irradiance against the traced estimate with the
 *               same directions (against black and unshadowed), and what
 *               the escape intervals cost in compression (Cornell box too)
 * Usage: cssm_tests PART. Exit 0 on success, 1 with a message otherwise. */
#include "cssm.h"
#include "env_cssm.h"
#include "motion.h"

#include "check.h"
#include "gpu_fixture.h"

#include "gi/gpu.h"
#include "gi/algo/hull.h"
#include "gi/mesh.h"
#include "gi/raytrace.h"
#include "gi/rng.h"
#include "gi/sampling.h"
#include "gi/scene.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef GI_SOURCE_DIR
#define GI_SOURCE_DIR "."
#endif

/* The margins the motion part must beat the best trivial answer by, in
 * agreement rate (measured +24 points on all pairs, +38 on the pairs the
 * motion changed: README "Tests"). */
#define MOTION_MARGIN 0.15
#define MOTION_MARGIN_AFFECTED 0.25
#define TWO_MOVERS 400 /* part_motion2: pairs between the two moving objects */

static gi_scene *load(const char *rel)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", GI_SOURCE_DIR, rel);
    gi_error err;
    gi_scene *s = gi_scene_load(path, &err);
    if (!s)
        fprintf(stderr, "FAIL: %s\n", err.text);
    return s;
}

/* ------------------------------------------------------------ traversal */

static void check_traversals(const cssm_atlas *a, const char *what)
{
    for (int how = 0; how < 3; how++) {
        uint32_t *order = cssm_traverse(a, (cssm_traversal)how);
        CHECK_MSG(order != NULL, "traverse");
        if (!order)
            return;
        unsigned char *seen = calloc(a->count, 1);
        uint32_t twice = 0, jumps = 0, chart_changes = 0;
        for (uint32_t k = 0; k < a->count; k++) {
            CHECK_MSG(order[k] < a->count, "texel index %u out of range", order[k]);
            if (order[k] >= a->count)
                break;
            twice += seen[order[k]];
            seen[order[k]] = 1;
            if (k == 0)
                continue;
            const cssm_texel *p = &a->texels[order[k - 1]], *q = &a->texels[order[k]];
            if (p->chart != q->chart) {
                chart_changes++;
                continue;
            }
            if (p->chart < 0)
                continue;
            int dx = abs((int)p->x - (int)q->x), dy = abs((int)p->y - (int)q->y);
            jumps += dx + dy != 1;
        }
        uint32_t missed = 0;
        for (uint32_t i = 0; i < a->count; i++)
            missed += !seen[i];
        CHECK_MSG(!twice && !missed, "%s %s: %u visited twice, %u missed", what,
                  cssm_traversal_name((cssm_traversal)how), twice, missed);
        printf("%s %-7s: %u texels, each once; %u steps leave the chart, %u in-chart steps are not "
               "to a "
               "4-neighbour\n",
               what, cssm_traversal_name((cssm_traversal)how), a->count, chart_changes, jumps);
        /* charts are visited one after the other: each is entered once */
        if (how != CSSM_GREEDY)
            CHECK_MSG(chart_changes <= a->chart_count, "%s: %u chart changes for %u charts", what,
                      chart_changes, a->chart_count);
        /* zig-zag jumps once per row at most (a row broken by a hole); spiral
         * only after stepping back */
        if (how == CSSM_ZIGZAG) {
            uint32_t rows = 0;
            for (uint32_t c = 0; c < a->chart_count; c++)
                rows += a->charts[c].h;
            CHECK_MSG(jumps <= rows, "zig-zag: %u jumps for %u rows", jumps, rows);
        }
        if (how == CSSM_SPIRAL)
            CHECK_MSG(jumps * 10 <= a->chart_texels,
                      "spiral: %u jumps for %u chart texels (more than 10 %%)", jumps,
                      a->chart_texels);
        free(seen);
        free(order);
    }
}

static int part_traversal(void)
{
    const char *scenes[2] = {"scenes/cornell_box.gltf", "tests/data/conformance/furnace_050.gltf"};
    for (int k = 0; k < 2; k++) {
        gi_scene *s = load(scenes[k]);
        if (!s)
            return 1;
        for (uint32_t R = 16; R <= 64; R *= 2) {
            cssm_atlas a;
            gi_error err;
            gi_result r = cssm_atlas_build(s, 0.0f, R, 0, &a, &err);
            CHECK_MSG(r == GI_OK, "atlas: %s", err.text);
            if (r != GI_OK)
                continue;
            double texel_area = 0;
            for (uint32_t i = 0; i < a.count; i++)
                texel_area += a.texels[i].area;
            printf("%s atlas %u^2: %u texels (%u in %u charts, %u surface samples), coverage %.3f, "
                   "texel area / "
                   "surface area %.4f\n",
                   scenes[k], R, a.count, a.chart_texels, a.chart_count, a.count - a.chart_texels,
                   a.covered_area / a.surface_area, texel_area / a.surface_area);
            CHECK_MSG(fabs(texel_area / a.surface_area - 1.0) < 0.01,
                      "texel areas sum to %.4f of the surface", texel_area / a.surface_area);
            if (k == 0 && R >= 32)
                CHECK_MSG(a.chart_count >= 5 && a.chart_texels * 3 > 2 * a.count,
                          "Cornell box: %u charts, %u of %u texels", a.chart_count, a.chart_texels,
                          a.count);
            char what[64];
            snprintf(what, sizeof what, "%s %u^2", k ? "sphere" : "cornell", R);
            check_traversals(&a, what);
            cssm_atlas_free(&a);
            if (k == 0 && R == 32 && cssm_atlas_build(s, 0.0f, R, 1, &a, &err) == GI_OK) {
                /* no parametrisation: surface samples at the charts' density (the paper's greedy
                 * case) */
                printf("%s atlas %u^2, samples only: %u texels\n", scenes[k], R, a.count);
                CHECK_MSG(a.chart_count == 0 && a.count > 300, "samples only: %u charts, %u texels",
                          a.chart_count, a.count);
                check_traversals(&a, "cornell samples");
                cssm_atlas_free(&a);
            }
        }
        gi_scene_free(s);
    }
    return 0;
}

/* ----------------------------------------------------------------- tree */

/* A pseudo-random but fixed refine decision per node. */
static int decide(uint32_t node, uint32_t salt)
{
    return (gi_pcg_hash(node * 2654435761u ^ salt) & 3u) != 0;
}

static void recursive(const cssm_tree *t, int32_t i, uint32_t salt, int full, uint32_t *out,
                      uint32_t *n)
{
    const cssm_node *nd = &t->nodes[i];
    if (nd->child >= 0 && (full || decide((uint32_t)i, salt))) {
        /* the right child found independently: the left subtree holds 2 count - 1 nodes */
        int32_t left = nd->child;
        int32_t right = left + (int32_t)(2 * t->nodes[left].count - 1);
        recursive(t, left, salt, full, out, n);
        recursive(t, right, salt, full, out, n);
        return;
    }
    out[(*n)++] = (uint32_t)i;
}

static void stackless(const cssm_tree *t, uint32_t salt, int full, uint32_t *out, uint32_t *n)
{
    int32_t i = 0;
    while (i >= 0) {
        const cssm_node *nd = &t->nodes[i];
        if (nd->child >= 0 && (full || decide((uint32_t)i, salt))) {
            i = nd->child;
            continue;
        }
        out[(*n)++] = (uint32_t)i;
        i = nd->skip;
    }
}

static int part_tree(void)
{
    gi_scene *s = load("scenes/cornell_box.gltf");
    if (!s)
        return 1;
    cssm_atlas a;
    cssm_tree t;
    gi_error err;
    if (cssm_atlas_build(s, 0.0f, 32, 0, &a, &err) != GI_OK ||
        cssm_tree_build(&a, &t, &err) != GI_OK) {
        fprintf(stderr, "FAIL: %s\n", err.text);
        gi_scene_free(s);
        return 1;
    }
    CHECK_MSG(t.count == 2 * a.count - 1, "%u nodes for %u texels", t.count, a.count);
    uint32_t *x = malloc(t.count * sizeof *x), *y = malloc(t.count * sizeof *y);
    for (uint32_t salt = 0; salt < 65; salt++) {
        uint32_t nx = 0, ny = 0;
        int full = salt == 64;
        recursive(&t, 0, salt, full, x, &nx);
        stackless(&t, salt, full, y, &ny);
        CHECK_MSG(nx == ny && !memcmp(x, y, nx * sizeof *x),
                  "salt %u: recursive %u nodes, stack-less %u, differ", salt, nx, ny);
        if (full)
            CHECK_MSG(nx == a.count, "full traversal: %u leaves of %u", nx, a.count);
    }
    /* every texel lies in the spheres of its leaf's ancestors; areas add up */
    uint32_t outside = 0, area_bad = 0;
    for (uint32_t i = 0; i < t.count; i++) {
        const cssm_node *nd = &t.nodes[i];
        double area = 0;
        for (uint32_t k = nd->first; k < nd->first + nd->count; k++) {
            const cssm_texel *tx = &a.texels[t.leaves[k]];
            outside += gi_v3_length(gi_v3_sub(tx->p, nd->c)) > nd->r * 1.0001f;
            area += tx->area;
        }
        area_bad += fabs(area - nd->area) > 1e-4 * area;
    }
    CHECK_MSG(!outside && !area_bad, "%u texels outside their node's sphere, %u node areas off",
              outside, area_bad);
    printf("tree: %u nodes over %u texels; 65 traversals (64 selective, 1 full) equal to the "
           "recursive ones\n",
           t.count, a.count);
    free(x);
    free(y);
    cssm_tree_free(&t);
    cssm_atlas_free(&a);
    gi_scene_free(s);
    return 0;
}

/* ----------------------------------------------------------- visibility */

/* The scene at GI_SOURCE_DIR/rel uploaded to a new GL context
 * (gpu_fixture.h); 0 when any step fails (counted as a failed check). */
static int load_gpu(const char *rel, gi_gpu **gpu, gi_scene **s, gi_gpu_scene **gs)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", GI_SOURCE_DIR, rel);
    return gpu_fixture_load(path, gpu, s, gs) && *gs;
}

/* A scene with the GL context, Embree at t0 (and t1 where it differs:
 * the moved scene), the atlas (32^2) at t0 and its spiral order; the maps
 * `m` are the caller's, and with movers the motion `mo` (motion_open). */
#define MOTION_MAX_MOVERS 2
typedef struct fixture {
    gi_scene *s;
    gi_gpu *gpu;
    gi_gpu_scene *gs;
    gi_rt *rt0, *rt1;
    cssm_atlas a;
    uint32_t *order;
    cssm_maps m;
    cssm_motion mo;
    gi_vec3 c0[MOTION_MAX_MOVERS], c1[MOTION_MAX_MOVERS]; /* the movers' sphere centres at t0, t1 */
    float radius[MOTION_MAX_MOVERS];
} fixture;

/* 0 on success; on failure the message is printed and fixture_close
 * frees what was made. */
static int fixture_open(fixture *f, const char *rel, float t0, float t1)
{
    memset(f, 0, sizeof *f);
    if (!load_gpu(rel, &f->gpu, &f->s, &f->gs))
        return 1;
    gi_error err = {0};
    if (gi_rt_create(f->s, t0, &f->rt0, &err) != GI_OK ||
        (t1 != t0 && gi_rt_create(f->s, t1, &f->rt1, &err) != GI_OK)) {
        fprintf(stderr, "FAIL: set-up: %s\n", err.text);
        return 1;
    }
    if (cssm_atlas_build(f->s, t0, 32, 0, &f->a, &err) != GI_OK) {
        fprintf(stderr, "FAIL: set-up: atlas: %s\n", err.text);
        return 1;
    }
    f->order = cssm_traverse(&f->a, CSSM_SPIRAL);
    if (!f->order) {
        fprintf(stderr, "FAIL: set-up: traverse\n");
        return 1;
    }
    return 0;
}

static void fixture_close(fixture *f)
{
    free(f->order);
    cssm_maps_free(&f->m);
    cssm_motion_free(&f->mo);
    cssm_atlas_free(&f->a);
    gi_rt_free(f->rt0);
    gi_rt_free(f->rt1);
    gi_gpu_scene_free(f->gs);
    gi_gpu_destroy(f->gpu);
    gi_scene_free(f->s);
}

/* A receiver point x on texel i (a random point p of the texel) and the
 * centre of sender j's cube map now: 0 when the two do not face each
 * other (the gathers never ask such pairs). */
static int fixture_pair(const fixture *f, uint32_t j, uint32_t i, uint32_t *rng, gi_vec3 *p,
                        gi_vec3 *x, gi_vec3 *eye)
{
    const cssm_texel *tj = &f->a.texels[j], *ti = &f->a.texels[i];
    gi_vec3 tu, tv;
    gi_onb(ti->n, &tu, &tv);
    float side = sqrtf(ti->area);
    *p =
        gi_v3_add(ti->p, gi_v3_add(gi_v3_scale(tu, (gi_rng_next_float(rng) - 0.5f) * side * 0.9f),
                                   gi_v3_scale(tv, (gi_rng_next_float(rng) - 0.5f) * side * 0.9f)));
    *x = cssm_receiver_point(&f->m, &f->a, *p, ti->n);
    *eye = cssm_motion_eye(f->m.motion, &f->m, j);
    gi_vec3 d = gi_v3_sub(*x, *eye);
    return gi_v3_dot(d, tj->n) > 0.0f && gi_v3_dot(d, ti->n) < 0.0f;
}

/* Whether Embree (rt) finds the segment eye-x free. */
static int fixture_truth(const fixture *f, const gi_rt *rt, gi_vec3 eye, gi_vec3 x)
{
    gi_vec3 d = gi_v3_sub(x, eye);
    float len = gi_v3_length(d);
    d = gi_v3_scale(d, 1.0f / len);
    return !gi_rt_occluded(rt, eye, d, 1e-4f * f->a.diameter, len * (1.0f - 1e-4f));
}

static int part_visibility(void)
{
    fixture f;
    gi_error err = {0};
    if (fixture_open(&f, "scenes/cornell_box.gltf", 0.0f, 0.0f) ||
        cssm_maps_build(f.gs, &f.a, f.order, 32, NULL, &f.m, &err) != GI_OK) {
        if (f.order)
            fprintf(stderr, "FAIL: set-up: %s\n", err.text);
        fixture_close(&f);
        return 1;
    }
    const cssm_atlas *a = &f.a;
    const float bias = 0.004f * a->diameter; /* the plugin's default */
    const int pairs = 20000;
    int agree = 0, agree_pcf = 0, visible = 0, tried = 0, false_lit = 0, false_shadow = 0;
    uint32_t rng = gi_rng_init(7, 0, 0x715u);
    while (tried < pairs) {
        uint32_t j = gi_rng_next_u32(&rng) % a->count, i = gi_rng_next_u32(&rng) % a->count;
        gi_vec3 p, x, eye;
        if (i == j || !fixture_pair(&f, j, i, &rng, &p, &x, &eye))
            continue;
        tried++;
        int truth = fixture_truth(&f, f.rt0, eye, x);
        int v = cssm_visible(&f.m, j, x, bias, 0) > 0.5f;
        float vp = cssm_visible(&f.m, j, x, bias, 1);
        visible += truth;
        agree += v == truth;
        false_lit += v && !truth;
        false_shadow += !v && truth;
        agree_pcf += (vp > 0.5f) == truth;
    }
    double rate = (double)agree / tried, rate_pcf = (double)agree_pcf / tried;
    double always = (double)visible / tried, never = 1.0 - always;
    printf("visibility (Cornell box, atlas 32^2, 6 x 32 x 32, spiral, %d facing pairs): CSSM "
           "agrees with Embree on "
           "%.2f %% (PCF, thresholded at 1/2: %.2f %%); always-visible %.2f %%, never-visible %.2f "
           "%%\n",
           tried, 100 * rate, 100 * rate_pcf, 100 * always, 100 * never);
    printf("errors: %.2f %% lit where Embree finds an occluder, %.2f %% shadowed where it finds "
           "none\n",
           100.0 * false_lit / tried, 100.0 * false_shadow / tried);
    double trivial = always > never ? always : never;
    /* measured 95.3 % (PCF 95.9 %) against 68.8 % for always-visible: the
     * misses are split between both kinds, the discretisation of 32 x 32
     * faces and of the atlas (Fig. 14) */
    CHECK_MSG(rate >= 0.94, "CSSM agreement %.4f below 0.94", rate);
    CHECK_MSG(rate >= trivial + 0.20,
              "CSSM agreement %.4f not 20 points above the best trivial answer %.4f", rate,
              trivial);
    CHECK_MSG(rate_pcf >= 0.94, "PCF agreement %.4f below 0.94", rate_pcf);
    fixture_close(&f);
    return 0;
}

/* ----------------------------------------------------------------- hull */

/* The 8 corners of the box [-h, h]^3 plus its centre and face centres
 * (inner points the hull must drop). */
static void box_points(float h, float *pts)
{
    for (int k = 0; k < 8; k++) {
        pts[3 * k + 0] = (k & 1) ? h : -h;
        pts[3 * k + 1] = (k & 2) ? h : -h;
        pts[3 * k + 2] = (k & 4) ? h : -h;
    }
    float inner[7][3] = {{0, 0, 0},  {h, 0, 0}, {-h, 0, 0}, {0, h, 0},
                         {0, -h, 0}, {0, 0, h}, {0, 0, -h}};
    memcpy(pts + 24, inner, sizeof inner);
}

static void translate(float m[16], float x, float y, float z)
{
    gi_mat4_identity(m);
    m[12] = x, m[13] = y, m[14] = z;
}

static int part_hull(void)
{
    gi_error err;
    float pts[45];
    box_points(0.5f, pts);
    gi_hull box;
    if (gi_hull_build(pts, 15, &box, &err) != GI_OK) {
        fprintf(stderr, "FAIL: %s\n", err.text);
        return 1;
    }
    CHECK_MSG(box.vertex_count == 8, "box hull: %u vertices, expected its 8 corners",
              box.vertex_count);
    CHECK_MSG(box.face_count == 12, "box hull: %u faces, expected 12 triangles", box.face_count);
    CHECK_MSG(gi_hull_contains(&box, gi_v3(0.49f, -0.49f, 0.2f), 0.0f) &&
                  !gi_hull_contains(&box, gi_v3(0.51f, 0, 0), 0.0f),
              "box hull: containment");
    float I[16], M[16];
    gi_mat4_identity(I);
    /* unit boxes: overlapping, touching, separated by a gap of 1e-3 and 1 */
    struct {
        float dx, dy, dz, gap; /* gap: the exact distance (0 when they overlap or touch) */
        int overlap;
    } cases[] = {{0.5f, 0.3f, 0.2f, 0.0f, 1},          {0.999f, 0.0f, 0.0f, 0.0f, 1},
                 {1.0f, 1.0f, 1.0f, 0.0f, 1},          {1.001f, 0.0f, 0.0f, 1e-3f, 0},
                 {0.0f, -1.001f, 0.5f, 1e-3f, 0},      {2.0f, 0.0f, 0.0f, 1.0f, 0},
                 {1.001f, 1.001f, 0.0f, 1.4142e-3f, 0}};
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        translate(M, cases[k].dx, cases[k].dy, cases[k].dz);
        int o = gi_hull_overlap(&box, I, &box, M, 0.0f);
        double d = gi_hull_distance(&box, I, &box, M);
        CHECK_MSG(o == cases[k].overlap, "boxes at (%g, %g, %g): overlap %d, expected %d",
                  cases[k].dx, cases[k].dy, cases[k].dz, o, cases[k].overlap);
        CHECK_MSG(fabs(d - cases[k].gap) <= 1e-5 + 1e-4 * cases[k].gap,
                  "boxes at (%g, %g, %g): distance %.7g, expected %.7g", cases[k].dx, cases[k].dy,
                  cases[k].dz, d, cases[k].gap);
    }
    /* a box turned 45 degrees about z: its edge reaches 0.5 sqrt(2) from its centre */
    float R[16], T[16];
    float q[4] = {0.0f, 0.0f, sinf(GI_PI / 8.0f), cosf(GI_PI / 8.0f)}, one[3] = {1, 1, 1};
    for (int side = -1; side <= 1; side += 2) {
        float t[3] = {0.5f + 0.5f * sqrtf(2.0f) + (float)side * 1e-3f, 0.3f, 0.0f};
        gi_mat4_trs(T, t, q, one);
        memcpy(R, T, sizeof R);
        int o = gi_hull_overlap(&box, I, &box, R, 0.0f);
        CHECK_MSG(o == (side < 0), "turned box %s by 1e-3: overlap %d",
                  side < 0 ? "reaching in" : "short", o);
    }
    /* a flat set (a quad): qhull is asked again with joggled input */
    float quad[12] = {-1, 0, -1, 1, 0, -1, 1, 0, 1, -1, 0, 1};
    gi_hull flat;
    if (gi_hull_build(quad, 4, &flat, &err) != GI_OK) {
        fprintf(stderr, "FAIL: flat: %s\n", err.text);
        gi_hull_free(&box);
        return 1;
    }
    translate(M, 0.2f, 0.501f, 0.1f);
    CHECK_MSG(!gi_hull_overlap(&flat, I, &box, M, 0.0f), "box 1e-3 above a quad: overlap");
    translate(M, 0.2f, 0.499f, 0.1f);
    CHECK_MSG(gi_hull_overlap(&flat, I, &box, M, 0.0f),
              "box reaching 1e-3 through a quad: no overlap");
    /* point clouds on spheres (radii r1, r2): hulls lie inside the spheres and,
     * with 400 points, hold the concentric spheres of 0.9 r */
    uint32_t rng = gi_rng_init(3, 0, 0x411u);
    int wrong = 0, n = 0;
    for (int trial = 0; trial < 200; trial++) {
        float r1 = 0.2f + gi_rng_next_float(&rng), r2 = 0.2f + gi_rng_next_float(&rng);
        float cloud[2][400 * 3];
        float rr[2] = {r1, r2};
        for (int c = 0; c < 2; c++)
            for (int k = 0; k < 400; k++) {
                gi_vec3 w =
                    gi_sample_uniform_sphere(gi_rng_next_float(&rng), gi_rng_next_float(&rng));
                cloud[c][3 * k] = rr[c] * w.x, cloud[c][3 * k + 1] = rr[c] * w.y,
                             cloud[c][3 * k + 2] = rr[c] * w.z;
            }
        gi_hull h1, h2;
        if (gi_hull_build(cloud[0], 400, &h1, &err) != GI_OK ||
            gi_hull_build(cloud[1], 400, &h2, &err) != GI_OK) {
            fprintf(stderr, "FAIL: cloud: %s\n", err.text);
            return 1;
        }
        gi_vec3 dir = gi_sample_uniform_sphere(gi_rng_next_float(&rng), gi_rng_next_float(&rng));
        /* centres apart by more than r1 + r2 (separated) or less than 0.9 (r1 + r2) (overlapping)
         */
        int sep = trial & 1;
        float dist = sep ? (r1 + r2) * (1.0f + 0.001f + 0.3f * gi_rng_next_float(&rng))
                         : 0.9f * (r1 + r2) * (1.0f - 0.001f - 0.9f * gi_rng_next_float(&rng));
        translate(M, dir.x * dist, dir.y * dist, dir.z * dist);
        int o = gi_hull_overlap(&h1, I, &h2, M, 0.0f);
        wrong += o == sep;
        n++;
        gi_hull_free(&h1);
        gi_hull_free(&h2);
    }
    printf("hull: box 8 vertices / 12 faces; 7 box pairs and 2 turned-box pairs (gaps 1e-3) right; "
           "quad +-1e-3 right; "
           "%d of %d sphere-cloud pairs wrong\n",
           wrong, n);
    CHECK_MSG(wrong == 0, "%d of %d sphere-cloud pairs judged wrong", wrong, n);
    /* bad input: a clear error, no crash */
    float bad[3] = {0.0f, NAN, 0.0f};
    gi_hull none;
    CHECK_MSG(gi_hull_build(bad, 1, &none, &err) == GI_ERR_INVALID_ARGUMENT,
              "a NaN point accepted");
    CHECK_MSG(gi_hull_build(NULL, 0, &none, &err) == GI_ERR_INVALID_ARGUMENT, "no points accepted");
    gi_hull_free(&flat);
    gi_hull_free(&box);
    return 0;
}

/* --------------------------------------------------------------- motion */

/* 1 when the segment a-b passes within r of c. */
static int segment_near(gi_vec3 a, gi_vec3 b, gi_vec3 c, float r)
{
    gi_vec3 ab = gi_v3_sub(b, a);
    float l = gi_v3_dot(ab, ab), t = l > 0.0f ? gi_v3_dot(gi_v3_sub(c, a), ab) / l : 0.0f;
    t = t < 0.0f ? 0.0f : t > 1.0f ? 1.0f : t;
    gi_vec3 d = gi_v3_sub(gi_v3_add(a, gi_v3_scale(ab, t)), c);
    return gi_v3_dot(d, d) <= r * r;
}

/* Loads `rel`, which must have `movers` animated objects, and makes what
 * prepare() makes at t0 (cssm_hrc.c build_moving: the static CSSM without
 * the movers, each mover's CSSM and CSM); the movers are left at t0.
 * Prints each mover's way under `tag`. 0 on success. */
static int motion_open(fixture *f, const char *rel, uint32_t movers, float t0, float t1,
                       const char *tag)
{
    if (fixture_open(f, rel, t0, t1))
        return 1;
    uint32_t animated = 0;
    cssm_motion_find(f->s, &animated);
    if (animated != movers || movers > MOTION_MAX_MOVERS) {
        fprintf(stderr, "FAIL: set-up: %s has %u animated objects, expected %u\n", rel, animated,
                movers);
        return 1;
    }
    gi_error err = {0};
    if (cssm_motion_init(f->s, t0, &f->a, &f->mo, &err) != GI_OK) {
        fprintf(stderr, "FAIL: set-up: %s\n", err.text);
        return 1;
    }
    cssm_build_opts so = {.skip_objects = f->mo.object_moves, .dont_care = f->mo.on_moving};
    if (cssm_maps_build_ex(f->gs, &f->a, f->order, 32, &so, NULL, &f->m, &err) != GI_OK ||
        cssm_motion_build_maps(&f->mo, f->gs, &f->a, f->order, 32, NULL, &err) != GI_OK) {
        fprintf(stderr, "FAIL: set-up: %s\n", err.text);
        return 1;
    }
    f->m.motion = &f->mo;
    if (f->mo.mover_count != movers) {
        fprintf(stderr, "FAIL: set-up: %u movers, expected %u\n", f->mo.mover_count, movers);
        return 1;
    }
    for (uint32_t k = 0; k < movers; k++) {
        float sph[4], T[16];
        const uint32_t o = f->mo.movers[k].object;
        gi_mesh_object_sphere(f->s, o, sph);
        f->radius[k] = sph[3];
        gi_scene_object_transform(f->s, o, t0, T);
        f->c0[k] = gi_mat4_point(T, gi_v3(sph[0], sph[1], sph[2]));
        gi_scene_object_transform(f->s, o, t1, T);
        f->c1[k] = gi_mat4_point(T, gi_v3(sph[0], sph[1], sph[2]));
        printf("%s: mover %u '%s' moves %.3f (radius %.3f) from t = %g to %g s\n", tag, k,
               f->s->objects[o].name, gi_v3_length(gi_v3_sub(f->c1[k], f->c0[k])), f->radius[k], t0,
               t1);
    }
    return 0;
}

/* Kinds of pairs: static-static, mover sender, mover receiver, both ends
 * on one mover, ends on two movers. */
#define MOTION_KINDS 5
static int motion_kind(const cssm_motion *mo, uint32_t j, uint32_t i)
{
    int32_t gj = mo->mover_of[mo->object_of[j]], gi = mo->mover_of[mo->object_of[i]];
    return gj < 0 ? (gi < 0 ? 0 : 2) : gi < 0 ? 1 : gi == gj ? 3 : 4;
}

/* Agreement of CSSM visibility with Embree on the moved scene, in all and
 * per kind, and on the pairs whose visibility the motion changed. */
typedef struct motion_tally {
    int tried, agree, visible, unmoved, affected, agree_aff, vis_aff;
    int kinds[MOTION_KINDS], kind_agree[MOTION_KINDS], kind_vis[MOTION_KINDS];
} motion_tally;

/* 1 when the segment eye-x passes within a mover's sphere at t0 or t1. */
static int motion_near(const fixture *f, gi_vec3 eye, gi_vec3 x)
{
    int near = 0;
    for (uint32_t k = 0; k < f->mo.mover_count; k++)
        near |= segment_near(eye, x, f->c1[k], f->radius[k]) ||
                segment_near(eye, x, f->c0[k], f->radius[k]);
    return near;
}

/* Counts pair (j, i) of the given kind: CSSM visibility with D T^-1 (every
 * other pair as a pixel through its proxy texel, the rest as texel
 * receivers) against Embree on the moved scene, and the unmoved scene's
 * exact visibility. */
static void motion_judge(const fixture *f, motion_tally *t, int kind, uint32_t j, uint32_t i,
                         gi_vec3 p, gi_vec3 x, gi_vec3 eye)
{
    const cssm_texel *ti = &f->a.texels[i];
    const float bias = 0.004f * f->a.diameter;
    t->tried++;
    t->kinds[kind]++;
    int truth = fixture_truth(f, f->rt1, eye, x), before = fixture_truth(f, f->rt0, eye, x);
    cssm_receiver rc = {.x = x, .n = ti->n, .self = (int32_t)i};
    if (t->tried & 1) {
        int32_t proxy = cssm_motion_proxy(&f->mo, f->s, &f->a, ti->triangle, p, ti->n);
        rc.self = -1;
        rc.proxy1 = proxy >= 0 ? (uint32_t)proxy + 1u : 0u;
        rc.moving = cssm_motion_mover1(&f->mo, f->s, ti->triangle);
    }
    int v = cssm_visible_rc(&f->m, j, &rc, bias, 0) > 0.5f;
    t->visible += truth;
    t->agree += v == truth;
    t->unmoved += before == truth;
    t->kind_agree[kind] += v == truth;
    t->kind_vis[kind] += truth;
    if (before != truth) {
        t->affected++;
        t->agree_aff += v == truth;
        t->vis_aff += truth;
    }
}

/* Prints the tally and checks it: `pairs` pairs found, agreement at least
 * 90 % and MOTION_MARGIN above the best trivial answer (always visible,
 * never visible, the unmoved scene), MOTION_MARGIN_AFFECTED above it on
 * the pairs the motion changed, and 10 points above it for every kind
 * the sample reaches 200 times. */
static void motion_report(const char *tag, const motion_tally *t, int pairs)
{
    static const char *const kind_name[MOTION_KINDS] = {
        "static-static", "mover sender", "mover receiver", "one mover", "two movers"};
    double rate = (double)t->agree / t->tried, always = (double)t->visible / t->tried,
           never = 1.0 - always;
    double stale = (double)t->unmoved / t->tried;
    double rate_aff = t->affected ? (double)t->agree_aff / t->affected : 0.0;
    double always_aff = t->affected ? (double)t->vis_aff / t->affected : 0.0;
    printf("%s: %d facing pairs near a mover: agreement with Embree on the moved scene %.2f %%; "
           "always-visible "
           "%.2f %%, never-visible %.2f %%, the unmoved scene's exact visibility %.2f %%\n",
           tag, t->tried, 100 * rate, 100 * always, 100 * never, 100 * stale);
    printf(
        "%s: on the %d pairs whose visibility the motion changed: %.2f %% (always-visible %.2f %%, "
        "never-visible %.2f %%, unmoved 0 %%)\n",
        tag, t->affected, 100 * rate_aff, 100 * always_aff, 100 * (1.0 - always_aff));
    for (int k = 0; k < MOTION_KINDS; k++) {
        if (!t->kinds[k])
            continue;
        double rk = (double)t->kind_agree[k] / t->kinds[k],
               ak = (double)t->kind_vis[k] / t->kinds[k];
        printf("%s: %-14s %5d pairs: %.2f %% (always-visible %.2f %%, never-visible %.2f %%)\n",
               tag, kind_name[k], t->kinds[k], 100 * rk, 100 * ak, 100 * (1.0 - ak));
        /* every case of the combination (motion.h) that the sample reaches often enough */
        if (t->kinds[k] >= 200)
            CHECK_MSG(rk >= fmax(ak, 1.0 - ak) + 0.10,
                      "%s: agreement %.4f not 10 points above the best trivial answer",
                      kind_name[k], rk);
    }
    double trivial = fmax(fmax(always, never), stale);
    CHECK_MSG(t->tried == pairs, "only %d pairs found", t->tried);
    CHECK_MSG(rate >= 0.90, "agreement %.4f below 0.90", rate);
    CHECK_MSG(rate >= trivial + MOTION_MARGIN,
              "agreement %.4f not %.2f above the best trivial answer %.4f", rate, MOTION_MARGIN,
              trivial);
    CHECK_MSG(t->affected >= 100, "only %d pairs changed with the motion: the test cannot judge",
              t->affected);
    CHECK_MSG(rate_aff >= fmax(always_aff, 1.0 - always_aff) + MOTION_MARGIN_AFFECTED,
              "on the changed pairs agreement %.4f not %.2f above the best trivial answer",
              rate_aff, MOTION_MARGIN_AFFECTED);
}

/* §3.3 with one mover: the moving Cornell box, everything made at t0, the
 * bunny moved to t1 by cssm_motion_place alone (nothing made again);
 * facing texel / point pairs the bunny can matter to (an end on it, or
 * the segment passing within its sphere now or before) against Embree on
 * the moved scene. */
static int part_motion(void)
{
    const float t0 = 0.0f, t1 = 1.5f;
    fixture f;
    if (motion_open(&f, "scenes/cornell_moving.gltf", 1, t0, t1, "motion")) {
        fixture_close(&f);
        return 1;
    }
    cssm_motion_place(&f.mo, f.s, t1, &f.a);
    uint32_t bad = cssm_motion_check(&f.mo, f.s, t1);
    printf("motion: at t = %g s the bunny's hull overlaps %u hulls, %u objects reach into it%s%s\n",
           t1, f.mo.overlaps, bad, bad ? ": " : "", f.mo.what);
    CHECK_MSG(bad == 0, "the hull condition fails in the test scene: %s", f.mo.what);
    const int pairs = 6000;
    motion_tally t = {0};
    uint32_t rng = gi_rng_init(11, 0, 0x3a3u);
    int guard = 0;
    while (t.tried < pairs && guard++ < 4000000) {
        uint32_t j = gi_rng_next_u32(&rng) % f.a.count, i = gi_rng_next_u32(&rng) % f.a.count;
        gi_vec3 p, x, eye;
        if (i == j || !fixture_pair(&f, j, i, &rng, &p, &x, &eye))
            continue;
        int kind = motion_kind(&f.mo, j, i);
        if (kind == 0 && !motion_near(&f, eye, x))
            continue;
        motion_judge(&f, &t, kind, j, i, p, x, eye);
    }
    motion_report("motion", &t, pairs);
    fixture_close(&f);
    return 0;
}

/* Two moving objects (§3.3 for every object): the bunny and a box of
 * plugins/cssm_hrc/data/cornell_moving2.gltf (plugins/cssm_hrc/data/make_cornell_moving2.py),
 * everything made at t0, both moved to t1 by cssm_motion_place alone, facing texel / point pairs
 * that a mover can matter to against Embree on the moved scene; the per-pair hull check, also with
 * the box put onto the bunny. */
static int part_motion2(void)
{
    const float t0 = 0.0f, t1 = 1.6f; /* the tall block then hides the box from part of the bunny */
    fixture f;
    if (motion_open(&f, "plugins/cssm_hrc/data/cornell_moving2.gltf", 2, t0, t1, "motion2")) {
        fixture_close(&f);
        return 1;
    }
    cssm_motion *mo = &f.mo;
    cssm_motion_place(mo, f.s, t1, &f.a);
    uint32_t bad = cssm_motion_check(mo, f.s, t1);
    printf("motion2: at t = %g s %u of %u object pairs with a mover overlap, %u intrude%s%s\n", t1,
           mo->overlaps, mo->pair_count, bad, bad ? ": " : "", mo->what);
    CHECK_MSG(bad == 0, "the hull condition fails in the test scene: %s", mo->what);
    CHECK_MSG(mo->pair_count == 2 * (f.s->object_count - 2) + 1, "%u pairs", mo->pair_count);
    const int pairs = 6000;
    motion_tally t = {0};
    uint32_t rng = gi_rng_init(13, 0, 0x3a4u);
    int guard = 0;
    while (t.tried < pairs && guard++ < 4000000) {
        /* the last TWO_MOVERS pairs between the two movers (rare in a
         * uniform draw: the box has few texels) */
        const int between = t.tried >= pairs - TWO_MOVERS;
        uint32_t j = gi_rng_next_u32(&rng) % f.a.count, i = gi_rng_next_u32(&rng) % f.a.count;
        if (between) {
            uint32_t oj = mo->movers[gi_rng_next_u32(&rng) & 1].object;
            uint32_t oi = mo->movers[0].object + mo->movers[1].object - oj;
            j = mo->obj_texels[mo->obj_first[oj] +
                               gi_rng_next_u32(&rng) % (mo->obj_first[oj + 1] - mo->obj_first[oj])];
            i = mo->obj_texels[mo->obj_first[oi] +
                               gi_rng_next_u32(&rng) % (mo->obj_first[oi + 1] - mo->obj_first[oi])];
        }
        gi_vec3 p, x, eye;
        if (i == j || !fixture_pair(&f, j, i, &rng, &p, &x, &eye))
            continue;
        int kind = motion_kind(mo, j, i);
        if ((kind == 0 && !motion_near(&f, eye, x)) || (kind == 4) != between)
            continue;
        motion_judge(&f, &t, kind, j, i, p, x, eye);
    }
    motion_report("motion2", &t, pairs);
    CHECK_MSG(t.kinds[4] == TWO_MOVERS, "only %d pairs between the two movers", t.kinds[4]);
    /* per pair: the box put where the bunny is overlaps it and reaches into
     * its hull; the other pairs keep their state */
    unsigned char before_state[64];
    uint32_t np = mo->pair_count < 64 ? mo->pair_count : 64, mover_pair = UINT32_MAX;
    for (uint32_t k = 0; k < np; k++) {
        before_state[k] = (unsigned char)(mo->pairs[k].overlap | mo->pairs[k].intrusion << 1);
        if (mo->object_moves[mo->pairs[k].a] && mo->object_moves[mo->pairs[k].b])
            mover_pair = k;
    }
    CHECK_MSG(mover_pair < np && !mo->pairs[mover_pair].overlap,
              "the two movers' pair is missing or overlaps at t1");
    memcpy(mo->movers[1].T, mo->movers[0].T, sizeof mo->movers[1].T);
    bad = cssm_motion_check(mo, f.s, t1);
    printf("motion2: the box put onto the bunny: %u pairs overlap, %u intrude: %s\n", mo->overlaps,
           bad, mo->what);
    CHECK_MSG(mover_pair < np && mo->pairs[mover_pair].overlap && mo->pairs[mover_pair].intrusion,
              "the overlapping movers are not reported");
    for (uint32_t k = 0; k < np; k++) {
        if (k == mover_pair ||
            mo->object_moves[mo->pairs[k].a] + mo->object_moves[mo->pairs[k].b] != 1)
            continue;
        /* a pair of a static object and the bunny keeps its state */
        if (mo->mover_of[mo->pairs[k].a] == 0 || mo->mover_of[mo->pairs[k].b] == 0)
            CHECK_MSG(before_state[k] == (mo->pairs[k].overlap | mo->pairs[k].intrusion << 1),
                      "pair %u changed", k);
    }
    fixture_close(&f);
    return 0;
}

/* -------------------------------------------------------------- furnace */

static int part_furnace(int compact)
{
    gi_gpu *gpu = NULL;
    gi_scene *s = NULL;
    gi_gpu_scene *gs = NULL;
    if (!load_gpu("tests/data/conformance/furnace_050.gltf", &gpu, &s, &gs))
        return 1;
    cssm_atlas a;
    cssm_maps m;
    cssm_tree t;
    gi_error err;
    cssm_ctree ct = {0};
    if (cssm_atlas_build(s, 0.0f, 24, 0, &a, &err) != GI_OK ||
        cssm_tree_build(&a, &t, &err) != GI_OK ||
        (compact && cssm_ctree_build(&t, &a, &ct, &err) != GI_OK)) {
        fprintf(stderr, "FAIL: %s\n", err.text);
        return 1;
    }
    const char *how = compact ? " (nodes=compact)" : "";
    uint32_t *order = cssm_traverse(&a, CSSM_GREEDY);
    if (!order || cssm_maps_build(gs, &a, order, 16, NULL, &m, &err) != GI_OK) {
        fprintf(stderr, "FAIL: %s\n", order ? err.text : "traverse");
        return 1;
    }
    const double rho = 0.5, Le = 1.0;
    float *L = malloc(3 * a.count * sizeof *L), *NL = malloc(3 * t.count * sizeof *NL);
    cssm_gather_opts o = {.threshold = 0.1f,
                          .max_cut = 1024,
                          /* the plugin's defaults */ .clamp = 0.02f * a.diameter,
                          .bias = 0.004f * a.diameter};
    printf("furnace: %u surface samples on the sphere\n", a.count);
    for (uint32_t n = 1; n <= 3; n++) {
        cssm_gather_stats st = {0};
        if (cssm_solve_ex(&t, compact ? &ct : NULL, &a, &m, &o, n, NULL, NULL, L, NL, &st, &err) !=
            GI_OK) {
            fprintf(stderr, "FAIL: %s\n", err.text);
            return 1;
        }
        double atlas_expect = 0, pixel_expect = 0;
        for (uint32_t k = 0; k <= n; k++)
            atlas_expect += Le * pow(rho, k);
        pixel_expect = atlas_expect + Le * pow(rho, n + 1);
        double mean = 0, worst = 0;
        for (uint32_t i = 0; i < a.count; i++) {
            double v = (L[3 * i] + L[3 * i + 1] + L[3 * i + 2]) / 3.0;
            mean += v;
            worst = fmax(worst, fabs(v / atlas_expect - 1.0));
        }
        mean /= a.count;
        /* final gather at points just inside the sphere, seen from the centre */
        double pmean = 0;
        uint32_t rng = gi_rng_init(n, 0, 0xf00u);
        const int P = 200;
        for (int k = 0; k < P; k++) {
            const cssm_texel *x = &a.texels[gi_rng_next_u32(&rng) % a.count];
            cssm_receiver rc = {
                .x = cssm_receiver_point(&m, &a, x->p, x->n), .n = x->n, .self = -1, .glossy = 1};
            for (int c = 0; c < 3; c++)
                rc.kd[c] = (float)rho;
            rc.wo = x->n;
            float out[3];
            if (compact)
                cssm_cgather(&ct, &a, &m, &rc, &o, out, NULL);
            else
                cssm_gather(&t, &a, &m, NL, &rc, &o, out, NULL);
            pmean += Le + (out[0] + out[1] + out[2]) / 3.0;
        }
        pmean /= P;
        printf("furnace%s n = %u: atlas mean %.4f (expected %.4f, %+.2f %%, worst texel %.2f %%), "
               "final gather %.4f "
               "(expected %.4f, %+.2f %%); emission only %+.1f %%, black -100 %%; mean cut %.1f\n",
               how, n, mean, atlas_expect, 100 * (mean / atlas_expect - 1), 100 * worst, pmean,
               pixel_expect, 100 * (pmean / pixel_expect - 1), 100 * (Le / pixel_expect - 1),
               (double)st.nodes / st.receivers);
        CHECK_MSG(fabs(mean / atlas_expect - 1) <= 0.02, "n = %u: atlas off by more than 2 %%", n);
        CHECK_MSG(fabs(pmean / pixel_expect - 1) <= 0.02,
                  "n = %u: final gather off by more than 2 %%", n);
        if (compact) /* the Monte Carlo gather reads no hierarchy */
            continue;
        /* the same final gather by Monte Carlo from the atlas as a pdf (Sec. 4.6) */
        double *cdf = malloc((a.count + 1) * sizeof *cdf);
        double mc = 0;
        cssm_pdf_build(&a, L, cdf);
        for (int k = 0; k < P; k++) {
            const cssm_texel *x = &a.texels[gi_rng_next_u32(&rng) % a.count];
            cssm_receiver rc = {
                .x = cssm_receiver_point(&m, &a, x->p, x->n), .n = x->n, .self = -1};
            for (int c = 0; c < 3; c++)
                rc.kd[c] = (float)rho;
            cssm_gather_opts om = o;
            om.rng = &rng;
            float out[3];
            cssm_gather_mc(&a, &m, L, cdf, 64, &rc, &om, out);
            mc += Le + (out[0] + out[1] + out[2]) / 3.0;
        }
        mc /= P;
        free(cdf);
        printf(
            "furnace n = %u: Monte Carlo final gather (64 texels x %d receivers) %.4f (%+.2f %%)\n",
            n, P, mc, 100 * (mc / pixel_expect - 1));
        CHECK_MSG(fabs(mc / pixel_expect - 1) <= 0.02,
                  "n = %u: Monte Carlo final gather off by more than 2 %%", n);
    }
    cssm_ctree_free(&ct);
    free(L);
    free(NL);
    free(order);
    cssm_maps_free(&m);
    cssm_tree_free(&t);
    cssm_atlas_free(&a);
    gi_gpu_scene_free(gs);
    gi_gpu_destroy(gpu);
    gi_scene_free(s);
    return 0;
}

/* Textured albedo in the atlas: the checker ground of
 * scenes/teapot_plane.glb. Its texels carry the texture (both checker
 * colours appear), and their area-weighted mean albedo matches the mean
 * of the textured albedo at 20 000 random points of the same triangles
 * (uvs interpolated here) within 5 %, where the untextured factor is off
 * by more than 50 %. */
static int part_texture(void)
{
    gi_scene *s = load("scenes/teapot_plane.glb");
    if (!s)
        return 1;
    gi_error err;
    cssm_atlas a;
    if (cssm_atlas_build(s, 0.0f, 32, 0, &a, &err) != GI_OK) {
        fprintf(stderr, "FAIL: %s\n", err.text);
        return 1;
    }
    double sum = 0.0, area = 0.0, factor = 0.0;
    float lo = 1e9f, hi = -1e9f;
    uint32_t textured = 0;
    for (uint32_t i = 0; i < a.count; i++) {
        const cssm_texel *x = &a.texels[i];
        const gi_material *m = &s->materials[s->vertices[s->indices[3 * x->triangle]].material];
        if (m->albedo_texture < 0)
            continue;
        textured++;
        sum += x->area * x->albedo[1];
        area += x->area;
        factor = m->albedo[1];
        lo = fminf(lo, x->albedo[1]), hi = fmaxf(hi, x->albedo[1]);
    }
    /* the same mean at random points of the textured triangles, by area */
    double ref = 0.0, ref_area = 0.0;
    uint32_t rng = gi_rng_init(5, 0, 0x7e7u);
    for (uint32_t tri = 0; tri < s->triangle_count; tri++) {
        const uint32_t *idx = &s->indices[3 * tri];
        const gi_material *m = &s->materials[s->vertices[idx[0]].material];
        if (m->albedo_texture < 0)
            continue;
        gi_vec3 p[3];
        gi_scene_triangle_world(s, tri, 0.0f, p);
        float A = 0.5f * gi_v3_length(gi_v3_cross(gi_v3_sub(p[1], p[0]), gi_v3_sub(p[2], p[0])));
        const int n = 20000 / 2; /* the ground is two triangles or more: points per triangle */
        double acc = 0.0;
        for (int k = 0; k < n; k++) {
            float u = gi_rng_next_float(&rng), v = gi_rng_next_float(&rng);
            if (u + v > 1.0f)
                u = 1.0f - u, v = 1.0f - v;
            float uv[2], al[3];
            for (int c = 0; c < 2; c++)
                uv[c] = (1.0f - u - v) * s->vertices[idx[0]].uv[c] + u * s->vertices[idx[1]].uv[c] +
                        v * s->vertices[idx[2]].uv[c];
            gi_scene_albedo(s, s->vertices[idx[0]].material, uv, al);
            acc += al[1];
        }
        ref += A * acc / n;
        ref_area += A;
    }
    double mean = area > 0 ? sum / area : 0.0, want = ref_area > 0 ? ref / ref_area : 0.0;
    printf("texture: %u textured texels, albedo (green) %.3f .. %.3f, area mean %.4f; random "
           "points %.4f (%+.2f %%); "
           "the untextured factor %.3f (%+.1f %%)\n",
           textured, lo, hi, mean, want, 100.0 * (mean / want - 1.0), factor,
           100.0 * (factor / want - 1.0));
    CHECK_MSG(textured >= 100, "only %u textured texels", textured);
    CHECK_MSG(hi > lo + 0.2f, "the checker does not show in the atlas (%.3f .. %.3f)", lo, hi);
    CHECK_MSG(fabs(mean / want - 1.0) <= 0.05, "mean textured albedo %.4f, random points %.4f",
              mean, want);
    CHECK_MSG(fabs(factor / want - 1.0) > 0.5,
              "the test cannot tell: the factor is near the textured mean");
    cssm_atlas_free(&a);
    gi_scene_free(s);
    return 0;
}

/* ------------------------------------------------------ compact nodes */

/* Node i's view of the float tree (no light). */
static cssm_node_view float_view(const cssm_tree *t, int32_t i)
{
    const cssm_node *nd = &t->nodes[i];
    cssm_node_view v = {.c = nd->c,
                        .r = nd->r,
                        .p = nd->centroid,
                        .n = nd->n,
                        .cos_cone = nd->cos_cone,
                        .area = nd->area,
                        .child = nd->child,
                        .skip = nd->skip,
                        .first = nd->first,
                        .count = nd->count,
                        .rep = nd->rep};
    return v;
}

/* The skip-pointer traversal of part_tree over packed nodes. */
static void stackless_compact(const cssm_ctree *ct, uint32_t salt, int full, uint32_t *out,
                              uint32_t *n)
{
    int32_t i = 0;
    while (i >= 0) {
        cssm_node_view v;
        cssm_ctree_view(ct, (uint32_t)i, &v);
        if (v.child >= 0 && (full || decide((uint32_t)i, salt))) {
            i = v.child;
            continue;
        }
        out[(*n)++] = (uint32_t)i;
        i = v.skip;
    }
}

/* Angle between two directions, accurate near 0. */
static float angle_between(gi_vec3 a, gi_vec3 b)
{
    a = gi_v3_normalize(a), b = gi_v3_normalize(b);
    return 2.0f * atan2f(gi_v3_length(gi_v3_sub(a, b)), gi_v3_length(gi_v3_add(a, b)));
}

static float rnd_log(uint32_t *rng, float lo, float hi)
{
    return lo * powf(hi / lo, gi_rng_next_float(rng));
}

/* §4.2.1 encoding: random nodes round trip within the stated bounds
 * (centre half a step per axis; sphere and cone of the decoded node hold
 * the true ones, at most one code larger; area within half a log step;
 * intensity within 1/31.5 of its largest channel, zero on average;
 * pointers exact); on the
 * Cornell box tree: every texel inside its node's decoded sphere and cone,
 * pointers equal to the float tree's, skip-pointer traversals over packed
 * nodes equal to those over float nodes, the packed pull against the float
 * pull, and the log radius code against a linear one. */
static int part_compact(void)
{
    gi_error err;
    cssm_ctree ct;
    const float lo[3] = {-1.0f, 0.0f, 2.0f}, hi[3] = {3.0f, 0.5f, 2.25f};
    const float r_lo = 1e-3f, r_hi = 4.0f, a_lo = 1e-5f, a_hi = 10.0f;
    const uint32_t N = 20000;
    if (cssm_ctree_setup(&ct, N, lo, hi, r_lo, r_hi, a_lo, a_hi, &err) != GI_OK) {
        fprintf(stderr, "FAIL: %s\n", err.text);
        return 1;
    }
    ct.iscale = 3.0f;
    const float rstep = powf(r_hi / r_lo, 1.0f / 255.0f), astep = logf(a_hi / a_lo) / 255.0f;
    uint32_t rng = gi_rng_init(7, 0, 0xc0au);
    uint32_t bad_c = 0, bad_r = 0, loose_r = 0, bad_n = 0, bad_k = 0, loose_k = 0, bad_a = 0,
             bad_i = 0, bad_p = 0;
    float max_n = 0.0f, max_i = 0.0f, max_dk = 0.0f;
    double bias_i = 0.0;
    uint32_t bias_n = 0;
    for (uint32_t i = 0; i < N; i++) {
        cssm_node_view v = {0}, d;
        float p[3];
        for (int k = 0; k < 3; k++)
            p[k] = lo[k] + (hi[k] - lo[k]) * gi_rng_next_float(&rng);
        v.c = gi_v3(p[0], p[1], p[2]);
        v.r = rnd_log(&rng, r_lo, r_hi * 0.5f);
        v.n = gi_sample_uniform_sphere(gi_rng_next_float(&rng), gi_rng_next_float(&rng));
        v.cos_cone =
            (i % 7) == 0 ? -1.0f : 1.0f - 2.0f * gi_rng_next_float(&rng) * gi_rng_next_float(&rng);
        v.area = rnd_log(&rng, a_lo, a_hi);
        float mag = ct.iscale * exp2f(-40.0f + 42.0f * gi_rng_next_float(&rng));
        for (int k = 0; k < 3; k++)
            v.I[k] = (gi_pcg_hash(i * 3u + (uint32_t)k) % 5u) == 0 ? 0.0f
                                                                   : mag * gi_rng_next_float(&rng);
        v.child = (i % 5) == 0 ? -1 : (int32_t)(gi_rng_next_u32(&rng) % CSSM_COMPACT_MAX_NODES);
        v.skip = (i % 3) == 0 ? -1 : (int32_t)(gi_rng_next_u32(&rng) % CSSM_COMPACT_MAX_NODES);
        if (i == 1)
            v.child = (int32_t)CSSM_COMPACT_MAX_NODES - 1, v.skip = 0;
        cssm_ctree_encode(&ct, i, &v);
        cssm_ctree_view(&ct, i, &d);
        float dc[3] = {d.c.x - v.c.x, d.c.y - v.c.y, d.c.z - v.c.z};
        for (int k = 0; k < 3; k++)
            bad_c += fabsf(dc[k]) > 0.5f * (hi[k] - lo[k]) / 255.0f * 1.0001f + 1e-6f;
        float need = v.r + gi_v3_length(gi_v3_sub(v.c, d.c));
        bad_r += d.r < need;
        loose_r += d.r > fmaxf(need, r_lo) * rstep * 1.0001f;
        float an = angle_between(v.n, d.n);
        max_n = fmaxf(max_n, an);
        bad_n += an > 1e-3f;
        if (v.cos_cone <= -1.0f) {
            bad_k += d.cos_cone > -1.0f;
        } else {
            /* compared as cosines: the decoded cone must reach the true
             * cone's angle plus the normal's rounding, and stay within one
             * code (pi / 255) of it */
            float kneed = acosf(v.cos_cone) + an;
            bad_k += kneed < (float)GI_PI && d.cos_cone > cosf(kneed) + 1e-6f;
            loose_k += kneed + (float)GI_PI / 255.0f < (float)GI_PI &&
                       d.cos_cone < cosf(kneed + (float)GI_PI / 255.0f) - 1e-6f;
            max_dk = fmaxf(max_dk, acosf(fmaxf(-1.0f, d.cos_cone)) - kneed);
        }
        bad_a += fabsf(logf(d.area / v.area)) > 0.5f * astep * 1.001f;
        float mx = fmaxf(v.I[0], fmaxf(v.I[1], v.I[2]));
        for (int k = 0; k < 3; k++) {
            float e = fabsf(d.I[k] - v.I[k]);
            bad_i += e > mx / 31.5f * 1.0001f;
            if (mx > 0.0f) {
                max_i = fmaxf(max_i, e / mx);
                bias_i += (double)(d.I[k] - v.I[k]) / mx, bias_n++;
            }
        }
        bad_p += d.child != v.child || d.skip != v.skip;
    }
    CHECK_MSG(!bad_c, "%u centres off by more than half a step", bad_c);
    CHECK_MSG(!bad_r && !loose_r,
              "radius: %u smaller than the true sphere needs, %u more than one code larger", bad_r,
              loose_r);
    CHECK_MSG(!bad_n, "%u normals off by more than 1e-3 rad", bad_n);
    CHECK_MSG(!bad_k && !loose_k,
              "cone: %u narrower than the true cone, %u more than one code wider", bad_k, loose_k);
    CHECK_MSG(!bad_a, "%u areas off by more than half a log step", bad_a);
    CHECK_MSG(!bad_i, "%u intensity channels off by more than 1/31.5 of the largest", bad_i);
    CHECK_MSG(!bad_p, "%u pointers changed", bad_p);
    /* the dithered rounding: a mean signed error within a few standard
     * errors of 0 (one step is at most 1/31.5, a uniform error's sd 1/109) */
    bias_i /= bias_n;
    CHECK_MSG(fabs(bias_i) < 4.0 / (109.0 * sqrt((double)bias_n)) + 1e-4,
              "intensity rounding biased by %.5f", bias_i);
    printf("compact: %u random nodes: normal error at most %.2e rad (%.4f deg), cone widened by at "
           "most %.4f rad, "
           "intensity error at most %.4f of the largest channel (mean signed %+.5f), radius step "
           "x%.4f, area step x%.4f\n",
           N, (double)max_n, (double)max_n * 180.0 / GI_PI, (double)max_dk, (double)max_i, bias_i,
           (double)rstep, (double)expf(astep));
    cssm_ctree_free(&ct);

    /* the Cornell box's tree */
    gi_scene *s = load("scenes/cornell_box.gltf");
    if (!s)
        return 1;
    cssm_atlas a;
    cssm_tree t;
    if (cssm_atlas_build(s, 0.0f, 32, 0, &a, &err) != GI_OK ||
        cssm_tree_build(&a, &t, &err) != GI_OK || cssm_ctree_build(&t, &a, &ct, &err) != GI_OK) {
        fprintf(stderr, "FAIL: %s\n", err.text);
        gi_scene_free(s);
        return 1;
    }
    uint32_t outside = 0, out_cone = 0, ptr = 0;
    double over_log = 0.0, over_lin = 0.0;
    float rmax = ct.rtab[255];
    for (uint32_t i = 0; i < t.count; i++) {
        cssm_node_view f = float_view(&t, (int32_t)i), d;
        cssm_ctree_view(&ct, i, &d);
        ptr += d.child != f.child || d.skip != f.skip || d.first != f.first || d.count != f.count ||
               d.rep != f.rep;
        float need = 0.0f;
        for (uint32_t k = f.first; k < f.first + f.count; k++) {
            const cssm_texel *x = &a.texels[t.leaves[k]];
            float reach = gi_v3_length(gi_v3_sub(x->p, d.c)) + 0.75f * sqrtf(x->area);
            need = fmaxf(need, reach);
            outside += reach > d.r;
            out_cone += d.cos_cone > -1.0f && gi_v3_dot(x->n, d.n) < d.cos_cone - 1e-6f;
        }
        /* what a linear code (steps of rmax / 255, rounded up) would give */
        float lin = ceilf(need / rmax * 255.0f) / 255.0f * rmax;
        over_log += d.r / need - 1.0;
        over_lin += lin / need - 1.0;
    }
    over_log /= t.count;
    over_lin /= t.count;
    CHECK_MSG(!outside, "%u texels outside their node's decoded sphere", outside);
    CHECK_MSG(!out_cone, "%u texel normals outside their node's decoded cone", out_cone);
    CHECK_MSG(!ptr,
              "%u nodes whose pointers, leaves or visibility texel differ from the float tree's",
              ptr);
    CHECK_MSG(over_log < over_lin,
              "the log radius code (%.3f) is not tighter than a linear one (%.3f)", over_log,
              over_lin);
    uint32_t *x = malloc(t.count * sizeof *x), *y = malloc(t.count * sizeof *y);
    uint32_t differ = 0;
    for (uint32_t salt = 0; salt < 65; salt++) {
        uint32_t nx = 0, ny = 0;
        int full = salt == 64;
        stackless(&t, salt, full, x, &nx);
        stackless_compact(&ct, salt, full, y, &ny);
        differ += nx != ny || memcmp(x, y, nx * sizeof *x);
    }
    CHECK_MSG(
        !differ,
        "%u of 65 skip-pointer traversals over packed nodes differ from those over float nodes",
        differ);
    /* the packed pull (re-encoded at each node) against the float pull x area */
    float *tl = malloc(3 * a.count * sizeof *tl), *nl = malloc(3 * t.count * sizeof *nl);
    for (uint32_t i = 0; i < a.count; i++)
        for (int k = 0; k < 3; k++)
            tl[3 * i + k] = a.texels[i].albedo[k] + 10.0f * a.texels[i].emission[k];
    cssm_tree_pull(&t, &a, tl, nl);
    cssm_ctree_pull(&ct, &a, tl);
    /* each re-encoding errs by at most 1/31.5 of the node's largest channel
     * (at most its channel sum S); the nodes of one level below a node sum
     * to its S, so a node of height h errs by at most (h + 1) S / 31.5 */
    uint32_t *height = calloc(t.count, sizeof *height), over = 0;
    double worst = 0.0, mean = 0.0, root = 0.0;
    for (int32_t i = (int32_t)t.count - 1; i >= 0; i--) {
        const cssm_node *nd = &t.nodes[i];
        if (nd->child >= 0)
            height[i] = 1 + (height[nd->child] > height[t.nodes[nd->child].skip]
                                 ? height[nd->child]
                                 : height[t.nodes[nd->child].skip]);
        cssm_node_view d;
        cssm_ctree_view(&ct, (uint32_t)i, &d);
        float mx = 0.0f, sum = 0.0f;
        for (int k = 0; k < 3; k++)
            mx = fmaxf(mx, nl[3 * i + k] * nd->area), sum += nl[3 * i + k] * nd->area;
        for (int k = 0; k < 3; k++) {
            double e = fabs(d.I[k] - nl[3 * i + k] * nd->area);
            over += e > (height[i] + 1) * sum / 31.5 * 1.001;
            worst = fmax(worst, e / mx);
            mean += e / mx / (3.0 * t.count);
            if (i == 0)
                root = fmax(root, e / mx);
        }
    }
    free(height);
    CHECK_MSG(!over, "packed pull: %u channels beyond the bound (h + 1) S / 31.5", over);
    printf(
        "compact: Cornell box 32^2, %u nodes (%zu bytes each as floats + radiance, %zu packed): "
        "texels inside "
        "decoded spheres and cones, pointers exact, 65 traversals equal; radius over-estimate log "
        "%.3f, linear "
        "%.3f (mean); packed pull error mean %.4f, worst %.4f, root %.4f of the largest channel\n",
        t.count, sizeof(cssm_node) + 3 * sizeof(float), sizeof(cssm_pnode), over_log, over_lin,
        mean, worst, root);
    free(tl);
    free(nl);
    free(x);
    free(y);
    cssm_ctree_free(&ct);
    cssm_tree_free(&t);
    cssm_atlas_free(&a);
    gi_scene_free(s);
    return 0;
}

/* ------------------------------------------------------------------ env */

/* Margins of part_env (README "Tests"): the escape test's agreement with
 * Embree, balanced over escaping and blocked directions, above the 1/2 of
 * always / never escapes (measured 93.4 and 95.5 %: README "Tests"), and the per-texel
 * irradiance RMSE against the traced estimate as a fraction of the better
 * of black / unshadowed. */
#define ENV_ESCAPE_MARGIN 0.35
#define ENV_IRRADIANCE_RATIO 0.5

typedef struct env_truth_ctx {
    const gi_rt *rt;
    gi_vec3 x;
} env_truth_ctx;

static float env_truth(const void *ctx, gi_vec3 w)
{
    const env_truth_ctx *t = ctx;
    return gi_rt_occluded(t->rt, t->x, w, 0.0f, INFINITY) ? 0.0f : 1.0f;
}

static float env_open(const void *ctx, gi_vec3 w)
{
    (void)ctx, (void)w;
    return 1.0f;
}

/* One scene of part_env: compression with and without escape intervals,
 * then (check != 0) the escape test and the irradiance. */
static int env_scene(const char *rel, int check)
{
    fixture f;
    cssm_maps plain = {0};
    const uint32_t M = 16; /* the plugin's default */
    cssm_build_opts eo = {.escape = 1};
    gi_error err = {0};
    if (fixture_open(&f, rel, 0.0f, 0.0f) ||
        cssm_maps_build(f.gs, &f.a, f.order, M, NULL, &plain, &err) != GI_OK ||
        cssm_maps_build_ex(f.gs, &f.a, f.order, M, &eo, NULL, &f.m, &err) != GI_OK) {
        if (f.order)
            fprintf(stderr, "FAIL: set-up: %s\n", err.text);
        cssm_maps_free(&plain);
        fixture_close(&f);
        return 1;
    }
    const gi_scene *s = f.s;
    const cssm_atlas *a = &f.a;
    const cssm_maps *m = &f.m;
    double rp = (double)cssm_maps_bytes_uncompressed(&plain) / (double)cssm_maps_bytes(&plain);
    double re = (double)cssm_maps_bytes_uncompressed(m) / (double)cssm_maps_bytes(m);
    double sp = (double)cssm_maps_segments(&plain) / (6.0 * M * M),
           se = (double)cssm_maps_segments(m) / (6.0 * M * M);
    printf("%s (atlas 32^2, %u texels, 6 x %u x %u, spiral): compression %.2f : 1 -> %.2f : 1 with "
           "escape intervals "
           "(segments per texel %.1f -> %.1f, %+.1f %%)\n",
           rel, a->count, M, M, rp, re, sp, se, 100.0 * (se / sp - 1.0));
    CHECK_MSG(se >= sp, "escape intervals cannot merge runs that were apart (%.2f < %.2f)", se, sp);
    {
        /* what the escape intervals do to the texel-to-point visibility of
         * the gathers (a run of surfaces without a second one now stores the
         * middle up to the far plane, not its nearest surface) */
        const float bias = 0.004f * a->diameter;
        int tried = 0, ap = 0, ae = 0, vis = 0;
        uint32_t rng = gi_rng_init(5, 0, 0x7e5u);
        while (tried < 5000) {
            uint32_t j = gi_rng_next_u32(&rng) % a->count, i = gi_rng_next_u32(&rng) % a->count;
            if (i == j)
                continue;
            gi_vec3 x = cssm_receiver_point(m, a, a->texels[i].p, a->texels[i].n);
            gi_vec3 d = gi_v3_sub(x, m->eye[j]);
            float len = gi_v3_length(d);
            if (gi_v3_dot(d, a->texels[j].n) <= 0.0f || gi_v3_dot(d, a->texels[i].n) >= 0.0f)
                continue;
            tried++;
            int truth = !gi_rt_occluded(f.rt0, m->eye[j], gi_v3_scale(d, 1.0f / len),
                                        1e-4f * a->diameter, len * (1.0f - 1e-4f));
            vis += truth;
            ap += (cssm_visible(&plain, j, x, bias, 0) > 0.5f) == truth;
            ae += (cssm_visible(m, j, x, bias, 0) > 0.5f) == truth;
        }
        printf("  texel-point visibility (%d facing pairs): %.2f %% agree with Embree, %.2f %% "
               "with escape "
               "intervals (always-visible %.2f %%)\n",
               tried, 100.0 * ap / tried, 100.0 * ae / tried, 100.0 * vis / tried);
        CHECK_MSG(ae >= ap - tried / 100,
                  "escape intervals cost more than 1 point of visibility (%d -> %d of %d)", ap, ae,
                  tried);
    }
    if (check) {
        /* the escape test: random texel, cosine-weighted direction about its normal */
        const int pairs = 20000;
        int agree = 0, agree_pcf = 0, open = 0, false_esc = 0, false_block = 0;
        uint32_t rng = gi_rng_init(11, 0, 0xe5cu);
        for (int k = 0; k < pairs; k++) {
            uint32_t j = gi_rng_next_u32(&rng) % a->count;
            float u1 = gi_rng_next_float(&rng), u2 = gi_rng_next_float(&rng);
            gi_vec3 w = gi_to_world(gi_sample_cosine_hemisphere(u1, u2), a->texels[j].n);
            int truth = !gi_rt_occluded(f.rt0, m->eye[j], w, 0.0f, INFINITY);
            int e = cssm_escape(m, j, w, 0) > 0.5f;
            open += truth;
            agree += e == truth;
            agree_pcf += (cssm_escape(m, j, w, 1) > 0.5f) == truth;
            false_esc += e && !truth;
            false_block += !e && truth;
        }
        double rate = (double)agree / pairs, always = (double)open / pairs, never = 1.0 - always;
        double trivial = always > never ? always : never;
        /* most directions of these open scenes escape, so always-escapes
         * agrees often too: the balanced rate (mean of the rates on the
         * escaping and on the blocked directions) is 1/2 for both trivial
         * answers whatever the mix */
        const int blocked = pairs - open;
        double r_open = open ? 1.0 - (double)false_block / open : 1.0;
        double r_blocked = blocked ? 1.0 - (double)false_esc / blocked : 1.0;
        double balanced = 0.5 * (r_open + r_blocked);
        printf("  escape test, %d texel / direction pairs: agrees with Embree on %.2f %% (PCF %.2f "
               "%%); always "
               "escapes %.2f %%, never %.2f %%; errors %.2f %% escape where Embree hits, %.2f %% "
               "blocked where it "
               "does not; balanced %.2f %% (escaping %.2f %%, blocked %.2f %% of %d; trivial "
               "answers 50 %%)\n",
               pairs, 100 * rate, 100.0 * agree_pcf / pairs, 100 * always, 100 * never,
               100.0 * false_esc / pairs, 100.0 * false_block / pairs, 100 * balanced, 100 * r_open,
               100 * r_blocked, blocked);
        CHECK_MSG(blocked >= 200, "only %d blocked directions: the test cannot tell", blocked);
        CHECK_MSG(rate > trivial, "escape agreement %.4f not above the better trivial answer %.4f",
                  rate, trivial);
        CHECK_MSG(balanced >= 0.5 + ENV_ESCAPE_MARGIN,
                  "balanced escape agreement %.4f not %.0f points above 1/2", balanced,
                  100 * ENV_ESCAPE_MARGIN);
        /* per-texel irradiance: the same directions, visibility by the maps,
         * by Embree, by nothing */
        const uint32_t K = 128; /* the plugin's env_samples */
        double se_c = 0, se_o = 0, se_b = 0, sum_t = 0, sum_c = 0;
        for (uint32_t i = 0; i < a->count; i++) {
            float ec[3], et[3], eo3[3];
            cssm_env_texel_ctx pc = {.m = m, .texel = i, .n = a->texels[i].n, .pcf = 0};
            env_truth_ctx tc = {.rt = f.rt0, .x = m->eye[i]};
            cssm_env_estimate(s->envmap, a->texels[i].n, K, i, NULL, cssm_env_texel_vis, &pc, ec);
            cssm_env_estimate(s->envmap, a->texels[i].n, K, i, NULL, env_truth, &tc, et);
            cssm_env_estimate(s->envmap, a->texels[i].n, K, i, NULL, env_open, NULL, eo3);
            for (int c = 0; c < 3; c++) {
                se_c += (ec[c] - et[c]) * (double)(ec[c] - et[c]);
                se_o += (eo3[c] - et[c]) * (double)(eo3[c] - et[c]);
                se_b += et[c] * (double)et[c];
                sum_t += et[c];
                sum_c += ec[c];
            }
        }
        double n3 = 3.0 * a->count, rc = sqrt(se_c / n3), ro = sqrt(se_o / n3),
               rb = sqrt(se_b / n3);
        double best = ro < rb ? ro : rb;
        printf("  texel irradiance (%u directions, the same for all): RMSE against the traced "
               "estimate %.4f, "
               "unshadowed %.4f, black %.4f (%.2f x the better); mean %+.2f %%\n",
               K, rc, ro, rb, rc / best, 100.0 * (sum_c / sum_t - 1.0));
        CHECK_MSG(rc < ENV_IRRADIANCE_RATIO * best, "irradiance RMSE %.4f not below %.2f x %.4f",
                  rc, ENV_IRRADIANCE_RATIO, best);
    }
    cssm_maps_free(&plain);
    fixture_close(&f);
    return 0;
}

/* 16-bit pointers: a tree of 65 535 nodes (32 768 texels) packs with
 * every pointer exact, one of 65 537 (32 769 texels) is refused with a
 * one-line error. */
static int part_compact_limit(void)
{
    const uint32_t sizes[2] = {32768, 32769};
    uint32_t rng = gi_rng_init(3, 0, 0x11au);
    for (int s = 0; s < 2; s++) {
        cssm_atlas a = {0};
        a.count = sizes[s];
        a.texels = calloc(a.count, sizeof *a.texels);
        if (!a.texels) {
            fprintf(stderr, "FAIL: out of memory\n");
            return 1;
        }
        for (uint32_t i = 0; i < a.count; i++) {
            a.texels[i].p =
                gi_v3(gi_rng_next_float(&rng), gi_rng_next_float(&rng), gi_rng_next_float(&rng));
            a.texels[i].n = gi_v3(0, 0, 1);
            a.texels[i].area = 1e-4f;
        }
        cssm_tree t;
        cssm_ctree ct;
        gi_error err = {{0}};
        if (cssm_tree_build(&a, &t, &err) != GI_OK) {
            fprintf(stderr, "FAIL: %s\n", err.text);
            return 1;
        }
        gi_result r = cssm_ctree_build(&t, &a, &ct, &err);
        if (s == 0) {
            CHECK_MSG(r == GI_OK, "%u nodes refused: %s", t.count, err.text);
            uint32_t ptr = 0;
            for (uint32_t i = 0; r == GI_OK && i < t.count; i++) {
                cssm_node_view d;
                cssm_ctree_view(&ct, i, &d);
                ptr += d.child != t.nodes[i].child || d.skip != t.nodes[i].skip;
            }
            CHECK_MSG(!ptr, "%u of %u nodes' pointers differ", ptr, t.count);
            printf("compact_limit: %u nodes packed, pointers exact\n", t.count);
        } else {
            CHECK_MSG(r == GI_ERR_INVALID_ARGUMENT && strstr(err.text, "at most 65535") &&
                          !strchr(err.text, '\n'),
                      "%u nodes: result %d, '%s'", t.count, (int)r, err.text);
            printf("compact_limit: %u nodes refused: %s\n", t.count, err.text);
        }
        cssm_ctree_free(&ct);
        cssm_tree_free(&t);
        free(a.texels);
    }
    return 0;
}

static int part_env(void)
{
    int r = env_scene("scenes/bunny_env.glb", 1);
    r |= env_scene("scenes/teapot_plane.glb", 1);
    r |= env_scene("scenes/cornell_box.gltf", 0);
    return r;
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(
            stderr,
            "usage: cssm_tests "
            "traversal|tree|visibility|furnace|hull|motion|motion2|texture|compact|compact_furnace|"
            "compact_limit|escape\n");
        return 2;
    }
    int r;
    if (!strcmp(argv[1], "traversal"))
        r = part_traversal();
    else if (!strcmp(argv[1], "tree"))
        r = part_tree();
    else if (!strcmp(argv[1], "visibility"))
        r = part_visibility();
    else if (!strcmp(argv[1], "furnace"))
        r = part_furnace(0);
    else if (!strcmp(argv[1], "compact_furnace"))
        r = part_furnace(1);
    else if (!strcmp(argv[1], "compact"))
        r = part_compact();
    else if (!strcmp(argv[1], "compact_limit"))
        r = part_compact_limit();
    else if (!strcmp(argv[1], "hull"))
        r = part_hull();
    else if (!strcmp(argv[1], "motion"))
        r = part_motion();
    else if (!strcmp(argv[1], "motion2"))
        r = part_motion2();
    else if (!strcmp(argv[1], "texture"))
        r = part_texture();
    else if (!strcmp(argv[1], "escape"))
        r = part_env();
    else {
        fprintf(stderr, "cssm_tests: unknown part '%s'\n", argv[1]);
        return 2;
    }
    if (r || gi_test_failed) {
        fprintf(stderr, "cssm_tests %s: %d check(s) failed\n", argv[1], gi_test_failed + r);
        return 1;
    }
    printf("cssm_tests %s: ok\n", argv[1]);
    return 0;
}
