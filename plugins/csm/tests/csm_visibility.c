/* The csm plugin's CPU side against exact ray casting on the bunny:
 *  - precompute the bunny's CSM (N = 8 x 8 directions, M = 64) on the GL
 *    context with the plugin's own code (plugins/csm/precompute.c);
 *  - lossless on real maps: re-render maps and check z1 <= z_avg < z2 for
 *    every texel (z_avg == z1 on degenerate texels);
 *  - visibility of random point-direction pairs around the bunny (points
 *    inside the mesh left out): the nearest-filter CSM query against brute
 *    force ray casting along the query direction w, and along the snapped
 *    map direction (which isolates the depth/codec path from the angular
 *    discretisation of §4.5);
 *  - the GLSL query (shaders/csm_query.glsl) on the same pairs, moved by a
 *    rigid transform of the object (§4.6), and the same data uploaded as
 *    the plugin does: nearest equals the CPU query, and
 *    the Russian-roulette filter averaged over 256 stratified random
 *    numbers equals the generalised PCF value (§4.5);
 *  - open surfaces (plugins/csm/README.md "Open and single-sided
 *    surfaces"): the ground plane of bunny_env.glb has one surface per
 *    texel. Points on the bunny's underside and points just above the
 *    ground, toward directions below the horizon: the product of both
 *    objects' CSMs (N = 8 x 8, M = 64, nearest) against exact ray casting
 *    (gi_rt_occluded on the whole scene) with the default thin shell
 *    (open_surfaces=shell, z2 and z3 options) and without it (open), which
 *    lets the light through the ground; and the same for a local point
 *    light below the ground (cube-map CSM of the ground, §3.3). */
#include "csm_cpu.h"
#include "csm_local.h"

#include "gi/mesh.h"
#include "gi/raytrace.h"
#include "gi/rng.h"
#include "gi/sampling.h"
#include "gi/shader.h"

#include "csm_test_util.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

extern const gi_shader_source gi_csm_query_shaders[];

/* EXPECT(cond, fmt, ...): CHECK_MSG of the unit tests' check.h, which
 * counts failures in gi_test_failed. */
#include "check.h"
#define EXPECT CHECK_MSG
#include "vis_score.h"

/* Number of hits of the ray o + h d, h > 0, with object k (local space). */
static int hits(const gi_scene *s, uint32_t k, gi_vec3 o, gi_vec3 d)
{
    const gi_object *ob = &s->objects[k];
    int n = 0;
    for (uint32_t t = ob->first_triangle; t < ob->first_triangle + ob->triangle_count; t++) {
        const float *q0 = s->vertices[s->indices[3 * t]].position,
                    *q1 = s->vertices[s->indices[3 * t + 1]].position,
                    *q2 = s->vertices[s->indices[3 * t + 2]].position;
        n += csm_test_ray_hits_triangle(gi_v3(q0[0], q0[1], q0[2]), gi_v3(q1[0], q1[1], q1[2]),
                                        gi_v3(q2[0], q2[1], q2[2]), o, d, INFINITY);
    }
    return n;
}

/* The plugin's default shell_thickness (fraction of R). */
#define SHELL 1e-3f

/* Visibility of world point x toward world unit w through the CSMs of
 * objects ks[0..n) (nearest filter, bias 0.01 R each): the product of §4.6. */
static int csm_lit(const gi_gpu_scene *gs, const uint32_t *ks, const gi_csm_data *const *data,
                   float (*spheres)[4], int n, uint32_t N, gi_vec3 x, gi_vec3 w)
{
    for (int i = 0; i < n; i++) {
        float inv[16];
        gi_mat4_invert(inv, gs->world_from_local[ks[i]]);
        gi_vec3 xl = gi_mat4_point(inv, x), wl = gi_v3_normalize(gi_mat4_dir(inv, w));
        if (!gi_csm_dir_visible(data[i], spheres[i], N, N, GI_CSM_ORDER_HILBERT, xl, wl,
                                0.01f * spheres[i][3]))
            return 0;
    }
    return 1;
}

/* Part 2's variants: 0 shell (z2), 1 open (z2), 2 shell (z3), 3 shell (z3,
 * spherical far plane). */
enum { VARIANTS = 4 };
static const char *variant_names[VARIANTS] = {"shell, z2", "open, z2", "shell, z3",
                                              "shell, z3 + far plane"};

/* Part 2's scene: the bunny and the ground, both objects' CSMs in every
 * variant and a ray caster on the whole scene. */
typedef struct open_scene {
    const gi_scene *s;
    const gi_gpu_scene *gs;
    gi_rt *rt;
    uint32_t N, M;
    uint32_t ks[2]; /* the bunny, the ground */
    float spheres[2][4];
    gi_csm_data data[VARIANTS][2];
} open_scene;

