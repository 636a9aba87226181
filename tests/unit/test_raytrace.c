/* gi/raytrace.h against brute force:
 *  - on the Cornell box and on a small hand-made scene (a sphere around a
 *    plane and a disk, built through the real loader), gi_rt_intersect
 *    agrees with a double-precision Moller-Trumbore test over every
 *    triangle (placed independently, by gi_scene_triangle_world) on
 *    thousands of random rays: same hit/miss, t within 1e-4 relative, the
 *    same triangle unless another one lies at the same t (a tie: a shared
 *    edge or coplanar overlap); a disagreement is excused only for a ray
 *    passing within 1e-5 (barycentric) of a triangle's edge, and the
 *    number of those is reported and bounded;
 *  - the hit record: object and triangle ids as the scene has them, the
 *    position o + t d, the unit geometric normal of the CCW corners;
 *  - gi_rt_occluded agrees with gi_rt_intersect on segments shorter and
 *    longer than the first hit, with tmin > 0 and non-unit directions;
 *  - concurrent queries from several threads give the single-thread hits;
 *  - scenes/cornell_moving.gltf: after gi_rt_set_time the positions and
 *    the hits are those of the scene at the new time (and differ from the
 *    old one where the bunny moved), back again gives bit-identical hits;
 *  - bad input (NULL scene, non-finite time, a NaN vertex) is an error,
 *    and a failed set_time leaves the old placement. */
#include "check.h"
#include "ref_scenes.h"

#include "gi/raytrace.h"
#include "gi/rng.h"
#include "gi/sampling.h"

#include <float.h>
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define EDGE_EPS 1e-5

typedef struct bf_hit {
    double t;
    uint32_t tri;
    double edge; /* smallest barycentric of the hit (distance to an edge) */
} bf_hit;

typedef struct bf_scene {
    uint32_t n;
    double (*p)[9];
    uint8_t *single; /* the material is single-sided: culled from behind (gi/scene.h) */
} bf_scene;

static bf_scene bf_place(const gi_scene *s, float time)
{
    bf_scene b = {s->triangle_count, malloc((size_t)s->triangle_count * sizeof(double[9])),
                  malloc(s->triangle_count ? s->triangle_count : 1)};
    for (uint32_t t = 0; t < s->triangle_count; t++) {
        b.single[t] = !s->materials[s->vertices[s->indices[3 * (size_t)t]].material].double_sided;
        gi_vec3 p[3];
        gi_scene_triangle_world(s, t, time, p);
        for (int k = 0; k < 3; k++) {
            b.p[t][3 * k] = p[k].x;
            b.p[t][3 * k + 1] = p[k].y;
            b.p[t][3 * k + 2] = p[k].z;
        }
    }
    return b;
}

/* Moller-Trumbore in double on one triangle: t, or -1 for no hit. Also the
 * smallest barycentric (how close the ray passes to an edge), even for a
 * miss (negative then). A single-sided triangle seen from its back (det <=
 * 0: d along cross(e1, e2)) is no surface (gi/scene.h). */
static double mt(const double *p, const double o[3], const double d[3], int single, double *edge)
{
    double e1[3], e2[3], pv[3], tv[3], qv[3];
    for (int k = 0; k < 3; k++) {
        e1[k] = p[3 + k] - p[k];
        e2[k] = p[6 + k] - p[k];
        tv[k] = o[k] - p[k];
    }
    pv[0] = d[1] * e2[2] - d[2] * e2[1];
    pv[1] = d[2] * e2[0] - d[0] * e2[2];
    pv[2] = d[0] * e2[1] - d[1] * e2[0];
    double det = e1[0] * pv[0] + e1[1] * pv[1] + e1[2] * pv[2];
    *edge = -1.0;
    if (fabs(det) < 1e-300 || (single && det < 0.0))
        return -1.0;
    double u = (tv[0] * pv[0] + tv[1] * pv[1] + tv[2] * pv[2]) / det;
    qv[0] = tv[1] * e1[2] - tv[2] * e1[1];
    qv[1] = tv[2] * e1[0] - tv[0] * e1[2];
    qv[2] = tv[0] * e1[1] - tv[1] * e1[0];
    double v = (d[0] * qv[0] + d[1] * qv[1] + d[2] * qv[2]) / det;
    double t = (e2[0] * qv[0] + e2[1] * qv[1] + e2[2] * qv[2]) / det;
    *edge = fmin(fmin(u, v), 1.0 - u - v);
    return *edge >= 0.0 ? t : -1.0;
}

