/* cssm_tests' parts on moving rigid objects in cssm_hrc (§3.3, motion.c):
 *   hull     the core's convex hulls (qhull) and their overlap test
 *            (GJK): overlapping pairs found, separated and near-touching
 *            ones (gap 1e-3) not, against the closed-form answers of
 *            boxes and against the bounding spheres of point clouds
 *   motion   the moving Cornell box (the bunny moves), maps made at
 *            t = 0, the bunny moved to t = 1.5 s (D T^-1, nothing made
 *            again): visibility against Embree on the moved scene for
 *            pairs near the bunny, against always / never visible and
 *            the unmoved scene's visibility
 *   motion2  the same with two moving objects, and the per-pair hull
 *            check */
#include "cssm_tests.h"

#include "check.h"

#include "gi/algo/hull.h"
#include "gi/mesh.h"
#include "gi/rng.h"
#include "gi/sampling.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* The margins the motion part must beat the best trivial answer by, in
 * agreement rate (measured +24 points on all pairs, +38 on the pairs the
 * motion changed: README "Tests"). */
#define MOTION_MARGIN 0.15
#define MOTION_MARGIN_AFFECTED 0.25
#define TWO_MOVERS 400 /* cssm_test_motion2: pairs between the two moving objects */

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

/* Unit boxes overlapping, touching and separated by gaps of 1e-3 and 1
 * (with their exact distances), and a box turned 45 degrees reaching
 * 1e-3 into / stopping 1e-3 short of another. */
static void hull_box_pairs(const gi_hull *box)
{
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
        int o = gi_hull_overlap(box, I, box, M, 0.0f);
        double d = gi_hull_distance(box, I, box, M);
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
        int o = gi_hull_overlap(box, I, box, R, 0.0f);
        CHECK_MSG(o == (side < 0), "turned box %s by 1e-3: overlap %d",
                  side < 0 ? "reaching in" : "short", o);
    }
}

/* A flat set (a quad) and a box 1e-3 above it and 1e-3 through it; 1
 * when the quad's hull cannot be built (the message printed). */
static int hull_flat(const gi_hull *box, gi_hull *flat)
{
    gi_error err;
    float I[16], M[16];
    gi_mat4_identity(I);
    /* a flat set (a quad): qhull is asked again with joggled input */
    float quad[12] = {-1, 0, -1, 1, 0, -1, 1, 0, 1, -1, 0, 1};
    if (gi_hull_build(quad, 4, flat, &err) != GI_OK) {
        fprintf(stderr, "FAIL: flat: %s\n", err.text);
        return 1;
    }
    translate(M, 0.2f, 0.501f, 0.1f);
    CHECK_MSG(!gi_hull_overlap(flat, I, box, M, 0.0f), "box 1e-3 above a quad: overlap");
    translate(M, 0.2f, 0.499f, 0.1f);
    CHECK_MSG(gi_hull_overlap(flat, I, box, M, 0.0f),
              "box reaching 1e-3 through a quad: no overlap");
    return 0;
}

/* 200 pairs of point clouds on spheres, separated or overlapping: the
 * pairs judged wrong into *wrong of *n; 1 when a hull cannot be built
 * (the message printed). */
static int hull_clouds(int *wrong_out, int *n_out)
{
    gi_error err;
    float I[16], M[16];
    gi_mat4_identity(I);
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
    *wrong_out = wrong;
    *n_out = n;
    return 0;
}

int cssm_test_hull(void)
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
    hull_box_pairs(&box);
    gi_hull flat;
    if (hull_flat(&box, &flat)) {
        gi_hull_free(&box);
        return 1;
    }
    int wrong = 0, n = 0;
    if (hull_clouds(&wrong, &n))
        return 1;
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
 * prepare() makes at t0 (motion_update.c cssm_build_moving: the static CSSM without
 * the movers, each mover's CSSM and CSM); the movers are left at t0.
 * Prints each mover's way under `tag`. 0 on success. */
static int motion_open(cssm_fixture *f, const char *rel, uint32_t movers, float t0, float t1,
                       const char *tag)
{
    if (cssm_fixture_open(f, rel, t0, t1))
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
static int motion_near(const cssm_fixture *f, gi_vec3 eye, gi_vec3 x)
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
static void motion_judge(const cssm_fixture *f, motion_tally *t, int kind, uint32_t j, uint32_t i,
                         gi_vec3 p, gi_vec3 x, gi_vec3 eye)
{
    const cssm_texel *ti = &f->a.texels[i];
    const float bias = 0.004f * f->a.diameter;
    t->tried++;
    t->kinds[kind]++;
    int truth = cssm_fixture_truth(f, f->rt1, eye, x),
        before = cssm_fixture_truth(f, f->rt0, eye, x);
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
int cssm_test_motion(void)
{
    const float t0 = 0.0f, t1 = 1.5f;
    cssm_fixture f;
    if (motion_open(&f, "scenes/cornell_moving.gltf", 1, t0, t1, "motion")) {
        cssm_fixture_close(&f);
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
        if (i == j || !cssm_fixture_pair(&f, j, i, &rng, &p, &x, &eye))
            continue;
        int kind = motion_kind(&f.mo, j, i);
        if (kind == 0 && !motion_near(&f, eye, x))
            continue;
        motion_judge(&f, &t, kind, j, i, p, x, eye);
    }
    motion_report("motion", &t, pairs);
    cssm_fixture_close(&f);
    return 0;
}

/* Two moving objects (§3.3 for every object): the bunny and a box of
 * plugins/cssm_hrc/data/cornell_moving2.gltf (plugins/cssm_hrc/data/make_cornell_moving2.py),
 * everything made at t0, both moved to t1 by cssm_motion_place alone, facing texel / point pairs
 * that a mover can matter to against Embree on the moved scene; the per-pair hull check, also with
 * the box put onto the bunny. */
int cssm_test_motion2(void)
{
    const float t0 = 0.0f, t1 = 1.6f; /* the tall block then hides the box from part of the bunny */
    cssm_fixture f;
    if (motion_open(&f, "plugins/cssm_hrc/data/cornell_moving2.gltf", 2, t0, t1, "motion2")) {
        cssm_fixture_close(&f);
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
        if (i == j || !cssm_fixture_pair(&f, j, i, &rng, &p, &x, &eye))
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
    cssm_fixture_close(&f);
    return 0;
}