/* Builds the CSMs of both objects in every variant; returns the failures. */
static int build_variants(open_scene *o)
{
    int fails = 0;
    gi_error err;
    memset(o->data, 0, sizeof o->data);
    for (int v = 0; v < VARIANTS; v++)
        for (int i = 0; i < 2; i++) {
            csm_build_desc d = {.M = o->M,
                                .n_theta = o->N,
                                .n_phi = o->N,
                                .order = GI_CSM_ORDER_HILBERT,
                                .z3 = v == 2   ? CSM_DEPTH_Z3
                                      : v == 3 ? CSM_DEPTH_SPHERE
                                               : CSM_DEPTH_Z2,
                                .shell = v == 1 ? 0.0f : SHELL * o->spheres[i][3],
                                .batch = 16};
            if (csm_build_object(o->gs, o->ks[i], o->spheres[i], &d, NULL, 0, 1, &o->data[v][i],
                                 &err) != GI_OK) {
                fprintf(stderr, "%s\n", err.text);
                fails++;
            }
        }
    return fails;
}

/* The bunny's triangles in world space (3 corners each) and the CDF of
 * the areas of those whose geometric normal points down. */
typedef struct underside {
    float *cdf;
    gi_vec3 *tp;
    float total;
} underside;

static underside make_underside(const open_scene *o)
{
    const gi_scene *s = o->s;
    const gi_object *ob = &s->objects[o->ks[0]];
    const float *m = o->gs->world_from_local[o->ks[0]];
    underside u;
    u.cdf = malloc(sizeof(float) * ob->triangle_count);
    u.tp = malloc(sizeof(gi_vec3) * 3 * ob->triangle_count);
    u.total = 0;
    for (uint32_t t = 0; t < ob->triangle_count; t++) {
        for (int j = 0; j < 3; j++) {
            const float *q =
                s->vertices[s->indices[3 * (ob->first_triangle + t) + (uint32_t)j]].position;
            u.tp[3 * t + (uint32_t)j] = gi_mat4_point(m, gi_v3(q[0], q[1], q[2]));
        }
        gi_vec3 n = gi_v3_cross(gi_v3_sub(u.tp[3 * t + 1], u.tp[3 * t]),
                                gi_v3_sub(u.tp[3 * t + 2], u.tp[3 * t]));
        float len = gi_v3_length(n);
        u.total += len > 0 && n.y < -0.3f * len ? len : 0.0f;
        u.cdf[t] = u.total;
    }
    return u;
}

/* The receiver point x of one pair of set A (kind 0: on the bunny's
 * underside, offset one texel along its normal n) or set B (kind 1: above
 * the ground, n stays as it is); 0 when the draw is left out. */
static int sample_receiver(const open_scene *o, const underside *u, int kind, float texel,
                           uint32_t *rng, gi_vec3 *x, gi_vec3 *n)
{
    if (kind == 0) {
        float r = gi_rng_next_float(rng) * u->total;
        uint32_t lo = 0, hi = o->s->objects[o->ks[0]].triangle_count - 1;
        while (lo < hi) {
            uint32_t mid = (lo + hi) / 2;
            if (u->cdf[mid] > r)
                hi = mid;
            else
                lo = mid + 1;
        }
        float b[3];
        gi_sample_uniform_triangle(gi_rng_next_float(rng), gi_rng_next_float(rng), b);
        const gi_vec3 *q = &u->tp[3 * lo];
        *n = gi_v3_normalize(gi_v3_cross(gi_v3_sub(q[1], q[0]), gi_v3_sub(q[2], q[0])));
        *x = gi_v3_add(gi_v3_add(gi_v3_scale(q[0], b[0]), gi_v3_scale(q[1], b[1])),
                       gi_v3_scale(q[2], b[2]));
        *x = gi_v3_add(*x, gi_v3_scale(*n, texel));
        return !(x->y < 0.1f); /* below: within the ground's bias band */
    }
    *x = gi_v3(1.2f * (2.0f * gi_rng_next_float(rng) - 1.0f), 0.1f + 0.3f * gi_rng_next_float(rng),
               1.2f * (2.0f * gi_rng_next_float(rng) - 1.0f));
    /* leave out points inside the bunny (odd hits both ways) */
    gi_rt_hit h1, h2;
    return !(gi_rt_intersect(o->rt, *x, gi_v3(0, 1, 0), 0, INFINITY, &h1) &&
             h1.object == o->ks[0] &&
             gi_rt_intersect(o->rt, *x, gi_v3(0, -1, 0), 0, INFINITY, &h2) &&
             h2.object == o->ks[0] && gi_v3_dot(h1.ng, gi_v3(0, 1, 0)) > 0);
}

enum { OPEN_PAIRS = 1500 };