/* Closest hit in [tmin, tmax]; near_edge set when some triangle is passed
 * within EDGE_EPS of an edge at a t in range (hit or miss there is then
 * up to rounding). */
static int bf_intersect(const bf_scene *b, gi_vec3 of, gi_vec3 df, double tmin, double tmax,
                        bf_hit *h, int *near_edge)
{
    double o[3] = {of.x, of.y, of.z}, d[3] = {df.x, df.y, df.z};
    h->t = INFINITY;
    h->tri = UINT32_MAX;
    *near_edge = 0;
    for (uint32_t i = 0; i < b->n; i++) {
        double edge;
        double t = mt(b->p[i], o, d, b->single[i], &edge);
        if (fabs(edge) < EDGE_EPS)
            *near_edge = 1;
        if (t >= tmin && t <= tmax && t < h->t) {
            h->t = t;
            h->tri = i;
            h->edge = edge;
        }
    }
    return h->tri != UINT32_MAX;
}

typedef struct cmp_stats {
    int rays, hits, excused, bad_hitmiss, bad_t, bad_tri, ties, bad_record, bad_occluded;
} cmp_stats;

static float urand(uint32_t *rng)
{
    return gi_rng_next_float(rng);
}

/* One ray against both; updates the statistics. */
static void compare_ray(const gi_rt *rt, const gi_scene *s, const bf_scene *b, gi_vec3 o, gi_vec3 d,
                        float tmin, float tmax, cmp_stats *st)
{
    gi_rt_hit h;
    bf_hit bh;
    int near_edge;
    int hit = gi_rt_intersect(rt, o, d, tmin, tmax, &h);
    int bhit = bf_intersect(b, o, d, tmin, tmax, &bh, &near_edge);
    st->rays++;
    /* The lean query gives the same hit, to the bit. */
    float tt = 0.0f, tu = 0.0f, tv = 0.0f;
    uint32_t ttri = 0;
    int thit = gi_rt_intersect_tuv(rt, o, d, tmin, tmax, &tt, &tu, &tv, &ttri);
    st->bad_record +=
        thit != hit || (hit && (tt != h.t || tu != h.u || tv != h.v || ttri != h.triangle));
    if (hit != bhit) {
        if (near_edge)
            st->excused++;
        else {
            st->bad_hitmiss++;
            if (st->bad_hitmiss <= 3)
                fprintf(stderr, "hit/miss differ: embree %d brute %d (t %g tri %u)\n", hit, bhit,
                        hit ? (double)h.t : bh.t, hit ? h.triangle : bh.tri);
        }
        return;
    }
    if (!hit) {
        st->bad_occluded += gi_rt_occluded(rt, o, d, tmin, tmax) != 0;
        return;
    }
    st->hits++;
    if (fabs(h.t - bh.t) > 1e-4 * bh.t + 1e-6) {
        if (near_edge)
            st->excused++;
        else {
            st->bad_t++;
            if (st->bad_t <= 3)
                fprintf(stderr, "t differs: embree %.9g (tri %u) brute %.9g (tri %u)\n",
                        (double)h.t, h.triangle, bh.t, bh.tri);
        }
        return;
    }
    if (h.triangle != bh.tri) {
        /* A tie: Embree's triangle is hit by the brute force too, at the same t. */
        double edge, o3[3] = {o.x, o.y, o.z}, d3[3] = {d.x, d.y, d.z};
        double t2 =
            h.triangle < b->n ? mt(b->p[h.triangle], o3, d3, b->single[h.triangle], &edge) : -1.0;
        if (t2 >= 0.0 && fabs(t2 - bh.t) <= 1e-4 * bh.t + 1e-6)
            st->ties++;
        else if (near_edge)
            st->excused++;
        else
            st->bad_tri++;
    }
    /* The hit record. */
    const uint32_t *idx = s->indices + 3 * (size_t)h.triangle;
    gi_vec3 p[3];
    gi_scene_triangle_world(s, h.triangle, gi_rt_time(rt), p);
    gi_vec3 c = gi_v3_cross(gi_v3_sub(p[1], p[0]), gi_v3_sub(p[2], p[0]));
    gi_vec3 ng = gi_v3_normalize(c);
    gi_vec3 at = gi_v3_add(o, gi_v3_scale(d, h.t));
    float scale = 1e-4f * (1.0f + gi_v3_length(at));
    int ok =
        h.object == s->vertices[idx[0]].object && h.object < s->object_count &&
        h.triangle >= s->objects[h.object].first_triangle &&
        h.triangle < s->objects[h.object].first_triangle + s->objects[h.object].triangle_count &&
        gi_v3_length(gi_v3_sub(h.position, at)) <= scale &&
        fabsf(gi_v3_length(h.ng) - 1.0f) < 1e-5f && gi_v3_dot(h.ng, ng) > 0.9999f && h.u >= 0.0f &&
        h.v >= 0.0f && h.u + h.v <= 1.0f + 1e-6f;
    if (!ok && st->bad_record < 3)
        fprintf(stderr, "bad record: tri %u object %u pos %g %g %g vs %g %g %g\n", h.triangle,
                h.object, (double)h.position.x, (double)h.position.y, (double)h.position.z,
                (double)at.x, (double)at.y, (double)at.z);
    st->bad_record += !ok;
    /* occluded on segments ending before and after the first hit */
    st->bad_occluded += gi_rt_occluded(rt, o, d, tmin, tmax) != 1;
    st->bad_occluded += gi_rt_occluded(rt, o, d, tmin, h.t * 0.999f) != 0;
    st->bad_occluded += gi_rt_occluded(rt, o, d, tmin, h.t * 1.001f + 1e-6f) != 1;
}