/* Part 2's counts per variant and kind of pair (0: set A, 1: set B). */
typedef struct open_tally {
    int occluded[2], agree[VARIANTS][2], agree_occ[VARIANTS][2];
    vis_score score[VARIANTS][2];
} open_tally;

/* Pairs: A, points on the bunny's underside (triangles whose world
 * geometric normal points down), offset one texel of the bunny's map
 * along it, at least 0.1 above the ground, directions below the horizon
 * on the normal's side; B,
 * points 0.1..0.4 above the ground (outside the bunny) near it,
 * directions below the horizon for 3 pairs in 4 and above it (toward
 * the sky, past the bunny) for the fourth. The ground's bias
 * (0.01 R = 0.07) is a band of about that height in which even a
 * correct CSM lights points behind the plane, hence the heights.
 *
 * Set A is occluded by construction (below the horizon, under the
 * bunny: "never lit" agrees on 99 %), so on A only the occluded pairs
 * shadowed are required (the shell's purpose; open surfaces leak).
 * Set B holds both answers: the shell must shadow what lies below the
 * plane and must not shadow the sky above it, scored against the
 * trivial answers (vis_score.h). */
static void score_open_pairs(open_scene *o, open_tally *t)
{
    underside u = make_underside(o);
    uint32_t rng = gi_rng_init(11, 0, 1);
    const float texel = 2.0f * o->spheres[0][3] / (float)o->M;
    memset(t, 0, sizeof *t);
    for (int kind = 0; kind < 2; kind++)
        for (int p = 0; p < OPEN_PAIRS;) {
            gi_vec3 x, w, n = gi_v3(0, 1, 0);
            if (!sample_receiver(o, &u, kind, texel, &rng, &x, &n))
                continue;
            w = gi_sample_uniform_sphere(gi_rng_next_float(&rng), gi_rng_next_float(&rng));
            int upward = kind == 1 && p % 4 == 3;
            if ((upward ? w.y < 0.1f : w.y > -0.1f) || (kind == 0 && gi_v3_dot(w, n) < 0.1f))
                continue;
            int exact = !gi_rt_occluded(o->rt, x, w, 1e-4f, INFINITY);
            t->occluded[kind] += !exact;
            for (int v = 0; v < VARIANTS; v++) {
                const gi_csm_data *dv[2] = {&o->data[v][0], &o->data[v][1]};
                int lit = csm_lit(o->gs, o->ks, dv, o->spheres, 2, o->N, x, w);
                t->agree[v][kind] += lit == exact;
                t->agree_occ[v][kind] += !exact && !lit;
                vis_add(&t->score[v][kind], exact, lit);
            }
            p++;
        }
    free(u.cdf);
    free(u.tp);
}

/* Prints part 2's pair counts and checks them; returns the failures. */
static int check_open_pairs(const open_tally *t)
{
    int fails = 0;
    static const char *kinds[2] = {"bunny underside", "above the ground"};
    for (int kind = 0; kind < 2; kind++)
        for (int v = 0; v < VARIANTS; v++)
            printf("open surfaces, %s, %s: %d pairs (%d occluded): %.1f%% agree with ray casting, "
                   "%.1f%% of the occluded ones shadowed\n",
                   kinds[kind], variant_names[v], OPEN_PAIRS, t->occluded[kind],
                   100.0 * t->agree[v][kind] / OPEN_PAIRS,
                   100.0 * t->agree_occ[v][kind] / (t->occluded[kind] ? t->occluded[kind] : 1));
    if (t->occluded[0] < OPEN_PAIRS * 9 / 10) {
        fprintf(stderr, "%s: only %d occluded pairs\n", kinds[0], t->occluded[0]);
        fails++;
    }
    for (int kind = 0; kind < 2; kind++) {
        for (int v = 0; v < VARIANTS; v++) {
            if (v == 1)
                continue; /* open: the leak, checked below */
            if (t->agree_occ[v][kind] < t->occluded[kind] * 95 / 100) {
                fprintf(stderr, "%s, %s: %d of %d occluded pairs shadowed\n", kinds[kind],
                        variant_names[v], t->agree_occ[v][kind], t->occluded[kind]);
                fails++;
            }
            char what[128];
            snprintf(what, sizeof what, "open surfaces, %s, %s", kinds[kind], variant_names[v]);
            if (kind == 1) {
                if (t->agree[v][kind] < OPEN_PAIRS * 95 / 100) {
                    fprintf(stderr, "%s, %s: %d of %d agree\n", kinds[kind], variant_names[v],
                            t->agree[v][kind], OPEN_PAIRS);
                    fails++;
                }
                fails += vis_check(&t->score[v][kind], what, VIS_MARGIN, 100);
            }
        }
        if (t->agree_occ[1][kind] > t->occluded[kind] / 2) {
            fprintf(stderr, "%s, open: %d of %d occluded pairs shadowed: the leak is gone?\n",
                    kinds[kind], t->agree_occ[1][kind], t->occluded[kind]);
            fails++;
        }
    }
    return fails;
}