static void report(const char *name, const cmp_stats *st)
{
    printf("%s: %d rays, %d hits, %d ties, %d excused (within %g of an edge), "
           "hit/miss %d, t %d, triangle %d, record %d, occluded %d disagreements\n",
           name, st->rays, st->hits, st->ties, st->excused, EDGE_EPS, st->bad_hitmiss, st->bad_t,
           st->bad_tri, st->bad_record, st->bad_occluded);
    CHECK(st->bad_hitmiss == 0 && st->bad_t == 0 && st->bad_tri == 0);
    CHECK(st->bad_record == 0 && st->bad_occluded == 0);
    CHECK_MSG(st->excused * 200 <= st->rays, "%d of %d rays excused", st->excused, st->rays);
    CHECK_MSG(st->hits * 4 >= st->rays, "only %d hits of %d rays", st->hits, st->rays);
}

/* Random rays: origins in the bounds grown by 20 %, directions uniform,
 * some non-unit; a quarter aimed at a random triangle's interior point so
 * that small objects are hit too. */
static void random_rays(const gi_rt *rt, const gi_scene *s, const bf_scene *b, float time, int n,
                        uint32_t seed, cmp_stats *st)
{
    uint32_t rng = gi_rng_init(seed, 0, 1);
    float bb[6];
    gi_scene_bounds_at(s, time, bb);
    for (int i = 0; i < n; i++) {
        gi_vec3 o;
        float *oo = &o.x;
        for (int k = 0; k < 3; k++) {
            float ext = bb[3 + k] - bb[k];
            oo[k] = bb[k] - 0.2f * ext + 1.4f * ext * urand(&rng);
        }
        gi_vec3 d = gi_sample_uniform_sphere(urand(&rng), urand(&rng));
        if (i % 4 == 0 && s->triangle_count) {
            uint32_t t = (uint32_t)(urand(&rng) * (float)s->triangle_count) % s->triangle_count;
            gi_vec3 p[3];
            gi_scene_triangle_world(s, t, time, p);
            float a = urand(&rng), c = urand(&rng);
            if (a + c > 1.0f)
                a = 1.0f - a, c = 1.0f - c;
            gi_vec3 q = gi_v3_add(p[0], gi_v3_add(gi_v3_scale(gi_v3_sub(p[1], p[0]), a),
                                                  gi_v3_scale(gi_v3_sub(p[2], p[0]), c)));
            gi_vec3 dd = gi_v3_sub(q, o);
            if (gi_v3_length(dd) > 1e-3f)
                d = gi_v3_normalize(dd);
        }
        float len = i % 3 == 0 ? 0.25f + 4.0f * urand(&rng) : 1.0f; /* non-unit d */
        d = gi_v3_scale(d, len);
        float tmin = i % 5 == 0 ? 0.5f * urand(&rng) : 0.0f;
        float tmax = i % 7 == 0 ? 2.0f * urand(&rng) : INFINITY;
        compare_ray(rt, s, b, o, d, tmin, tmax, st);
    }
}