/* A point light 1 below the ground's centre: the ground's cube-map CSM
 * (radial depth) for points 0.1..0.4 above the ground within 2 of the
 * centre, all occluded by the ground. Returns the failures. */
static int point_light_below_ground(const open_scene *o)
{
    int fails = 0;
    gi_error err;
    const uint32_t kg = o->ks[1];
    float gs_[4];
    memcpy(gs_, o->spheres[1], sizeof gs_);
    float inv[16];
    gi_mat4_invert(inv, o->gs->world_from_local[kg]);
    gi_vec3 light = gi_v3(0.0f, -1.0f, 0.0f);
    int cube_shadowed[2] = {0, 0}, cube_occluded = 0;
    for (int v = 0; v < 2; v++) {
        csm_local_desc d = {.M = o->M,
                            .o = gi_mat4_point(inv, light),
                            .n_u = 1,
                            .n_v = 1,
                            .order = GI_CSM_ORDER_SCANLINE,
                            .shell = v == 0 ? SHELL * gs_[3] : 0.0f,
                            .batch = 6};
        gi_csm_data cd;
        if (csm_build_local(o->gs, kg, gs_, &d, NULL, 0, 1, &cd, &err) != GI_OK) {
            fprintf(stderr, "%s\n", err.text);
            fails++;
            continue;
        }
        uint32_t r2 = gi_rng_init(12, 0, 1);
        for (int p = 0; p < 500; p++) {
            gi_vec3 x = gi_v3(2.0f * (2.0f * gi_rng_next_float(&r2) - 1.0f),
                              0.1f + 0.3f * gi_rng_next_float(&r2),
                              2.0f * (2.0f * gi_rng_next_float(&r2) - 1.0f));
            gi_vec3 to = gi_v3_sub(light, x);
            if (v == 0)
                cube_occluded += gi_rt_occluded(o->rt, x, to, 1e-4f, 1.0f - 1e-4f);
            cube_shadowed[v] +=
                !csm_local_visible_nearest(&cd, &d, gi_mat4_point(inv, x), 0, 0, 0.01f * gs_[3]);
        }
        gi_csm_data_free(&cd);
    }
    printf("open surfaces, point light below the ground (cube map): %d of 500 pairs occluded; "
           "shadowed: shell %d, "
           "open %d\n",
           cube_occluded, cube_shadowed[0], cube_shadowed[1]);
    if (cube_shadowed[0] < cube_occluded * 95 / 100 || cube_shadowed[1] > cube_occluded / 2) {
        fprintf(stderr, "cube map: shell %d, open %d of %d occluded\n", cube_shadowed[0],
                cube_shadowed[1], cube_occluded);
        fails++;
    }
    return fails;
}

/* Part 2: open surfaces. Returns the number of failed checks. */
static int open_surfaces(const gi_scene *s, const gi_gpu_scene *gs, uint32_t kb)
{
    gi_error err;
    open_scene o = {.s = s, .gs = gs, .N = 8, .M = 64};
    uint32_t kg = 0;
    while (kg < s->object_count && strcmp(s->objects[kg].name, "ground") != 0)
        kg++;
    if (kg == s->object_count || gi_rt_create(s, 0.0f, &o.rt, &err) != GI_OK) {
        fprintf(stderr, "no ground object / ray casting failed\n");
        return 1;
    }
    o.ks[0] = kb;
    o.ks[1] = kg;
    gi_mesh_object_sphere(s, kb, o.spheres[0]);
    gi_mesh_object_sphere(s, kg, o.spheres[1]);
    int fails = build_variants(&o);
    if (fails)
        return fails;
    printf("ground: R = %.3f, %u maps of %u^2: %.2f segments per texel with the shell, %.2f open\n",
           (double)o.spheres[1][3], o.N * o.N, o.M,
           (double)o.data[0][1].segment_count / (o.M * o.M),
           (double)o.data[1][1].segment_count / (o.M * o.M));
    open_tally t;
    score_open_pairs(&o, &t);
    fails += check_open_pairs(&t);
    fails += point_light_below_ground(&o);
    for (int v = 0; v < VARIANTS; v++)
        for (int i = 0; i < 2; i++)
            gi_csm_data_free(&o.data[v][i]);
    gi_rt_free(o.rt);
    return fails;
}

/* The spherical far plane (csm_sphere_far, depth=sphere): on an
 * orthographic map of the bunny's sphere (eye 2R from the centre) the exit
 * depth of texel (i, j) is 2R + sqrt(R^2 - r^2), r the texel centre's
 * distance from the axis; on a cube face at a point p inside the sphere the
 * radial exit depth t puts p + t d on the sphere, d the texel's direction
 * (x, y, -1) in the face's eye space (90 degree field of view). Returns the
 * number of failures. */