/* Several threads cast the same rays; every result must equal the
 * single-thread one. */
typedef struct mt_job {
    const gi_rt *rt;
    const gi_vec3 *o, *d;
    const gi_rt_hit *want;
    const int *want_hit;
    int n, first, stride, bad;
} mt_job;

static void *mt_worker(void *arg)
{
    mt_job *j = arg;
    for (int rep = 0; rep < 4; rep++)
        for (int i = j->first; i < j->n; i += j->stride) {
            gi_rt_hit h;
            int hit = gi_rt_intersect(j->rt, j->o[i], j->d[i], 0.0f, INFINITY, &h);
            j->bad += hit != j->want_hit[i] ||
                      (hit && (h.t != j->want[i].t || h.triangle != j->want[i].triangle));
            j->bad += gi_rt_occluded(j->rt, j->o[i], j->d[i], 0.0f, INFINITY) != hit;
        }
    return NULL;
}

static void test_threads(const gi_rt *rt, const gi_scene *s)
{
    enum { N = 4000, T = 4 };
    gi_vec3 *o = malloc(N * sizeof *o), *d = malloc(N * sizeof *d);
    gi_rt_hit *want = malloc(N * sizeof *want);
    int *want_hit = malloc(N * sizeof *want_hit);
    uint32_t rng = gi_rng_init(99, 0, 1);
    float bb[6];
    gi_scene_bounds_at(s, 0.0f, bb);
    for (int i = 0; i < N; i++) {
        o[i] = gi_v3(bb[0] + (bb[3] - bb[0]) * urand(&rng), bb[1] + (bb[4] - bb[1]) * urand(&rng),
                     bb[2] + (bb[5] - bb[2]) * urand(&rng));
        d[i] = gi_sample_uniform_sphere(urand(&rng), urand(&rng));
        want_hit[i] = gi_rt_intersect(rt, o[i], d[i], 0.0f, INFINITY, &want[i]);
    }
    pthread_t th[T];
    mt_job jobs[T];
    for (int k = 0; k < T; k++) {
        jobs[k] = (mt_job){rt, o, d, want, want_hit, N, k, 1 + k % 2, 0}; /* overlapping sets */
        CHECK(pthread_create(&th[k], NULL, mt_worker, &jobs[k]) == 0);
    }
    int bad = 0;
    for (int k = 0; k < T; k++) {
        pthread_join(th[k], NULL);
        bad += jobs[k].bad;
    }
    printf("threads: %d threads x 4 passes over %d rays, %d results differ from one thread\n", T, N,
           bad);
    CHECK(bad == 0);
    free(o);
    free(d);
    free(want);
    free(want_hit);
}

static void test_scene(const char *path, int rays)
{
    gi_error err;
    gi_scene *s = gi_scene_load(path, &err);
    CHECK_MSG(s != NULL, "%s", err.text);
    if (!s)
        return;
    gi_rt *rt = NULL;
    CHECK_MSG(gi_rt_create(s, 0.0f, &rt, &err) == GI_OK && rt, "%s", err.text);
    if (rt) {
        bf_scene b = bf_place(s, 0.0f);
        cmp_stats st = {0};
        random_rays(rt, s, &b, 0.0f, rays, 1, &st);
        report(path, &st);
        test_threads(rt, s);
        free(b.p);
        free(b.single);
    }
    gi_rt_free(rt);
    gi_scene_free(s);
}

/* A closed sphere (flat faces, inside front) around a plane and a disk: small, hand-made. */
static void test_handmade(void)
{
    tg_scene tb;
    tg_init(&tb);
    const float alb[3] = {0.5f, 0.5f, 0.5f}, em[3] = {0, 0, 0};
    int m = tg_material(&tb, alb, em, 0);
    tg_icosphere(&tb, 3.0f, 2, 0, m);
    tg_plane(&tb, 1.0f, -0.5f, m);
    tg_disk(&tb, 0.7f, 0.8f, 7, m);
    const float eye[3] = {0.0f, 0.5f, 2.5f}, target[3] = {0, 0, 0};
    tg_camera(&tb, eye, target, 60.0f, 0.01f);
    gi_error err;
    gi_scene *s = tg_load(&tb, NULL, &err);
    CHECK_MSG(s != NULL, "%s", err.text);
    if (!s)
        return;
    gi_rt *rt = NULL;
    CHECK_MSG(gi_rt_create(s, 0.0f, &rt, &err) == GI_OK, "%s", err.text);
    bf_scene b = bf_place(s, 0.0f);
    cmp_stats st = {0};
    random_rays(rt, s, &b, 0.0f, 3000, 2, &st);
    report("hand-made (sphere, plane, disk)", &st);
    /* From the centre every ray hits the sphere from inside (its front),
     * unless the plane or the disk is in the way. */
    int ok = 0, n = 0;
    uint32_t rng = gi_rng_init(5, 0, 1);
    for (int i = 0; i < 500; i++) {
        gi_vec3 d = gi_sample_uniform_sphere(urand(&rng), urand(&rng));
        gi_rt_hit h;
        if (!gi_rt_intersect(rt, gi_v3(0.0f, 0.2f, 0.0f), d, 0.0f, INFINITY, &h))
            continue;
        n++;
        if (h.object == 0)
            ok += gi_v3_dot(h.ng, d) < 0.0f && fabsf(gi_v3_length(h.position) - 3.0f) < 0.5f;
        else
            ok += h.object == 1 ? d.y < 0.0f : d.y > 0.0f;
    }
    CHECK_MSG(n == 500 && ok == 500, "%d of %d rays from the centre hit, %d as expected", n, 500,
              ok);
    /* Empty interval and tmin past everything: no hit. */
    gi_rt_hit h;
    CHECK(!gi_rt_intersect(rt, gi_v3(0, 0.2f, 0), gi_v3(1, 0, 0), 10.0f, INFINITY, &h));
    CHECK(!gi_rt_occluded(rt, gi_v3(0, 0.2f, 0), gi_v3(1, 0, 0), 10.0f, INFINITY));
    CHECK(!gi_rt_intersect(rt, gi_v3(0, 0.2f, 0), gi_v3(1, 0, 0), 0.0f, 1.0f, &h));
    free(b.p);
    free(b.single);
    gi_rt_free(rt);
    gi_scene_free(s);
}

static int hits_equal(const gi_rt_hit *a, const gi_rt_hit *b)
{
    return a->t == b->t && a->triangle == b->triangle && a->u == b->u && a->v == b->v;
}