static int sphere_far_plane(const float sphere[4])
{
    const uint32_t M = 32;
    float far[32 * 32];
    int fails = 0;
    double worst = 0;
    gi_depth_view v;
    csm_map_view(sphere, 1.1f, 2.3f, &v);
    csm_sphere_far(&v, GI_DEPTH_EYE_Z, sphere, M, far);
    const double R = sphere[3];
    for (uint32_t j = 0; j < M; j++)
        for (uint32_t i = 0; i < M; i++) {
            double x = ((i + 0.5) / M * 2 - 1) * R, y = ((j + 0.5) / M * 2 - 1) * R,
                   r2 = x * x + y * y;
            double want = r2 <= R * R ? 2 * R + sqrt(R * R - r2) : FLT_MAX;
            double got = far[j * M + i];
            if (want == FLT_MAX ? got != FLT_MAX : fabs(got - want) > 1e-4 * R) {
                fails++;
            } else if (want != FLT_MAX && fabs(got - want) / R > worst) {
                worst = fabs(got - want) / R;
            }
        }
    gi_vec3 c = gi_v3(sphere[0], sphere[1], sphere[2]);
    gi_vec3 p = gi_v3_add(c, gi_v3(0.3f * sphere[3], -0.2f * sphere[3], 0.1f * sphere[3]));
    gi_depth_view cube[6];
    gi_depth_cube_views(p, 1e-3f * sphere[3], 4.0f * sphere[3], cube);
    for (int face = 0; face < 6; face++) {
        float inv[16];
        gi_mat4_invert(inv, cube[face].view);
        csm_sphere_far(&cube[face], GI_DEPTH_RADIAL, sphere, M, far);
        for (uint32_t j = 0; j < M; j++)
            for (uint32_t i = 0; i < M; i++) {
                gi_vec3 d =
                    gi_mat4_dir(inv, gi_v3((i + 0.5f) / M * 2 - 1, (j + 0.5f) / M * 2 - 1, -1.0f));
                gi_vec3 q = gi_v3_add(p, gi_v3_scale(gi_v3_normalize(d), far[j * M + i]));
                double off = fabs(gi_v3_length(gi_v3_sub(q, c)) - R) / R;
                if (off > 1e-4)
                    fails++;
                worst = off > worst ? off : worst;
            }
    }
    printf("spherical far plane: worst relative error %.2g (orthographic map and 6 cube faces of "
           "%u^2)\n",
           worst, M);
    if (fails)
        fprintf(stderr, "spherical far plane: %d texels off\n", fails);
    return fails;
}

/* Part 1's bunny: its CSM (N = 8 x 8 directions, M = 64) and what the
 * checks on it share. */
typedef struct bunny {
    const gi_scene *s;
    const gi_gpu_scene *gs;
    uint32_t k; /* the bunny's object */
    float sphere[4];
    csm_build_desc desc;
    gi_csm_data data;
} bunny;

/* Lossless on real maps. Returns 0 when the depth renderer cannot be made. */
static int check_lossless(const bunny *bn)
{
    const uint32_t N = bn->desc.n_theta, M = bn->desc.M;
    gi_error err;
    /* the maps as plugins/csm/precompute.c renders them (receiver_side) */
    gi_depth_desc dd = {.size = M,
                        .surfaces = 2,
                        .metric = GI_DEPTH_EYE_Z,
                        .only_object = bn->k + 1u,
                        .local = 1,
                        .receiver_side = GI_SIDES_BOTH};
    gi_depth_renderer *dr = gi_depth_renderer_create(&dd, &err);
    if (!dr) {
        fprintf(stderr, "set-up failed: depth renderer: %s\n", err.text);
        return 0;
    }
    GLuint tex = gi_depth_texture_create(dr, 1);
    uint64_t bad = 0, checked = 0, degenerate = 0;
    for (uint32_t i = 0; i < N * N; i += 3) {
        uint32_t a, b;
        float theta, phi;
        gi_csm_order_cell(bn->desc.order, N, N, i, &a, &b);
        csm_cell_angles(N, N, a, b, &theta, &phi);
        gi_depth_view v;
        csm_map_view(bn->sphere, theta, phi, &v);
        EXPECT(gi_depth_render(dr, bn->gs, &v, 1, tex, 0, &err) == GI_OK, "%s", err.text);
        float *map = gi_depth_read_layer(tex, M, 0);
        for (uint32_t t = 0; t < M * M; t++) {
            float z1 = map[4 * t], z2 = map[4 * t + 1], z = gi_csm_lookup(&bn->data, t, i);
            int deg = z1 == z2 && z1 < FLT_MAX;
            degenerate += deg;
            int ok = z >= z1 && (z2 >= FLT_MAX || z < z2 || (deg && z == z1));
            bad += !ok;
            checked++;
        }
        free(map);
    }
    printf("lossless: %llu of %llu texels violate z1 <= z_avg < z2 (%llu degenerate)\n",
           (unsigned long long)bad, (unsigned long long)checked, (unsigned long long)degenerate);
    EXPECT(bad == 0, "%llu texels", (unsigned long long)bad);
    glDeleteTextures(1, &tex);
    gi_depth_renderer_free(dr);
    return 1;
}