static void test_moving(void)
{
    gi_error err;
    gi_scene *s = gi_scene_load(GI_SOURCE_DIR "/scenes/cornell_moving.gltf", &err);
    CHECK_MSG(s != NULL, "%s", err.text);
    if (!s)
        return;
    uint32_t bunny = 0;
    while (bunny < s->object_count && strcmp(s->objects[bunny].name, "bunny") != 0)
        bunny++;
    CHECK(bunny < s->object_count && s->objects[bunny].animated);
    if (bunny == s->object_count) {
        gi_scene_free(s);
        return;
    }
    const float t0 = 0.0f, t1 = 0.37f * s->animation_length;
    gi_rt *rt = NULL, *fresh = NULL;
    CHECK(gi_rt_create(s, t0, &rt, &err) == GI_OK);
    CHECK(gi_rt_create(s, t1, &fresh, &err) == GI_OK);
    CHECK(gi_rt_set_time(rt, t1, &err) == GI_OK && gi_rt_time(rt) == t1);
    /* Positions equal the scene's own placement at t1. */
    const float *pos = gi_rt_positions(rt);
    double worst = 0.0;
    for (uint32_t t = 0; t < s->triangle_count; t++) {
        gi_vec3 p[3];
        gi_scene_triangle_world(s, t, t1, p);
        for (int k = 0; k < 3; k++)
            worst = fmax(worst, gi_v3_length(gi_v3_sub(
                                    p[k], gi_v3_load(pos + 3 * (size_t)s->indices[3 * t + k]))));
    }
    printf("moving: max |placed - gi_scene_triangle_world(t1)| = %g\n", worst);
    CHECK(worst <= 1e-5);
    /* The bunny moved: rays at its triangles' centres at t1 hit it there. */
    gi_camera_frame cam = gi_scene_camera_at(s, 0, t1);
    const gi_object *ob = &s->objects[bunny];
    int n = 0, hit_now = 0, hit_before = 0, same_as_fresh = 0;
    gi_rt *old = NULL;
    CHECK(gi_rt_create(s, t0, &old, &err) == GI_OK);
    for (uint32_t t = ob->first_triangle; t < ob->first_triangle + ob->triangle_count; t += 23) {
        gi_vec3 p[3];
        gi_scene_triangle_world(s, t, t1, p);
        gi_vec3 c = gi_v3_scale(gi_v3_add(p[0], gi_v3_add(p[1], p[2])), 1.0f / 3.0f);
        gi_vec3 d = gi_v3_sub(c, cam.eye);
        gi_rt_hit h, hf, ho;
        n++;
        int a = gi_rt_intersect(rt, cam.eye, d, 0.0f, 1.0001f, &h);
        hit_now += a && h.object == bunny;
        int f = gi_rt_intersect(fresh, cam.eye, d, 0.0f, 1.0001f, &hf);
        same_as_fresh += a == f && (!a || hits_equal(&h, &hf));
        int o = gi_rt_intersect(old, cam.eye, d, 0.0f, 1.0001f, &ho);
        hit_before += o && ho.object == bunny && fabsf(ho.t - h.t) < 1e-3f;
    }
    printf("moving: %d rays at bunny triangles at t1: %d hit the bunny, %d equal a fresh build at "
           "t1, %d hit it where it was at t0\n",
           n, hit_now, same_as_fresh, hit_before);
    CHECK(n > 100 && hit_now * 10 >= n * 9); /* some centres hide behind other bunny parts */
    CHECK(same_as_fresh == n);
    CHECK(hit_before * 20 < n);
    /* Brute force at t1. */
    bf_scene b = bf_place(s, t1);
    cmp_stats st = {0};
    random_rays(rt, s, &b, t1, 1000, 3, &st);
    report("cornell_moving after set_time", &st);
    free(b.p);
    free(b.single);
    /* Back to t0: the very same hits as a BVH built at t0. */
    CHECK(gi_rt_set_time(rt, t0, &err) == GI_OK);
    uint32_t rng = gi_rng_init(11, 0, 1);
    int diff = 0;
    for (int i = 0; i < 500; i++) {
        gi_vec3 d = gi_sample_uniform_sphere(urand(&rng), urand(&rng));
        gi_vec3 o =
            gi_v3(1.0f + 3.0f * urand(&rng), 0.1f + 4.0f * urand(&rng), 1.0f + 3.0f * urand(&rng));
        gi_rt_hit ha, hb;
        int a = gi_rt_intersect(rt, o, d, 0.0f, INFINITY, &ha);
        int c = gi_rt_intersect(old, o, d, 0.0f, INFINITY, &hb);
        diff += a != c || (a && !hits_equal(&ha, &hb));
    }
    CHECK_MSG(diff == 0, "%d of 500 rays differ after returning to t0", diff);
    /* A failed set_time leaves the placement as it was. */
    CHECK(gi_rt_set_time(rt, NAN, &err) == GI_ERR_INVALID_ARGUMENT && strstr(err.text, "finite"));
    CHECK(gi_rt_set_time(rt, INFINITY, &err) == GI_ERR_INVALID_ARGUMENT);
    CHECK(gi_rt_time(rt) == t0);
    float saved = s->vertices[ob->first_vertex].position[0];
    s->vertices[ob->first_vertex].position[0] = NAN;
    CHECK(gi_rt_set_time(rt, t1, &err) == GI_ERR_INVALID_ARGUMENT &&
          strstr(err.text, "not finite"));
    printf("NaN vertex at set_time: %s\n", err.text);
    s->vertices[ob->first_vertex].position[0] = saved;
    CHECK(gi_rt_time(rt) == t0 && memcmp(gi_rt_positions(rt), gi_rt_positions(old),
                                         (size_t)s->vertex_count * 3 * sizeof(float)) == 0);
    gi_rt_free(old);
    gi_rt_free(fresh);
    gi_rt_free(rt);
    gi_scene_free(s);
}

/* GI_RT_FAST_TRAVERSAL (the reference's default): the same checks against
 * the brute force as the robust mode passes, on the tessellated box (many
 * shared edges) with its rays; an unknown option bit is refused. */
static void test_fast_traversal(void)
{
    gi_error err;
    gi_scene *s = gi_scene_load(GI_SOURCE_DIR "/scenes/cornell_box.gltf", &err);
    CHECK_MSG(s != NULL, "%s", err.text);
    if (!s)
        return;
    gi_rt *rt = (gi_rt *)&err;
    CHECK(gi_rt_create_ex(s, 0.0f, 1u << 7, &rt, &err) == GI_ERR_INVALID_ARGUMENT && rt == NULL);
    printf("unknown option: %s\n", err.text);
    CHECK_MSG(gi_rt_create_ex(s, 0.0f, GI_RT_FAST_TRAVERSAL, &rt, &err) == GI_OK && rt, "%s",
              err.text);
    if (rt) {
        bf_scene b = bf_place(s, 0.0f);
        cmp_stats st = {0};
        random_rays(rt, s, &b, 0.0f, 3000, 7, &st);
        report("cornell_box.gltf, fast traversal", &st);
        free(b.p);
        free(b.single);
    }
    gi_rt_free(rt);
    gi_scene_free(s);
}

static void test_bad_input(void)
{
    gi_error err;
    gi_rt *rt = (gi_rt *)&err; /* must be reset to NULL on failure */
    CHECK(gi_rt_create(NULL, 0.0f, &rt, &err) == GI_ERR_INVALID_ARGUMENT && rt == NULL);
    printf("NULL scene: %s\n", err.text);
    gi_scene *s = gi_scene_load(GI_SOURCE_DIR "/scenes/cornell_box_coarse.gltf", &err);
    CHECK_MSG(s != NULL, "%s", err.text);
    if (!s)
        return;
    CHECK(gi_rt_create(s, NAN, &rt, &err) == GI_ERR_INVALID_ARGUMENT && rt == NULL);
    printf("NaN time: %s\n", err.text);
    CHECK(gi_rt_create(s, -INFINITY, &rt, &err) == GI_ERR_INVALID_ARGUMENT && rt == NULL);
    CHECK(gi_rt_create(s, 0.0f, NULL, &err) == GI_ERR_INVALID_ARGUMENT);
    CHECK(gi_rt_set_time(NULL, 0.0f, &err) == GI_ERR_INVALID_ARGUMENT);
    float saved = s->vertices[3].position[2];
    s->vertices[3].position[2] = INFINITY;
    CHECK(gi_rt_create(s, 0.0f, &rt, &err) == GI_ERR_INVALID_ARGUMENT && rt == NULL);
    printf("Inf vertex: %s\n", err.text);
    s->vertices[3].position[2] = 3e18f; /* finite, but its square overflows */
    CHECK(gi_rt_create(s, 0.0f, &rt, &err) == GI_ERR_INVALID_ARGUMENT && rt == NULL);
    s->vertices[3].position[2] = saved;
    CHECK(gi_rt_create(s, 0.0f, &rt, &err) == GI_OK && rt != NULL);
    CHECK(strncmp(gi_rt_version(rt), "embree 3.", 9) == 0 && gi_rt_scene(rt) == s);
    /* Static scene: set_time only records the time. */
    CHECK(gi_rt_set_time(rt, 1.5f, &err) == GI_OK && gi_rt_time(rt) == 1.5f);
    gi_rt_free(rt);
    gi_rt_free(NULL);
    gi_scene_free(s);
}