enum { BUNNY_PAIRS = 2000 };

/* Part 1's pairs (x, w) as the GLSL check uploads them (8 floats: x, 1,
 * w, 0), with the CPU query's and ray casting's answers. */
typedef struct bunny_pairs {
    float *pin;
    int *cpu_lit, *exact_lit;
} bunny_pairs;

/* Visibility against ray casting. */
static void check_cpu_query(const bunny *bn, bunny_pairs *bp)
{
    const gi_scene *s = bn->s;
    const uint32_t N = bn->desc.n_theta, k = bn->k;
    const float *sphere = bn->sphere;
    uint32_t rng = gi_rng_init(7, 0, 1);
    gi_vec3 c = gi_v3(sphere[0], sphere[1], sphere[2]);
    float R = sphere[3], bias = 0.01f * R;
    int pairs = 0, agree = 0, agree_snapped = 0, shadowed = 0, inside = 0;
    vis_score score_w = {0}, score_snapped = {0};
    while (pairs < BUNNY_PAIRS) {
        gi_vec3 x = gi_v3_add(c, gi_v3_scale(gi_sample_uniform_sphere(gi_rng_next_float(&rng),
                                                                      gi_rng_next_float(&rng)),
                                             1.5f * R * cbrtf(gi_rng_next_float(&rng))));
        gi_vec3 w = gi_sample_uniform_sphere(gi_rng_next_float(&rng), gi_rng_next_float(&rng));
        int hw = hits(s, k, x, w);
        if ((hw & 1) && (hits(s, k, x, gi_v3_scale(w, -1)) & 1)) {
            inside++;
            continue;
        }
        int exact = hw == 0;
        int lit = gi_csm_dir_visible(&bn->data, sphere, N, N, bn->desc.order, x, w, bias);
        float *q = bp->pin + 8 * pairs;
        q[0] = x.x, q[1] = x.y, q[2] = x.z, q[3] = 1, q[4] = w.x, q[5] = w.y, q[6] = w.z, q[7] = 0;
        bp->cpu_lit[pairs] = lit;
        bp->exact_lit[pairs] = exact;
        pairs++;
        float u, v, theta, phi;
        csm_grid_coords(w, N, N, &u, &v);
        int bi = (int)floorf(v + 0.5f);
        csm_cell_angles(N, N, (uint32_t)floorf(u + 0.5f) % N,
                        (uint32_t)(bi < 0         ? 0
                                   : bi >= (int)N ? (int)N - 1
                                                  : bi),
                        &theta, &phi);
        int exact_snapped = hits(s, k, x, csm_dir(theta, phi)) == 0;
        shadowed += !exact;
        agree += lit == exact;
        agree_snapped += lit == exact_snapped;
        vis_add(&score_w, exact, lit);
        vis_add(&score_snapped, exact_snapped, lit);
    }
    printf("visibility, %d pairs (%d shadowed, %d inside points skipped): %.1f%% agree with rays "
           "along w, "
           "%.1f%% with rays along the snapped map direction\n",
           pairs, shadowed, inside, 100.0 * agree / pairs, 100.0 * agree_snapped / pairs);
    EXPECT(agree >= pairs * 90 / 100, "%d of %d", agree, pairs);
    EXPECT(agree_snapped >= pairs * 97 / 100, "%d of %d", agree_snapped, pairs);
    gi_test_failed += vis_check(&score_w, "bunny, nearest CSM vs rays along w", VIS_MARGIN, 100);
    gi_test_failed +=
        vis_check(&score_snapped, "bunny, nearest CSM vs rays along the snapped map direction",
                  VIS_MARGIN, 100);
}

static const char *query_kernel =
    "#include \"csm_query.glsl\"\n"
    "layout(local_size_x = 64) in;\n"
    "layout(std430, binding = 0) readonly buffer In { vec4 pin[]; };\n"
    "layout(std430, binding = 1) writeonly buffer Out { vec4 pout[]; };\n"
    "uniform uint u_count;\n"
    "void main() {\n"
    "    uint c = gl_GlobalInvocationID.x;\n"
    "    if (c >= u_count) return;\n"
    "    vec3 x = pin[2u * c].xyz, w = pin[2u * c + 1u].xyz;\n"
    "    float rr = 0.0;\n"
    "    for (int j = 0; j < 256; j++) rr += csm_visibility_object(0u, x, vec3(0.0), w, 2, "
    "(float(j) + 0.5) / 256.0);\n"
    "    pout[c] = vec4(csm_visibility_object(0u, x, vec3(0.0), w, 0, 0.0),\n"
    "                   csm_visibility_object(0u, x, vec3(0.0), w, 1, 0.0), rr / 256.0, 0.0);\n"
    "}\n";