/* The 8-ray packet query gives each ray the hit the single-ray query
 * gives: camera-like bundles (one origin, directions a few degrees apart)
 * and scattered rays, full packets and partial ones (n = 1..8). */
static void test_packets(void)
{
    gi_error err;
    gi_scene *s = gi_scene_load(GI_SOURCE_DIR "/scenes/cornell_box.gltf", &err);
    CHECK_MSG(s != NULL, "%s", err.text);
    if (!s)
        return;
    gi_rt *rt = NULL;
    CHECK_MSG(gi_rt_create_ex(s, 0.0f, GI_RT_FAST_TRAVERSAL, &rt, &err) == GI_OK && rt, "%s",
              err.text);
    uint32_t rng = 12345u, rays = 0, hits = 0, same = 0;
    for (int round = 0; rt && round < 400; round++) {
        uint32_t n = 1u + (uint32_t)round % 8u;
        int bundle = round % 2 == 0;
        gi_vec3 o[8], d[8];
        float tmin[8], tmax[8], t[8], u[8], v[8];
        uint32_t tri[8];
        int hit[8];
        gi_vec3 eye =
            gi_v3(urand(&rng) * 0.8f + 0.1f, urand(&rng) * 0.8f + 0.1f, urand(&rng) * 0.8f + 0.1f);
        for (uint32_t i = 0; i < n; i++) {
            gi_vec3 a = gi_v3(urand(&rng) * 2.0f - 1.0f, urand(&rng) * 2.0f - 1.0f,
                              urand(&rng) * 2.0f - 1.0f);
            o[i] = bundle ? eye : gi_v3(urand(&rng), urand(&rng), urand(&rng));
            d[i] = gi_v3_normalize(
                bundle ? gi_v3_add(gi_v3(0.0f, 0.0f, -1.0f), gi_v3_scale(a, 0.1f)) : a);
            tmin[i] = i == 3 ? 0.05f : 0.0f;
            tmax[i] = i == 5 ? 0.3f : INFINITY;
        }
        gi_rt_intersect8_tuv(rt, n, o, d, tmin, tmax, hit, t, u, v, tri);
        for (uint32_t i = 0; i < n; i++) {
            float t1 = 0, u1 = 0, v1 = 0;
            uint32_t tri1 = 0;
            int h1 = gi_rt_intersect_tuv(rt, o[i], d[i], tmin[i], tmax[i], &t1, &u1, &v1, &tri1);
            rays++;
            hits += h1 != 0;
            same +=
                h1 == hit[i] && (!h1 || (tri1 == tri[i] && fabsf(t1 - t[i]) <= 1e-5f * t1 &&
                                         fabsf(u1 - u[i]) <= 1e-5f && fabsf(v1 - v[i]) <= 1e-5f));
        }
    }
    printf("packets: %u of %u rays agree with single-ray queries (%u hits)\n", same, rays, hits);
    /* both kinds of answer are covered */
    CHECK_MSG(rays == 1800 && same == rays && hits > rays / 4 && hits < rays,
              "%u of %u agree, %u hits", same, rays, hits);
    gi_rt_free(rt);
    gi_scene_free(s);
}

int main(void)
{
    (void)tg_environment; /* ref_scenes.h helpers this test does not need */
    (void)tg_point_light;
    test_bad_input();
    test_handmade();
    test_scene(GI_SOURCE_DIR "/scenes/cornell_box.gltf", 3000);
    test_fast_traversal();
    test_packets();
    test_moving();
    return gi_test_finish();
}