/* §4.6: the object moved rigidly (rotation, translation, uniform
 * scale); the pairs go to the GPU in world space and the query takes
 * them back with local_from_world. */
static void move_rigidly(csm_gpu_object *obj, float *pin)
{
    const float tr[3] = {0.7f, -0.3f, 2.0f}, q[4] = {0.2f, 0.5f, -0.1f, 0.8f},
                sc[3] = {1.5f, 1.5f, 1.5f};
    float qn[4];
    memcpy(qn, q, sizeof q);
    gi_quat_normalize(qn);
    gi_mat4_trs(obj->world_from_local, tr, qn, sc);
    gi_mat4_invert(obj->local_from_world, obj->world_from_local);
    for (int p = 0; p < BUNNY_PAIRS; p++) {
        float *e = pin + 8 * p;
        gi_vec3 xw = gi_mat4_point(obj->world_from_local, gi_v3(e[0], e[1], e[2]));
        gi_vec3 ww = gi_v3_normalize(gi_mat4_dir(obj->world_from_local, gi_v3(e[4], e[5], e[6])));
        e[0] = xw.x, e[1] = xw.y, e[2] = xw.z, e[4] = ww.x, e[5] = ww.y, e[6] = ww.z;
    }
}

/* The query kernel's results on the pairs, 4 floats each, with the CSM
 * uploaded as the plugin does; zeros when the kernel did not build. */
static float *run_query_kernel(GLuint prog, const bunny *bn, const csm_gpu_object *obj,
                               const float *pin)
{
    const uint32_t N = bn->desc.n_theta, M = bn->desc.M;
    const gi_csm_data *data = &bn->data;
    uint32_t cells[64];
    for (uint32_t b = 0; b < N; b++)
        for (uint32_t a = 0; a < N; a++)
            cells[b * N + a] = gi_csm_order_index(bn->desc.order, N, N, a, b);
    GLuint bufs[7];
    glCreateBuffers(7, bufs);
    glNamedBufferStorage(bufs[0], (GLsizeiptr)(sizeof(float) * 8 * BUNNY_PAIRS), pin, 0);
    glNamedBufferStorage(bufs[1], (GLsizeiptr)(sizeof(float) * 4 * BUNNY_PAIRS), NULL, 0);
    glNamedBufferStorage(bufs[2], (GLsizeiptr)sizeof *obj, obj, 0);
    glNamedBufferStorage(bufs[3], (GLsizeiptr)(sizeof(uint32_t) * (M * M + 1)), data->offsets, 0);
    glNamedBufferStorage(bufs[4], (GLsizeiptr)(sizeof(float) * data->segment_count), data->z_avg,
                         0);
    glNamedBufferStorage(bufs[5], (GLsizeiptr)(sizeof(uint32_t) * data->segment_count), data->i_end,
                         0);
    glNamedBufferStorage(bufs[6], (GLsizeiptr)sizeof cells, cells, 0);
    static const GLuint binding[7] = {0, 1, 8, 9, 10, 11, 12};
    for (int i = 0; i < 7; i++)
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, binding[i], bufs[i]);
    float *gout = calloc(4 * BUNNY_PAIRS, sizeof(float));
    if (prog) {
        glUseProgram(prog);
        glUniform1ui(glGetUniformLocation(prog, "u_count"), BUNNY_PAIRS);
        glUniform1ui(glGetUniformLocation(prog, "csm_n_theta"), N);
        glUniform1ui(glGetUniformLocation(prog, "csm_n_phi"), N);
        csm_test_dispatch_read(BUNNY_PAIRS, bufs[1], (GLsizeiptr)(sizeof(float) * 4 * BUNNY_PAIRS),
                               gout);
        glUseProgram(0);
        glDeleteProgram(prog);
    }
    glDeleteBuffers(7, bufs);
    return gout;
}

/* The GLSL query on the same pairs. */
static void check_glsl_query(const bunny *bn, const bunny_pairs *bp)
{
    gi_error err;
    EXPECT(gi_shader_register(gi_csm_query_shaders, NULL) == GI_OK, "shader table refused");
    GLuint prog = gi_program_build_compute_text("plugins/csm/tests/csm_query_kernel.comp",
                                                query_kernel, NULL, &err);
    EXPECT(prog != 0, "%s", err.text);
    csm_gpu_object obj;
    memset(&obj, 0, sizeof obj);
    move_rigidly(&obj, bp->pin);
    float bias = 0.01f * bn->sphere[3];
    memcpy(obj.sphere, bn->sphere, sizeof obj.sphere);
    obj.M = bn->desc.M;
    memcpy(&obj.bias_bits, &bias, sizeof bias);
    float *gout = run_query_kernel(prog, bn, &obj, bp->pin);
    int gpu_same = 0, pcf_agree = 0;
    vis_score score_pcf = {0};
    for (int p = 0; p < BUNNY_PAIRS; p++) {
        gpu_same += (gout[4 * p] > 0.5f) == (bp->cpu_lit[p] != 0);
        pcf_agree += (gout[4 * p + 1] >= 0.5f) == (bp->exact_lit[p] != 0);
        vis_add(&score_pcf, bp->exact_lit[p], gout[4 * p + 1] >= 0.5f);
    }
    double rr_err_mean, rr_err_max;
    csm_test_rr_error(gout, BUNNY_PAIRS, &rr_err_mean, &rr_err_max);
    printf("GLSL query (moved object): nearest equals the CPU query on %d of %d pairs; PCF >= 1/2 "
           "agrees with ray casting on %.1f%%; "
           "RR averaged over 256 stratified numbers vs PCF: mean |diff| %.4f, max %.4f\n",
           gpu_same, BUNNY_PAIRS, 100.0 * pcf_agree / BUNNY_PAIRS, rr_err_mean, rr_err_max);
    EXPECT(gpu_same >= BUNNY_PAIRS - 2, "%d of %d", gpu_same,
           BUNNY_PAIRS); /* texel-edge rounding may flip one or two */
    EXPECT(pcf_agree >= BUNNY_PAIRS * 90 / 100, "%d of %d", pcf_agree, BUNNY_PAIRS);
    gi_test_failed +=
        vis_check(&score_pcf, "bunny, GLSL PCF >= 1/2 vs rays along w", VIS_MARGIN, 100);
    EXPECT(rr_err_mean < 0.01 && rr_err_max <= 16.0 / 256.0 + 1e-3, "mean %g max %g", rr_err_mean,
           rr_err_max);
    free(gout);
}

int main(void)
{
    gi_gpu *gpu = csm_test_gpu(NULL);
    if (!gpu)
        return 1;
    gi_error err;
    gi_scene *s = gi_scene_load(GI_SOURCE_DIR "/scenes/bunny_env.glb", &err);
    if (!s) {
        fprintf(stderr, "%s\n", err.text);
        return 1;
    }
    gi_gpu_scene *gs = gi_gpu_scene_upload(gpu, s, &err);
    bunny bn = {.s = s, .gs = gs};
    while (bn.k < s->object_count && strcmp(s->objects[bn.k].name, "bunny") != 0)
        bn.k++;
    if (!gs || bn.k == s->object_count) {
        fprintf(stderr, "no bunny object / upload failed\n");
        return 1;
    }
    gi_mesh_object_sphere(s, bn.k, bn.sphere);
    const uint32_t N = 8, M = 64;
    bn.desc = (csm_build_desc){.M = M,
                               .n_theta = N,
                               .n_phi = N,
                               .order = GI_CSM_ORDER_HILBERT,
                               .z3 = 0,
                               .shell = SHELL * bn.sphere[3],
                               .batch = 16};
    if (csm_build_object(gs, bn.k, bn.sphere, &bn.desc, NULL, 0, 1, &bn.data, &err) != GI_OK) {
        fprintf(stderr, "set-up failed: the bunny's CSM: %s\n", err.text);
        return 1;
    }
    printf("bunny: R = %.4f, %u maps of %u^2: %.2f segments per texel, %.2f : 1\n",
           (double)bn.sphere[3], N * N, M, (double)bn.data.segment_count / (M * M),
           (double)bn.data.bytes_uncompressed / (double)bn.data.bytes_compressed);
    if (!check_lossless(&bn))
        return 1;
    bunny_pairs bp = {malloc(sizeof(float) * 8 * BUNNY_PAIRS), malloc(sizeof(int) * BUNNY_PAIRS),
                      malloc(sizeof(int) * BUNNY_PAIRS)};
    check_cpu_query(&bn, &bp);
    check_glsl_query(&bn, &bp);
    free(bp.pin);
    free(bp.cpu_lit);
    free(bp.exact_lit);

    gi_test_failed += open_surfaces(s, gs, bn.k);
    gi_test_failed += sphere_far_plane(bn.sphere);

    gi_csm_data_free(&bn.data);
    gi_gpu_scene_free(gs);
    gi_scene_free(s);
    gi_gpu_destroy(gpu);
    printf("%s\n", gi_test_failed ? "FAILED" : "ok");
    return gi_test_failed ? 1 : 0;
}
