/* The vlf plugin's parts against independent computations (the plugin's
 * CPU sources are compiled in; see plugins/vlf/README.md "Tests"):
 *
 *   vlf_tests dirs     the direction set covers the sphere evenly (largest
 *                      angular gap to the nearest direction bounded), the
 *                      triangulation is a closed sphere (Euler, solid angles
 *                      sum to 4 pi, every direction in at least 3 triangles,
 *                      each triangle counter-clockwise), barycentric weights
 *                      of random directions are non-negative, sum to 1 and
 *                      reproduce the direction; a node gets weight 1 itself;
 *   vlf_tests order    the depth order on random non-intersecting triangles,
 *                      pinwheels of cyclically overlapping sticks among
 *                      them: the faces along every ray of every subfield,
 *                      in order, equal the Embree hits along the ray, for
 *                      the face order (Newell with splitting, with and
 *                      without BSP cuts) and the per-ray sort, while the
 *                      plain sort by nearest depth fails; the face order
 *                      is the same on 1, 2 and 5 threads;
 *   vlf_tests energy   closed box: per iteration everything shot is received
 *                      (nothing escapes, nothing lands on a back face), and
 *                      the emitted flux equals the first iteration's shot;
 *                      perturbed directions sorted beside the sweeps give
 *                      the same field on 1, 2 and 5 threads;
 *   vlf_tests furnace  the closed emitting sphere (conformance scene):
 *                      the mean irradiance of the propagated field converges
 *                      to Le (1/(1 - rho) - 1) pi within 2 % as iterations grow;
 *   vlf_tests mirror   a mirror facing an emitter: the mirror's stored
 *                      radiance in the subfields around the reflected
 *                      direction shows the emitter (ks Le), and nothing where
 *                      the reflection misses it;
 *   vlf_tests precision the storage formats (RGBA16F, RGB9E5): encoders,
 *                      the propagated maps against float32 on the glossy
 *                      Cornell box, and the reported memory against the
 *                      packed bytes;
 *   vlf_tests sun      a directional light: open floor lit by E cos theta,
 *                      an occluder's shadow where it falls;
 *   vlf_tests point    point and spot lights: inverse square law, shadow,
 *                      spot cone; a point light's reflection in a mirror;
 *   vlf_tests albedo   the glossy lobe's albedo over incidence (its grazing
 *                      fall-off) against Monte Carlo of core brdf.h's lobe;
 *   vlf_tests texture  a textured floor: each element's albedo averages the
 *                      texture over it, and propagation shoots with it;
 *   vlf_tests hier     the hierarchical shortcut of the sort (objects in
 *                      boxes nothing else reaches into sorted on their own)
 *                      keeps the depth order right (Embree) and saves tests;
 *   vlf_tests gpu      propagation by the GL compute passes equals the
 *                      CPU's (glossy Cornell box in the three storage
 *                      formats, a sky-lit scene, a textured one with a
 *                      double-sided teapot);
 *   vlf_tests double   a double-sided panel lit from its back: the lit
 *                      side's irradiance against the light's integral,
 *                      nothing through the panel, the per-ray sort and
 *                      perturbed directions agree; single-sided, the same
 *                      light lands on its back. */
#include "vlf_field.h"
#include "vlf_gpu.h"

#include "gi/brdf.h"
#include "gi/gpu.h"
#include "gi/lights.h"
#include "gi/shader.h"
#include "gi/raytrace.h"
#include "gi/rng.h"
#include "gi/scene.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#define EXPECT CHECK_MSG

extern const gi_shader_source gi_vlf_shaders[];

static gi_scene *load(const char *rel)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", GI_SOURCE_DIR, rel);
    gi_error err;
    gi_scene *s = gi_scene_load(path, &err);
    EXPECT(s != NULL, "loading %s: %s", path, err.text);
    return s;
}

static vlf_settings defaults(void)
{
    return (vlf_settings){.l = 128,
                          .N = 64,
                          .m = 8,
                          .S = 2,
                          .density = 12,
                          .iterations = 8,
                          .seed = 1,
                          .order = VLF_ORDER_FACES,
                          .threads = 2,
                          .bsp_levels = 2,
                          .bsp_min = 4096,
                          .subdivide = 1};
}

static float frand(uint32_t *s)
{
    *s = *s * 1664525u + 1013904223u;
    return (float)(*s >> 8) / 16777216.0f;
}

static gi_vec3 rand_dir(uint32_t *s)
{
    float z = 2.0f * frand(s) - 1.0f, phi = 2.0f * GI_PI * frand(s);
    float r = sqrtf(fmaxf(0.0f, 1.0f - z * z));
    return gi_v3(r * cosf(phi), r * sinf(phi), z);
}

static void test_dirs(void)
{
    uint32_t ls[] = {8, 32, 128, 512};
    for (size_t li = 0; li < sizeof ls / sizeof ls[0]; li++) {
        vlf_dirs d;
        gi_error err;
        uint32_t l = ls[li];
        EXPECT(vlf_dirs_build(&d, l, &err) == GI_OK, "%s", err.text);
        uint32_t n = 2 * l;
        /* closed triangulated sphere: V - E + F = 2 with E = 3F/2 */
        EXPECT(d.tri_count == 2 * n - 4, "l=%u: %u triangles for %u nodes", l, d.tri_count, n);
        double sum = 0.0;
        for (uint32_t k = 0; k < n; k++)
            sum += d.solid_angle[k];
        CHECK_NEAR(sum, 4.0 * GI_PI, 1e-3);
        /* solid angles of the nodes within a factor of 2 of the mean */
        float mean = (float)(4.0 * GI_PI / n), lo = FLT_MAX, hi = 0;
        for (uint32_t k = 0; k < n; k++)
            lo = fminf(lo, d.solid_angle[k]), hi = fmaxf(hi, d.solid_angle[k]);
        EXPECT(lo > 0.5f * mean && hi < 2.0f * mean, "l=%u: solid angles %.4g..%.4g, mean %.4g", l,
               lo, hi, mean);
        uint32_t *deg = calloc(n, sizeof *deg);
        int ccw = 1;
        for (uint32_t t = 0; t < d.tri_count; t++) {
            gi_vec3 a = d.signed_dirs[d.tris[3 * t]], b = d.signed_dirs[d.tris[3 * t + 1]],
                    c = d.signed_dirs[d.tris[3 * t + 2]];
            if (gi_v3_dot(gi_v3_cross(gi_v3_sub(b, a), gi_v3_sub(c, a)), a) <= 0.0f)
                ccw = 0;
            for (int j = 0; j < 3; j++)
                deg[d.tris[3 * t + j]]++;
        }
        EXPECT(ccw, "l=%u: a triangle is not counter-clockwise seen from outside", l);
        uint32_t mindeg = UINT32_MAX;
        for (uint32_t k = 0; k < n; k++)
            mindeg = deg[k] < mindeg ? deg[k] : mindeg;
        EXPECT(mindeg >= 3, "l=%u: a direction lies in %u triangles", l, mindeg);
        free(deg);
        /* coverage: largest angle from a random direction to its nearest node,
         * against the cap radius of an even spread (acos(1 - 2/n)) times 1.6 */
        uint32_t seed = 12345u;
        float worst = 0.0f, bad_sum = 0.0f, worst_rec = 0.0f;
        for (int q = 0; q < 20000; q++) {
            gi_vec3 w = rand_dir(&seed);
            float best = -2.0f;
            for (uint32_t k = 0; k < n; k++)
                best = fmaxf(best, gi_v3_dot(w, d.signed_dirs[k]));
            worst = fmaxf(worst, acosf(fminf(1.0f, best)));
            uint32_t node[3];
            float al[3];
            vlf_dirs_locate(&d, w, node, al);
            float s = al[0] + al[1] + al[2];
            bad_sum = fmaxf(bad_sum, fabsf(s - 1.0f));
            EXPECT(al[0] >= 0 && al[1] >= 0 && al[2] >= 0, "negative weight");
            /* the weights reproduce the direction up to its length */
            gi_vec3 r = gi_v3_add(gi_v3_add(gi_v3_scale(d.signed_dirs[node[0]], al[0]),
                                            gi_v3_scale(d.signed_dirs[node[1]], al[1])),
                                  gi_v3_scale(d.signed_dirs[node[2]], al[2]));
            worst_rec = fmaxf(worst_rec, acosf(fminf(1.0f, gi_v3_dot(gi_v3_normalize(r), w))));
        }
        float cap = acosf(1.0f - 2.0f / (float)n);
        printf("dirs l=%u: %u triangles, largest gap %.2f deg (even-spread cap %.2f deg), solid "
               "angles %.4f..%.4f sr\n",
               l, d.tri_count, worst * 180 / GI_PI, cap * 180 / GI_PI, lo, hi);
        EXPECT(worst < 1.6f * cap, "l=%u: gap %.3g rad > 1.6 x %.3g", l, worst, cap);
        EXPECT(bad_sum < 1e-5f, "l=%u: weights sum off by %.3g", l, bad_sum);
        EXPECT(worst_rec < 1e-3f, "l=%u: interpolated direction off by %.3g rad", l, worst_rec);
        /* a node itself: weight 1 on it */
        int node_ok = 1;
        for (uint32_t k = 0; k < n; k++) {
            uint32_t node[3];
            float al[3];
            vlf_dirs_locate(&d, d.signed_dirs[k], node, al);
            float wk = 0.0f;
            for (int j = 0; j < 3; j++)
                if (node[j] == k)
                    wk += al[j];
            if (wk < 0.999f)
                node_ok = 0;
        }
        EXPECT(node_ok, "l=%u: a node does not get weight 1 at itself", l);
        vlf_dirs_free(&d);
    }
}

/* A hand-built test scene, zeroed: `triangles` triangles and `vertices`
 * vertices in one object on node 0, `materials` untextured black
 * materials, `nodes` identity nodes without parents. Freed by
 * gi_scene_free(). */
static gi_scene *bare_scene(uint32_t triangles, uint32_t vertices, uint32_t materials,
                            uint32_t nodes)
{
    gi_scene *s = calloc(1, sizeof *s);
    s->triangle_count = triangles;
    s->vertex_count = vertices;
    s->vertices = calloc(vertices, sizeof *s->vertices);
    s->indices = calloc(3 * (size_t)triangles, sizeof *s->indices);
    s->material_count = materials;
    s->materials = calloc(materials, sizeof *s->materials);
    for (uint32_t m = 0; m < materials; m++)
        s->materials[m].albedo_texture = -1;
    s->node_count = nodes;
    s->nodes = calloc(nodes, sizeof *s->nodes);
    for (uint32_t n = 0; n < nodes; n++) {
        s->nodes[n].parent = -1;
        s->nodes[n].rotation[3] = 1.0f;
        s->nodes[n].scale[0] = s->nodes[n].scale[1] = s->nodes[n].scale[2] = 1.0f;
    }
    s->object_count = 1;
    s->objects = calloc(1, sizeof *s->objects);
    s->objects[0].triangle_count = triangles;
    s->objects[0].vertex_count = vertices;
    return s;
}

/* A scene of the triangles tri[0 .. 9 count) (3 corners each), one material. */
static gi_scene *triangle_scene(const float *tri, uint32_t count)
{
    gi_scene *s = bare_scene(count, 3 * count, 1, 1);
    s->materials[0].albedo[0] = s->materials[0].albedo[1] = s->materials[0].albedo[2] = 0.5f;
    float lo[3] = {FLT_MAX, FLT_MAX, FLT_MAX}, hi[3] = {-FLT_MAX, -FLT_MAX, -FLT_MAX};
    for (uint32_t k = 0; k < 3 * count; k++) {
        gi_vertex *v = &s->vertices[k];
        memcpy(v->position, tri + 3 * (size_t)k, 3 * sizeof(float));
        v->normal[2] = 1.0f;
        s->indices[k] = k;
        for (int a = 0; a < 3; a++)
            lo[a] = fminf(lo[a], v->position[a]), hi[a] = fmaxf(hi[a], v->position[a]);
    }
    for (int a = 0; a < 3; a++)
        s->objects[0].local_bounds[a] = lo[a], s->objects[0].local_bounds[3 + a] = hi[a];
    return s;
}

static void put(float **w, gi_vec3 p)
{
    (*w)[0] = p.x, (*w)[1] = p.y, (*w)[2] = p.z;
    *w += 3;
}

/* Random non-intersecting triangles: one small triangle of random
 * orientation in each of the first `single` cells of a 4 x 4 x 4 grid, and
 * in each of the next `cyclic` cells a pinwheel of three sticks (quads of
 * two triangles) along the sides of a triangle, each rising from one corner
 * to the next: every stick lies over the next one where they cross, so
 * that the three overlap in a cycle seen from around the pinwheel's axis
 * (random) and no order of whole faces is right there. Each cell's shape
 * stays inside a ball of radius 0.45 around the cell's centre. */
static gi_scene *random_triangles(uint32_t single, uint32_t cyclic, uint32_t seed)
{
    uint32_t count = single + 6 * cyclic;
    float *tri = calloc((size_t)count * 9, sizeof *tri), *w = tri;
    for (uint32_t t = 0; t < single + cyclic; t++) {
        uint32_t cx = t % 4, cy = (t / 4) % 4, cz = t / 16;
        gi_vec3 c = gi_v3((float)cx + 0.5f, (float)cy + 0.5f, (float)cz + 0.5f);
        if (t < single) {
            for (int k = 0; k < 3; k++)
                put(&w, gi_v3_add(c, gi_v3_scale(rand_dir(&seed), 0.45f)));
            continue;
        }
        gi_vec3 ax = rand_dir(&seed), e1, e2;
        gi_onb(ax, &e1, &e2);
        float rot = 2.0f * GI_PI * frand(&seed);
        const float R = 0.22f, ext = 0.09f, hw = 0.06f, h = 0.06f;
        for (int j = 0; j < 3; j++) {
            float a0 = rot + 2.0f * GI_PI * (float)j / 3.0f, a1 = a0 + 2.0f * GI_PI / 3.0f;
            float p0[2] = {R * cosf(a0), R * sinf(a0)}, p1[2] = {R * cosf(a1), R * sinf(a1)};
            float d[2] = {p1[0] - p0[0], p1[1] - p0[1]}, len = sqrtf(d[0] * d[0] + d[1] * d[1]);
            d[0] /= len, d[1] /= len;
            float n[2] = {-d[1], d[0]};
            /* corners: start -hw, start +hw, end +hw, end -hw; height -h at the start, +h at the
             * end */
            float sx = p0[0] - ext * d[0], sy = p0[1] - ext * d[1], ex = p1[0] + ext * d[0],
                  ey = p1[1] + ext * d[1];
            float qx[4] = {sx - hw * n[0], sx + hw * n[0], ex + hw * n[0], ex - hw * n[0]};
            float qy[4] = {sy - hw * n[1], sy + hw * n[1], ey + hw * n[1], ey - hw * n[1]};
            float qz[4] = {-h, -h, h, h};
            gi_vec3 q[4];
            for (int k = 0; k < 4; k++)
                q[k] = gi_v3_add(
                    c, gi_v3_add(gi_v3_add(gi_v3_scale(e1, qx[k]), gi_v3_scale(e2, qy[k])),
                                 gi_v3_scale(ax, qz[k])));
            int idx[6] = {0, 1, 2, 0, 2, 3};
            for (int k = 0; k < 6; k++)
                put(&w, q[idx[k]]);
        }
    }
    gi_scene *s = triangle_scene(tri, count);
    free(tri);
    return s;
}

/* Every ray of every subfield, both ways: the faces it meets, in its
 * fragment list's order, against the faces Embree meets along the same
 * ray one hit after another. Returns the rays that hit something and
 * counts those whose whole sequence agrees. */
static uint32_t order_against_embree(const vlf_field *f, gi_rt *rt, uint32_t *agree,
                                     uint32_t *multi)
{
    uint32_t hits = 0;
    *agree = *multi = 0;
    enum { MAXH = 64 };
    for (uint32_t i = 0; i < f->prm.l; i++) {
        const vlf_psf *ps = &f->psf[i];
        uint32_t NS = f->prm.N * f->prm.S;
        for (uint32_t c = 0; c < NS * NS; c++) {
            float U = ((float)(c % NS) + 0.5f) / (float)NS * 2.0f - 1.0f;
            float V = ((float)(c / NS) + 0.5f) / (float)NS * 2.0f - 1.0f;
            for (int sign = -1; sign <= 1; sign += 2) {
                /* a world ray entering along sign * n from outside the unit sphere */
                gi_vec3 q = gi_v3_add(gi_v3_add(gi_v3_scale(ps->u, U), gi_v3_scale(ps->v, V)),
                                      gi_v3_scale(ps->n, -1.5f * (float)sign));
                gi_vec3 o = gi_v3_add(f->centre, gi_v3_scale(q, f->radius));
                gi_vec3 d = gi_v3_scale(ps->n, (float)sign);
                uint32_t want[MAXH], got[MAXH], nw = 0, ng = 0;
                float tmin = 0.0f;
                gi_rt_hit h;
                while (nw < MAXH && gi_rt_intersect(rt, o, d, tmin, FLT_MAX, &h)) {
                    uint32_t fc = f->tri_face[(size_t)h.triangle * f->tri_sub];
                    if (nw == 0 || want[nw - 1] != fc)
                        want[nw++] = fc;
                    tmin = h.t + 1e-4f;
                }
                uint32_t a = ps->cell_start[c], b = ps->cell_start[c + 1];
                for (uint32_t k = 0; k < b - a && ng < MAXH; k++) {
                    uint32_t fc = f->elem_face[ps->frag[sign > 0 ? a + k : b - 1 - k]];
                    if (ng == 0 || got[ng - 1] != fc)
                        got[ng++] = fc;
                }
                if (nw == 0 && ng == 0)
                    continue;
                hits++;
                *multi += nw > 1;
                *agree += nw == ng && memcmp(want, got, nw * sizeof *want) == 0;
            }
        }
    }
    return hits;
}

/* The field's depth lists and tile rectangles, equal byte for byte. */
static int same_field(const vlf_field *a, const vlf_field *b)
{
    if (a->prm.l != b->prm.l || a->nd_cells != b->nd_cells)
        return 0;
    uint32_t NS = a->prm.N * a->prm.S;
    for (uint32_t i = 0; i < a->prm.l; i++) {
        const vlf_psf *p = &a->psf[i], *q = &b->psf[i];
        if (p->frag_count != q->frag_count ||
            memcmp(p->cell_start, q->cell_start, ((size_t)NS * NS + 1) * sizeof *p->cell_start) ||
            memcmp(p->frag, q->frag, (size_t)p->frag_count * sizeof *p->frag))
            return 0;
    }
    return memcmp(a->rects, b->rects, (size_t)a->nd_count * a->prm.l * sizeof *a->rects) == 0;
}

/* The depth order (§3.2) on random non-intersecting triangles with cyclic
 * overlaps, checked ray by ray against Embree: the face order (Newell with
 * splitting; again with the BSP cuts forced on), and the per-ray sort,
 * must agree on at least 99.5 % of the rays that hit something; the plain
 * sort by nearest depth (the trivial answer) and Newell's order without
 * splitting are scored on the same rays and must miss at least 5 times as
 * many (plus 20). The face order holds with every triangle cut into 9. The face order is the same
 * for 1, 2 and 5 threads. */
static void test_order(void)
{
    gi_scene *s = random_triangles(32, 32, 777u);
    gi_rt *rt = NULL;
    gi_error e;
    EXPECT(gi_rt_create(s, 0.0f, &rt, &e) == GI_OK, "embree: %s", e.text);
    if (!rt) {
        gi_scene_free(s);
        return;
    }
    struct {
        const char *name;
        uint32_t order, bsp_levels, bsp_min, threads;
    } cfg[] = {{"faces (Newell, no BSP)", VLF_ORDER_FACES, 0, 4096, 2},
               {"faces (Newell, BSP 2 levels)", VLF_ORDER_FACES, 2, 16, 2},
               {"rays (per-ray depth sort)", VLF_ORDER_RAYS, 0, 4096, 2},
               {"plain (nearest depth only)", VLF_ORDER_PLAIN, 0, 4096, 2},
               {"Newell without splitting", VLF_ORDER_NOSPLIT, 0, 4096, 2},
               {"faces, triangles cut in 3^2", VLF_ORDER_FACES, 0, 4096, 3}};
    uint32_t miss[6] = {0}, hitc[6] = {0};
    vlf_field ref;
    int have_ref = 0;
    for (int k = 0; k < 6; k++) {
        vlf_settings p = defaults();
        p.l = 16;
        p.subdivide = k == 5 ? 3 : 1;
        p.N = 64;
        p.density = 8;
        p.order = cfg[k].order;
        p.bsp_levels = cfg[k].bsp_levels;
        p.bsp_min = cfg[k].bsp_min;
        p.threads = cfg[k].threads;
        vlf_field f;
        gi_error err;
        gi_result rc = vlf_field_build(&f, s, 0.0f, &p, &err);
        EXPECT(rc == GI_OK, "%s", err.text);
        if (rc != GI_OK)
            continue;
        uint32_t agree, multi;
        uint32_t hits = order_against_embree(&f, rt, &agree, &multi);
        miss[k] = hits - agree;
        hitc[k] = hits;
        printf("order %-30s %u rays hit, %u meet 2+ faces; whole sequence agrees with Embree on %u "
               "(%.3f %%); "
               "%llu pieces, %llu cycle splits, %llu BSP cuts, %llu unresolved, %.2f s\n",
               cfg[k].name, hits, multi, agree, 100.0 * agree / (hits ? hits : 1),
               (unsigned long long)f.st.sort_pieces, (unsigned long long)f.st.sort_splits,
               (unsigned long long)f.st.sort_bsp_cuts, (unsigned long long)f.st.sort_unresolved,
               f.st.sort_s);
        EXPECT(multi > hits / 10,
               "too few rays meet two faces (%u of %u): the test set-up is wrong", multi, hits);
        if (cfg[k].order == VLF_ORDER_NOSPLIT)
            EXPECT(f.st.sort_unresolved > 0, "no cycle met: the test set-up is wrong");
        if (cfg[k].order != VLF_ORDER_PLAIN && cfg[k].order != VLF_ORDER_NOSPLIT)
            EXPECT(agree >= hits - hits / 200,
                   "%s: depth order disagrees with Embree on %u of %u rays", cfg[k].name,
                   hits - agree, hits);
        if (cfg[k].order == VLF_ORDER_FACES) {
            EXPECT(f.st.sort_splits > 0, "%s: the cycles were not split", cfg[k].name);
            EXPECT(f.st.sort_unresolved == 0, "%s: %llu cycles unresolved", cfg[k].name,
                   (unsigned long long)f.st.sort_unresolved);
        }
        if (k == 1)
            EXPECT(f.st.sort_bsp_cuts > 0, "BSP forced on but nothing was cut");
        if (k == 0) {
            /* the same order on 1 and 5 threads */
            uint32_t tc[2] = {1, 5};
            for (int j = 0; j < 2; j++) {
                vlf_settings q = p;
                q.threads = tc[j];
                vlf_field g;
                EXPECT(vlf_field_build(&g, s, 0.0f, &q, &err) == GI_OK, "%s", err.text);
                EXPECT(same_field(&f, &g), "the face order on %u threads differs from 2 threads",
                       tc[j]);
                EXPECT(g.st.sort_splits == f.st.sort_splits && g.st.sort_pieces == f.st.sort_pieces,
                       "split counts differ across thread counts");
                vlf_field_free(&g);
            }
            ref = f;
            have_ref = 1;
            continue;
        }
        vlf_field_free(&f);
    }
    EXPECT(miss[3] >= 5 * miss[0] + 20 && miss[3] >= 5 * miss[1] + 20,
           "the plain sort misses %u of %u rays, Newell %u / %u: the cycles do not matter, the "
           "test proves nothing",
           miss[3], hitc[3], miss[0], miss[1]);
    /* the cycles need the splits: Newell's order without them fails there */
    EXPECT(miss[4] >= 5 * miss[0] + 20,
           "Newell without splitting misses only %u of %u rays (with: %u)", miss[4], hitc[4],
           miss[0]);
    if (have_ref)
        vlf_field_free(&ref);
    gi_rt_free(rt);
    gi_scene_free(s);
}

static void test_energy(void)
{
    gi_scene *s = load("tests/data/conformance/furnace_050.gltf");
    if (!s)
        return;
    vlf_settings p = defaults();
    p.l = 64;
    p.N = 48;
    p.density = 6;
    p.iterations = 1;
    if (getenv("VLF_N"))
        p.N = (uint32_t)atoi(getenv("VLF_N"));
    vlf_field f;
    gi_error err;
    EXPECT(vlf_field_build(&f, s, 0.0f, &p, &err) == GI_OK, "%s", err.text);
    vlf_field_propagate(&f, NULL, NULL, NULL);
    const vlf_stats *st = &f.st;
    printf("energy (closed sphere, 1 iteration): emitted %.6f shot %.6f received %.6f back %.6f "
           "escaped %.6f\n",
           st->flux_emitted, st->flux_shot, st->flux_received, st->flux_back, st->flux_escaped);
    CHECK_NEAR(st->flux_shot, st->flux_received + st->flux_back + st->flux_escaped,
               1e-4 * st->flux_shot);
    EXPECT(st->flux_escaped < 1e-3 * st->flux_shot, "light escaped a closed sphere: %.4g of %.4g",
           st->flux_escaped, st->flux_shot);
    EXPECT(st->flux_back < 1e-3 * st->flux_shot, "light met back faces in a closed sphere: %.4g",
           st->flux_back);
    /* what is shot in the first iteration is the emission, within the
     * aliasing of the faces' projections onto the rays */
    EXPECT(fabs(st->flux_shot / st->flux_emitted - 1.0) < 0.02, "shot %.5g vs emitted %.5g",
           st->flux_shot, st->flux_emitted);
    /* received = sum of E * area over elements */
    double absorbed = 0.0;
    for (uint32_t e = 0; e < f.elem_count; e++)
        absorbed +=
            (f.E_tot[3 * e] + f.E_tot[3 * e + 1] + f.E_tot[3 * e + 2]) / 3.0 * f.elem_area[e];
    EXPECT(fabs(absorbed / st->flux_received - 1.0) < 0.02,
           "irradiance x area %.5g vs received %.5g", absorbed, st->flux_received);
    vlf_field_free(&f);
    /* the same with every triangle cut into 4 (the tessellation sweep's option) */
    p.subdivide = 2;
    EXPECT(vlf_field_build(&f, s, 0.0f, &p, &err) == GI_OK, "%s", err.text);
    vlf_field_propagate(&f, NULL, NULL, NULL);
    printf("energy, triangles cut into 4 (%u triangles): emitted %.6f shot %.6f received %.6f back "
           "%.6f escaped %.6f\n",
           f.tri_count, st->flux_emitted, st->flux_shot, st->flux_received, st->flux_back,
           st->flux_escaped);
    CHECK_NEAR(st->flux_shot, st->flux_received + st->flux_back + st->flux_escaped,
               1e-4 * st->flux_shot);
    EXPECT(st->flux_escaped < 1e-3 * st->flux_shot && st->flux_back < 1e-3 * st->flux_shot,
           "subdivided: light escaped (%.4g) or met back faces (%.4g)", st->flux_escaped,
           st->flux_back);
    EXPECT(fabs(st->flux_shot / st->flux_emitted - 1.0) < 0.02,
           "subdivided: shot %.5g vs emitted %.5g", st->flux_shot, st->flux_emitted);
    vlf_field_free(&f);
    p.subdivide = 1;
    /* the same with 3 perturbed directions per fixed one (§3.5) */
    p.perturbed = 3;
    EXPECT(vlf_field_build(&f, s, 0.0f, &p, &err) == GI_OK, "%s", err.text);
    vlf_field_propagate(&f, NULL, NULL, NULL);
    printf("energy, 3 perturbed directions: emitted %.6f shot %.6f received %.6f back %.6f escaped "
           "%.6f\n",
           st->flux_emitted, st->flux_shot, st->flux_received, st->flux_back, st->flux_escaped);
    CHECK_NEAR(st->flux_shot, st->flux_received + st->flux_back + st->flux_escaped,
               1e-4 * st->flux_shot);
    EXPECT(st->flux_escaped < 1e-3 * st->flux_shot && st->flux_back < 1e-3 * st->flux_shot,
           "perturbed: light escaped (%.4g) or met back faces (%.4g)", st->flux_escaped,
           st->flux_back);
    EXPECT(fabs(st->flux_shot / st->flux_emitted - 1.0) < 0.02,
           "perturbed: shot %.5g vs emitted %.5g", st->flux_shot, st->flux_emitted);
    /* the perturbed lists sorted beside the sweeps on 2 threads (above) or
     * in line on 1, or on 5: the same field, bit for bit */
    uint32_t tc[2] = {1, 5};
    for (int k = 0; k < 2; k++) {
        vlf_settings q = p;
        q.threads = tc[k];
        vlf_field g;
        EXPECT(vlf_field_build(&g, s, 0.0f, &q, &err) == GI_OK, "%s", err.text);
        vlf_field_propagate(&g, NULL, NULL, NULL);
        int same = g.elem_count == f.elem_count &&
                   memcmp(g.E_tot, f.E_tot, (size_t)f.elem_count * 3 * sizeof *f.E_tot) == 0 &&
                   g.st.flux_shot == f.st.flux_shot && g.st.samples == f.st.samples;
        EXPECT(same, "perturbed propagation on %u threads differs from 2 threads", tc[k]);
        vlf_field_free(&g);
    }
    vlf_field_free(&f);
    gi_scene_free(s);
}

static void test_furnace(void)
{
    const char *files[] = {"tests/data/conformance/furnace_050.gltf",
                           "tests/data/conformance/furnace_080.gltf"};
    const double rho[] = {0.5, 0.8};
    for (int k = 0; k < 2; k++) {
        gi_scene *s = load(files[k]);
        if (!s)
            return;
        uint32_t its[] = {1, 8, 16};
        for (int q = 0; q < 3; q++) {
            vlf_settings p = defaults();
            if (!getenv("VLF_FULL"))
                p.l = 64, p.N = 48, p.density = 6;
            p.iterations = its[q];
            vlf_field f;
            gi_error err;
            EXPECT(vlf_field_build(&f, s, 0.0f, &p, &err) == GI_OK, "%s", err.text);
            vlf_field_propagate(&f, NULL, NULL, NULL);
            /* radiance of the surface = Le + rho E / pi, area-weighted mean */
            double num = 0.0, den = 0.0;
            for (uint32_t e = 0; e < f.elem_count; e++) {
                const vlf_face *fc = &f.faces[f.elem_face[e]];
                double L = fc->emission[0] + fc->kd[0] * f.E_tot[3 * e] / GI_PI;
                num += L * f.elem_area[e];
                den += f.elem_area[e];
            }
            double got = num / den, Le = f.faces[0].emission[0];
            double want = 0.0;
            for (uint32_t b = 0; b <= its[q]; b++)
                want += Le * pow(rho[k], b);
            printf("furnace rho=%.1f iterations %2u: mean radiance %.5f, due Le sum_{k<=%u} rho^k "
                   "= %.5f (limit %.5f)\n",
                   rho[k], its[q], got, its[q], want, Le / (1.0 - rho[k]));
            EXPECT(fabs(got / want - 1.0) < 0.02, "furnace %.4f vs %.4f", got, want);
            vlf_field_free(&f);
        }
        gi_scene_free(s);
    }
}

/* Two quads: an emitter of radiance 1 at height 1 facing down, and below
 * it a mirror (ks 0.8) tilted so that the emitter's light leaves it
 * toward +x. */
static void add_quad(gi_scene *s, uint32_t q, gi_vec3 a, gi_vec3 b, gi_vec3 c, gi_vec3 d,
                     uint32_t material)
{
    gi_vec3 v[4] = {a, b, c, d};
    for (int k = 0; k < 4; k++) {
        gi_vertex *x = &s->vertices[4 * q + (uint32_t)k];
        x->position[0] = v[k].x, x->position[1] = v[k].y, x->position[2] = v[k].z;
        x->normal[2] = 1.0f;
        x->material = material;
    }
    uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    for (int k = 0; k < 6; k++)
        s->indices[6 * q + (uint32_t)k] = 4 * q + idx[k];
}

static void test_mirror(void)
{
    gi_scene *s = bare_scene(4, 8, 2, 1);
    s->materials[0].emission[0] = s->materials[0].emission[1] = s->materials[0].emission[2] = 1.0f;
    s->materials[1].ks[0] = s->materials[1].ks[1] = s->materials[1].ks[2] = 0.8f;
    s->materials[1].mirror = 1;
    s->materials[1].exponent = GI_MIRROR_EXPONENT;
    /* emitter at z = 1, normal -z (clockwise seen from above) */
    add_quad(s, 0, gi_v3(-0.3f, -0.3f, 1.0f), gi_v3(-0.3f, 0.3f, 1.0f), gi_v3(0.3f, 0.3f, 1.0f),
             gi_v3(0.3f, -0.3f, 1.0f), 0);
    /* mirror around the origin, normal (sin 22.5, 0, cos 22.5): light coming
     * down (-z) leaves along (sin 45, 0, cos 45) */
    float c = cosf(GI_PI / 8), sn = sinf(GI_PI / 8);
    gi_vec3 tx = gi_v3(c, 0, -sn), ty = gi_v3(0, 1, 0);
    gi_vec3 P[4];
    float uv[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
    for (int k = 0; k < 4; k++)
        P[k] = gi_v3_add(gi_v3_scale(tx, 0.3f * uv[k][0]), gi_v3_scale(ty, 0.3f * uv[k][1]));
    add_quad(s, 1, P[0], P[1], P[2], P[3], 1);
    float lo[3] = {FLT_MAX, FLT_MAX, FLT_MAX}, hi[3] = {-FLT_MAX, -FLT_MAX, -FLT_MAX};
    for (uint32_t v = 0; v < 8; v++)
        for (int a = 0; a < 3; a++)
            lo[a] = fminf(lo[a], s->vertices[v].position[a]),
            hi[a] = fmaxf(hi[a], s->vertices[v].position[a]);
    for (int a = 0; a < 3; a++)
        s->objects[0].local_bounds[a] = lo[a], s->objects[0].local_bounds[3 + a] = hi[a];
    vlf_settings p = defaults();
    p.iterations = 2;
    vlf_field f;
    gi_error err;
    gi_result rc = vlf_field_build(&f, s, 0.0f, &p, &err);
    EXPECT(rc == GI_OK, "%s", err.text);
    if (rc == GI_OK) {
        vlf_field_propagate(&f, NULL, NULL, NULL);
        int mf = -1;
        for (uint32_t fi = 0; fi < f.face_count; fi++)
            if (f.faces[fi].nd >= 0)
                mf = (int)fi;
        EXPECT(mf >= 0, "no non-diffuse face");
        gi_vec3 refl = gi_v3_normalize(gi_v3(1, 0, 1));
        /* mean stored radiance of the mirror along each signed direction */
        double best_hit = 0.0, far = 0.0;
        float best_ang = 10.0f;
        for (uint32_t sd = 0; mf >= 0 && sd < 2 * p.l; sd++) {
            gi_vec3 w = f.dirs.signed_dirs[sd];
            uint32_t i = sd % p.l;
            if (gi_v3_dot(w, f.faces[mf].n) <= 0.0f)
                continue;
            const vlf_rect *r = &f.rects[(size_t)f.faces[mf].nd * p.l + i];
            double sum = 0.0;
            uint32_t n = 0;
            for (uint32_t k = 0; k < r->w * r->h; k++)
                if (f.nd_cover[r->offset + k])
                    sum += f.out_tot[3 * (size_t)(r->offset + k)], n++;
            double mean = n ? sum / n : 0.0;
            float ang = acosf(fminf(1.0f, gi_v3_dot(w, refl)));
            if (ang < best_ang)
                best_ang = ang, best_hit = mean;
            if (ang > 1.0f)
                far = fmax(far, mean);
        }
        /* the mirror's radiance toward the reflected direction shows the
         * emitter through it: most of ks Le = 0.8 at the direction nearest
         * the reflection (barycentric weights and the emitter's edges take
         * some), and nothing far from it */
        printf("mirror: stored radiance %.3f at the direction nearest the reflection (%.3f rad "
               "from it; ks Le = 0.8), "
               "at most %.4f beyond 1 rad from it (the emitter subtends up to 0.54 rad seen from "
               "the mirror)\n",
               best_hit, best_ang, far);
        EXPECT(best_hit > 0.3 && best_hit < 0.85, "mirror radiance toward the reflection %.3f",
               best_hit);
        EXPECT(far < 0.01, "mirror radiance away from the reflection %.4f", far);
        vlf_field_free(&f);
    }
    gi_scene_free(s);
}

/* Mean irradiance (channel 0) of the whole elements of face fi whose
 * centres (world x, y) lie in the box [x0, x1] x [y0, y1]; -1 if none. */
static double mean_E_in(const vlf_field *f, uint32_t fi, float x0, float x1, float y0, float y1)
{
    const vlf_face *fc = &f->faces[fi];
    double sum = 0.0;
    uint32_t n = 0;
    float texel = 1.0f / (f->prm.density * f->prm.density);
    for (uint32_t iy = 0; iy < fc->H; iy++)
        for (uint32_t ix = 0; ix < fc->W; ix++) {
            uint32_t e = fc->first_elem + iy * fc->W + ix;
            if (f->elem_area[e] < 0.99f * texel)
                continue;
            gi_vec3 q = gi_v3_add(
                fc->origin, gi_v3_add(gi_v3_scale(fc->t, ((float)ix + 0.5f) / f->prm.density),
                                      gi_v3_scale(fc->b, ((float)iy + 0.5f) / f->prm.density)));
            gi_vec3 w = gi_v3_add(f->centre, gi_v3_scale(q, f->radius));
            if (w.x < x0 || w.x > x1 || w.y < y0 || w.y > y1)
                continue;
            sum += f->E_tot[3 * (size_t)e];
            n++;
        }
    return n ? sum / n : -1.0;
}

/* Directional light: a floor (z = 0, [-1, 1]^2) under a square occluder
 * (z = 0.5, half size 0.25), a sun of irradiance 2 straight down and 30
 * degrees off: after one iteration the open floor's irradiance is within
 * 5 % of 2 cos(theta), and the floor around the shadow's centre (0, 0.5 tan
 * theta) gets under 5 % of it while the same spot mirrored (where the
 * shadow would fall were the light reversed) is lit; the always-lit and the
 * never-lit answers each fail one of these. */
static void test_sun(void)
{
    for (int k = 0; k < 2; k++) {
        float a = k ? GI_PI / 6.0f : 0.0f;
        gi_scene *s = bare_scene(4, 8, 1, 2);
        s->materials[0].albedo[0] = s->materials[0].albedo[1] = s->materials[0].albedo[2] = 0.5f;
        /* the light's node: turned by a about x, its -z pointing along (0, sin a, -cos a) */
        s->nodes[1].rotation[0] = sinf(0.5f * a);
        s->nodes[1].rotation[3] = cosf(0.5f * a);
        add_quad(s, 0, gi_v3(-1, -1, 0), gi_v3(1, -1, 0), gi_v3(1, 1, 0), gi_v3(-1, 1, 0), 0);
        add_quad(s, 1, gi_v3(-0.25f, -0.25f, 0.5f), gi_v3(0.25f, -0.25f, 0.5f),
                 gi_v3(0.25f, 0.25f, 0.5f), gi_v3(-0.25f, 0.25f, 0.5f), 0);
        float bounds[6] = {-1, -1, 0, 1, 1, 0.5f};
        memcpy(s->objects[0].local_bounds, bounds, sizeof bounds);
        s->light_count = 1;
        s->lights = calloc(1, sizeof *s->lights);
        s->lights[0].type = GI_LIGHT_DIRECTIONAL;
        s->lights[0].node = 1;
        s->lights[0].intensity[0] = s->lights[0].intensity[1] = s->lights[0].intensity[2] = 2.0f;
        vlf_settings p = defaults();
        p.iterations = 1;
        p.density = 16;
        vlf_field f;
        gi_error err;
        gi_result rc = vlf_field_build(&f, s, 0.0f, &p, &err);
        EXPECT(rc == GI_OK, "%s", err.text);
        if (rc == GI_OK) {
            vlf_field_propagate(&f, NULL, NULL, NULL);
            uint32_t floor = f.tri_face[0];
            double want = 2.0 * cos(a), ys = 0.5 * tan(a);
            double open = mean_E_in(&f, floor, 0.55f, 0.9f, -0.9f, 0.9f);
            double shadow = mean_E_in(&f, floor, -0.1f, 0.1f, (float)ys - 0.1f, (float)ys + 0.1f);
            double mirror = mean_E_in(&f, floor, -0.1f, 0.1f, (float)-ys - 0.1f, (float)-ys + 0.1f);
            printf("sun %2.0f deg: open floor E = %.4f (due %.4f), shadow centre (0, %.3f) E = "
                   "%.4f, %s E = %.4f\n",
                   a * 180.0 / GI_PI, open, want, ys, shadow,
                   k ? "the mirrored spot" : "(same spot)", mirror);
            EXPECT(fabs(open / want - 1.0) < 0.05, "sun: open floor %.4f, due %.4f", open, want);
            EXPECT(shadow >= 0.0 && shadow < 0.05 * want, "sun: the shadow gets %.4f", shadow);
            if (k)
                EXPECT(mirror > 0.9 * want, "sun: the spot opposite the shadow gets %.4f", mirror);
            EXPECT(f.sun_count == 1, "sun: %u directional lights seen", f.sun_count);
            vlf_field_free(&f);
        }
        gi_scene_free(s);
    }
}

/* Point and spot lights: the floor and occluder of test_sun, a point
 * light (intensity 3) at (0, 0, 1.5): after one iteration every whole
 * floor element outside the shadow's rim gets I h / d^3 at its centre
 * (1 %), the elements inside the shadow (|x|, |y| < 0.3; the occluder's
 * shadow reaches 0.375) nothing; a spot there pointing down (cones 0.3 and
 * 0.35 rad) the same times the glTF falloff, and nothing beyond its outer
 * cone. The unshadowed and the black answers each fail. */
static void test_point(void)
{
    for (int k = 0; k < 2; k++) {
        gi_scene *s = bare_scene(4, 8, 1, 2);
        s->materials[0].albedo[0] = s->materials[0].albedo[1] = s->materials[0].albedo[2] = 0.5f;
        s->nodes[1].translation[2] = 1.5f; /* -z of the node points down */
        add_quad(s, 0, gi_v3(-1, -1, 0), gi_v3(1, -1, 0), gi_v3(1, 1, 0), gi_v3(-1, 1, 0), 0);
        add_quad(s, 1, gi_v3(-0.25f, -0.25f, 0.5f), gi_v3(0.25f, -0.25f, 0.5f),
                 gi_v3(0.25f, 0.25f, 0.5f), gi_v3(-0.25f, 0.25f, 0.5f), 0);
        float bounds[6] = {-1, -1, 0, 1, 1, 0.5f};
        memcpy(s->objects[0].local_bounds, bounds, sizeof bounds);
        s->light_count = 1;
        s->lights = calloc(1, sizeof *s->lights);
        s->lights[0].type = k ? GI_LIGHT_SPOT : GI_LIGHT_POINT;
        s->lights[0].node = 1;
        s->lights[0].inner_cone = 0.3f;
        s->lights[0].outer_cone = 0.35f;
        s->lights[0].intensity[0] = s->lights[0].intensity[1] = s->lights[0].intensity[2] = 3.0f;
        vlf_settings p = defaults();
        p.iterations = 1;
        p.density = 16;
        vlf_field f;
        gi_error err;
        gi_result rc = vlf_field_build(&f, s, 0.0f, &p, &err);
        EXPECT(rc == GI_OK, "%s", err.text);
        if (rc == GI_OK) {
            vlf_field_propagate(&f, NULL, NULL, NULL);
            const vlf_face *fc = &f.faces[f.tri_face[0]];
            float texel = 1.0f / (p.density * p.density);
            double worst = 0.0, shadow = 0.0, beyond = 0.0, lit = 0.0;
            uint32_t n_lit = 0, n_shadow = 0, n_beyond = 0;
            float cos_i = cosf(0.3f), cos_o = cosf(0.35f);
            for (uint32_t iy = 0; iy < fc->H; iy++)
                for (uint32_t ix = 0; ix < fc->W; ix++) {
                    uint32_t e = fc->first_elem + iy * fc->W + ix;
                    if (f.elem_area[e] < 0.99f * texel)
                        continue;
                    gi_vec3 q = gi_v3_add(
                        fc->origin, gi_v3_add(gi_v3_scale(fc->t, ((float)ix + 0.5f) / p.density),
                                              gi_v3_scale(fc->b, ((float)iy + 0.5f) / p.density)));
                    gi_vec3 w = gi_v3_add(f.centre, gi_v3_scale(q, f.radius));
                    double d2 = (double)w.x * w.x + (double)w.y * w.y + 1.5 * 1.5, d = sqrt(d2);
                    double want = 3.0 * 1.5 / (d2 * d);
                    double ca = 1.5 / d;
                    if (k)
                        want *= gi_spot_falloff((float)ca, cos_i, cos_o);
                    double got = f.E_tot[3 * (size_t)e];
                    float rim = fmaxf(fabsf(w.x), fabsf(w.y));
                    if (rim < 0.3f) {
                        shadow = fmax(shadow, got);
                        n_shadow++;
                    } else if (rim > 0.45f && want > 0.05) {
                        worst = fmax(worst, fabs(got / want - 1.0));
                        lit += got;
                        n_lit++;
                    } else if (k && ca < cos_o - 0.01) {
                        beyond = fmax(beyond, got);
                        n_beyond++;
                    }
                }
            printf("%s: %u lit elements, worst %.3f %% off I h / d^3%s; %u in the shadow, at most "
                   "%.5f; %u beyond the cone, "
                   "at most %.5f\n",
                   k ? "spot" : "point", n_lit, 100.0 * worst, k ? " x falloff" : "", n_shadow,
                   shadow, n_beyond, beyond);
            EXPECT(n_lit > (k ? 8u : 100u) && n_shadow > 20,
                   "point: too few elements lit (%u) or shadowed (%u)", n_lit, n_shadow);
            EXPECT(worst < 0.01, "point: lit floor off the inverse square law by %.3g", worst);
            EXPECT(shadow < 1e-3, "point: the shadow gets %.4g", shadow);
            if (k)
                EXPECT(n_beyond > 50 && beyond < 1e-4,
                       "spot: %u elements beyond the cone get up to %.4g", n_beyond, beyond);
            vlf_field_free(&f);
        }
        gi_scene_free(s);
    }
}

/* A point light's reflection by a mirror (the first shot into non-diffuse
 * tiles): the tilted mirror of test_mirror (ks 0.8, 0.6 wide) under a
 * point light (3 W/sr) at (0, 0, 1): the flux the tiles send out (sum of
 * L x cell area x dOmega over every direction and covered cell) is within
 * 5 % of ks times the flux the light brings onto the mirror (I cos / d^2
 * integrated over it), the most of it goes out along one of the three
 * directions around the centre's reflection (sin 45, 0, cos 45), and none
 * along a direction more than 1 rad from it. */
static void test_point_mirror(void)
{
    gi_scene *s = bare_scene(2, 4, 1, 2);
    s->materials[0].ks[0] = s->materials[0].ks[1] = s->materials[0].ks[2] = 0.8f;
    s->materials[0].mirror = 1;
    s->materials[0].exponent = GI_MIRROR_EXPONENT;
    s->nodes[1].translation[2] = 1.0f;
    float c = cosf(GI_PI / 8), sn = sinf(GI_PI / 8);
    gi_vec3 tx = gi_v3(c, 0, -sn), ty = gi_v3(0, 1, 0);
    gi_vec3 P[4];
    float uv[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
    for (int k = 0; k < 4; k++)
        P[k] = gi_v3_add(gi_v3_scale(tx, 0.3f * uv[k][0]), gi_v3_scale(ty, 0.3f * uv[k][1]));
    add_quad(s, 0, P[0], P[1], P[2], P[3], 0);
    float lo[3] = {FLT_MAX, FLT_MAX, FLT_MAX}, hi[3] = {-FLT_MAX, -FLT_MAX, -FLT_MAX};
    for (uint32_t v = 0; v < 4; v++)
        for (int a = 0; a < 3; a++)
            lo[a] = fminf(lo[a], s->vertices[v].position[a]),
            hi[a] = fmaxf(hi[a], s->vertices[v].position[a]);
    for (int a = 0; a < 3; a++)
        s->objects[0].local_bounds[a] = lo[a], s->objects[0].local_bounds[3 + a] = hi[a];
    s->light_count = 1;
    s->lights = calloc(1, sizeof *s->lights);
    s->lights[0].type = GI_LIGHT_POINT;
    s->lights[0].node = 1;
    s->lights[0].intensity[0] = s->lights[0].intensity[1] = s->lights[0].intensity[2] = 3.0f;
    vlf_settings p = defaults();
    p.iterations = 1;
    vlf_field f;
    gi_error err;
    gi_result rc = vlf_field_build(&f, s, 0.0f, &p, &err);
    EXPECT(rc == GI_OK, "%s", err.text);
    if (rc == GI_OK) {
        vlf_field_propagate(&f, NULL, NULL, NULL);
        const vlf_face *fc = &f.faces[0];
        gi_vec3 refl = gi_v3_normalize(gi_v3(1, 0, 1));
        uint32_t node[3];
        float al[3];
        vlf_dirs_locate(&f.dirs, refl, node, al);
        /* the light's flux onto the mirror, world units: I cos / d^2 over it */
        double in = 0.0;
        gi_vec3 nrm = gi_v3(sn, 0, c);
        for (int a = 0; a < 200; a++)
            for (int b = 0; b < 200; b++) {
                gi_vec3 x = gi_v3_add(gi_v3_scale(tx, 0.3f * (((float)a + 0.5f) / 100.0f - 1.0f)),
                                      gi_v3_scale(ty, 0.3f * (((float)b + 0.5f) / 100.0f - 1.0f)));
                gi_vec3 d = gi_v3_sub(gi_v3(0, 0, 1), x);
                float d2 = gi_v3_dot(d, d);
                in += 3.0 * gi_v3_dot(nrm, gi_v3_normalize(d)) / d2 * (0.6 / 200.0) * (0.6 / 200.0);
            }
        double out = 0.0, best = 0.0, far = 0.0;
        uint32_t best_sd = UINT32_MAX;
        double cell = (2.0 / p.N) * (2.0 / p.N) * (double)f.radius * f.radius;
        for (uint32_t sd = 0; sd < 2 * p.l; sd++) {
            gi_vec3 w = f.dirs.signed_dirs[sd];
            if (gi_v3_dot(w, fc->n) <= 0.0f)
                continue;
            const vlf_rect *r = &f.rects[(size_t)fc->nd * p.l + sd % p.l];
            double sum = 0.0;
            for (uint32_t k = 0; k < r->w * r->h; k++)
                if (f.nd_cover[r->offset + k])
                    sum += f.out_tot[3 * (size_t)(r->offset + k)];
            double flux = sum * cell * f.dirs.solid_angle[sd];
            out += flux;
            if (flux > best)
                best = flux, best_sd = sd;
            if (acosf(fminf(1.0f, gi_v3_dot(w, refl))) > 1.0f)
                far = fmax(far, flux);
        }
        int near = best_sd == node[0] || best_sd == node[1] || best_sd == node[2];
        printf("point light in a mirror: flux out of the tiles %.4f, ks x flux onto the mirror "
               "%.4f (%+.2f %%); the "
               "largest share (%.0f %%) along %s of the reflection's three directions; at most "
               "%.2g beyond 1 rad\n",
               out, 0.8 * in, 100.0 * (out / (0.8 * in) - 1.0), 100.0 * best / (out > 0 ? out : 1),
               near ? "one" : "none", far);
        EXPECT(fabs(out / (0.8 * in) - 1.0) < 0.05, "point light in a mirror: out %.4f, due %.4f",
               out, 0.8 * in);
        EXPECT(near,
               "point light in a mirror: the most light leaves along direction %u, not around the "
               "reflection",
               best_sd);
        EXPECT(far < 1e-6 * out, "point light in a mirror: %.4g away from the reflection", far);
        vlf_field_free(&f);
    }
    gi_scene_free(s);
}

/* Relative L1 difference of two maps of count RGB values: sum |a - b| / sum |b|. */
static double rel_l1(const float *a, const float *b, size_t count)
{
    double num = 0.0, den = 0.0;
    for (size_t k = 0; k < 3 * count; k++)
        num += fabs((double)a[k] - b[k]), den += fabs((double)b[k]);
    return den > 0.0 ? num / den : 0.0;
}

/* Storage precision (§3.1, §6): the encoders against known values and
 * their rounding bounds; the glossy Cornell box propagated with maps in
 * RGBA16F and RGB9E5 against float32 (irradiance atlas and non-diffuse
 * tiles, relative L1 within 0.2 % and 1 %; the black map scores 100 %);
 * the maps hold only values of their format, and their packed bytes are
 * the memory reported (8 and 4 bytes a value against 12). */
static void test_precision(void)
{
    float one[3] = {1.0f, 0.5f, 0.25f}, back[3];
    uint16_t h[4];
    vlf_pack(VLF_PREC_16F, one, 1, h);
    EXPECT(h[0] == 0x3c00 && h[1] == 0x3800 && h[2] == 0x3400 && h[3] == 0,
           "half of 1, 0.5, 0.25: %04x %04x %04x", h[0], h[1], h[2]);
    uint32_t w;
    vlf_pack(VLF_PREC_RGB9E5, one, 1, &w);
    vlf_unpack(VLF_PREC_RGB9E5, &w, 1, back);
    EXPECT(back[0] == 1.0f && back[1] == 0.5f && back[2] == 0.25f,
           "rgb9e5 of 1, 0.5, 0.25: %g %g %g", back[0], back[1], back[2]);
    float big[3] = {1e6f, 70000.0f, 0.0f};
    vlf_quantise(VLF_PREC_16F, big, 1);
    EXPECT(big[0] == 65504.0f && big[1] == 65504.0f && big[2] == 0.0f,
           "half clamps to 65504: %g %g", big[0], big[1]);
    uint32_t seed = 99u;
    double worst16 = 0.0, worst9 = 0.0;
    for (int q = 0; q < 100000; q++) {
        float v[3], a[3], b[3];
        for (int k = 0; k < 3; k++)
            v[k] = ldexpf(frand(&seed), (int)(frand(&seed) * 20.0f) - 10);
        memcpy(a, v, sizeof v);
        memcpy(b, v, sizeof v);
        vlf_quantise(VLF_PREC_16F, a, 1);
        vlf_quantise(VLF_PREC_RGB9E5, b, 1);
        float mx = fmaxf(v[0], fmaxf(v[1], v[2]));
        for (int k = 0; k < 3; k++) {
            if (v[k] >= ldexpf(1.0f, -14))
                worst16 = fmax(worst16, fabs(a[k] - v[k]) / v[k]);
            worst9 = fmax(worst9, fabs(b[k] - v[k]) / mx);
        }
    }
    printf("precision: largest rounding error, half %.3g of the value (bound 2^-11 = %.3g), rgb9e5 "
           "%.3g of the largest "
           "channel (bound 2^-9 = %.3g)\n",
           worst16, ldexp(1, -11), worst9, ldexp(1, -9));
    EXPECT(worst16 <= ldexp(1, -11) * 1.0001, "half rounding %.3g", worst16);
    EXPECT(worst9 <= ldexp(1, -9) * 1.0001, "rgb9e5 rounding %.3g", worst9);

    gi_scene *s = load("scenes/cornell_glossy.gltf");
    if (!s)
        return;
    vlf_field f[3];
    gi_error err;
    const char *name[3] = {"32f", "16f", "rgb9e5"};
    const double bound_E[3] = {0.0, 0.002, 0.01}, bound_T[3] = {0.0, 0.002, 0.01};
    int ok[3] = {0, 0, 0};
    for (uint32_t k = 0; k < 3; k++) {
        vlf_settings p = defaults();
        p.l = 32, p.N = 32, p.density = 8, p.iterations = 4, p.precision = k;
        ok[k] = vlf_field_build(&f[k], s, 0.0f, &p, &err) == GI_OK;
        EXPECT(ok[k], "%s", err.text);
        if (!ok[k])
            continue;
        vlf_field_propagate(&f[k], NULL, NULL, NULL);
        size_t bpv = vlf_precision_bytes(k), count = (size_t)f[k].elem_count + f[k].nd_cells;
        /* the maps as packed for rendering: the reported bytes, and nothing lost */
        uint8_t *buf = malloc(count * bpv + 1);
        float *un = malloc(count * 3 * sizeof *un + 1);
        vlf_pack(k, f[k].E_tot, f[k].elem_count, buf);
        vlf_pack(k, f[k].out_tot, f[k].nd_cells, buf + (size_t)f[k].elem_count * bpv);
        vlf_unpack(k, buf, f[k].elem_count, un);
        vlf_unpack(k, buf + (size_t)f[k].elem_count * bpv, f[k].nd_cells,
                   un + 3 * (size_t)f[k].elem_count);
        int exact = memcmp(un, f[k].E_tot, (size_t)f[k].elem_count * 3 * sizeof *un) == 0 &&
                    memcmp(un + 3 * (size_t)f[k].elem_count, f[k].out_tot,
                           (size_t)f[k].nd_cells * 3 * sizeof *un) == 0;
        EXPECT(exact, "%s: the maps hold values the format cannot store", name[k]);
        EXPECT(f[k].st.bytes_maps_render == count * bpv,
               "%s: reported %zu bytes for the maps, packed %zu", name[k],
               f[k].st.bytes_maps_render, count * bpv);
        free(buf);
        free(un);
        printf("precision %-6s: %u elements + %u tile cells, maps %zu bytes (%zu a value), "
               "propagation %zu bytes, "
               "rendering %zu bytes, propagate %.2f s",
               name[k], f[k].elem_count, f[k].nd_cells, f[k].st.bytes_maps_render, bpv,
               f[k].st.bytes_propagate, f[k].st.bytes_render, f[k].st.propagate_s);
        if (k > 0 && ok[0]) {
            double eE = rel_l1(f[k].E_tot, f[0].E_tot, f[k].elem_count);
            double eT = rel_l1(f[k].out_tot, f[0].out_tot, f[k].nd_cells);
            float *zero = calloc((size_t)f[0].elem_count * 3 + 1, sizeof *zero);
            double black = rel_l1(zero, f[0].E_tot, f[0].elem_count);
            free(zero);
            printf("; against 32f: irradiance %.4f %%, tiles %.4f %% (black: %.0f %%)", 100 * eE,
                   100 * eT, 100 * black);
            EXPECT(eE < bound_E[k], "%s: irradiance differs from 32f by %.3g", name[k], eE);
            EXPECT(eT < bound_T[k], "%s: tiles differ from 32f by %.3g", name[k], eT);
            EXPECT(f[k].nd_cells > 0 &&
                       f[0].st.bytes_maps_render * bpv == f[k].st.bytes_maps_render * 12,
                   "%s: map bytes not in the ratio %zu : 12", name[k], bpv);
        }
        printf("\n");
    }
    for (int k = 0; k < 3; k++)
        if (ok[k])
            vlf_field_free(&f[k]);
    gi_scene_free(s);
}

/* The glossy lobe's grazing fall-off: vlf_phong_albedo (a quadrature)
 * against a Monte Carlo estimate of core brdf.h's lobe (gi_brdf_eval, wi
 * drawn from the lobe, 200 000 samples) for n = 10 and 50 at incidence
 * 0, 60, 80 and 88 degrees: within 0.01; 1 at normal incidence (1e-3);
 * the answer without fall-off (1 everywhere) misses at 80 degrees by more
 * than 0.1. */
static void test_albedo(void)
{
    const float ns[2] = {10.0f, 50.0f}, deg[4] = {0.0f, 60.0f, 80.0f, 88.0f};
    uint32_t seed = 31u;
    for (int a = 0; a < 2; a++)
        for (int b = 0; b < 4; b++) {
            float th = deg[b] * GI_PI / 180.0f;
            gi_vec3 N = gi_v3(0, 0, 1), wo = gi_v3(sinf(th), 0.0f, cosf(th));
            gi_brdf br = {{0, 0, 0}, {1, 1, 1}, ns[a], 0};
            gi_vec3 r = gi_reflect(wo, N);
            double sum = 0.0;
            const int M = 200000;
            for (int k = 0; k < M; k++) {
                gi_vec3 wi = gi_phong_lobe_sample(r, ns[a], frand(&seed), frand(&seed));
                float fv[3];
                gi_brdf_eval(&br, N, wo, wi, fv);
                float pdf = gi_phong_lobe_pdf(r, ns[a], wi);
                if (pdf > 0.0f)
                    sum += fv[0] * fmax(0.0, gi_v3_dot(N, wi)) / pdf;
            }
            double mc = sum / M, q = vlf_phong_albedo(ns[a], cosf(th));
            printf("albedo n = %2.0f, %2.0f deg: quadrature %.4f, Monte Carlo %.4f\n", ns[a],
                   deg[b], q, mc);
            EXPECT(fabs(q - mc) < 0.01, "n %g at %g deg: quadrature %.4f, Monte Carlo %.4f", ns[a],
                   deg[b], q, mc);
            if (b == 0)
                EXPECT(fabs(q - 1.0) < 1e-3, "albedo at normal incidence %.5f", q);
            if (b == 2 && a == 0)
                EXPECT(fabs(1.0 - mc) > 0.1,
                       "no fall-off at 80 deg (%.4f): the test proves nothing", mc);
        }
}

/* Textured albedo in propagation: a floor (albedo 0.8 x a texture of 8 x 1
 * texels, the left four black, the right four white) under an emitting
 * square facing down, 1 iteration: each floor element's albedo is the
 * texture averaged over it (0 on the black half, 0.8 on the white half,
 * where the bilinear texture is constant), the radiance it shoots on is
 * albedo x E / pi there (1e-5), and the area-weighted mean albedo of the
 * floor is within 2 % of 0.8 x the texture's mean over it; the answer
 * without the texture (0.8 everywhere) fails the black half. */
static void test_texture(void)
{
    /* floor z = 0 over [-1, 1]^2 facing +z; emitter z = 1 over [-0.5, 0.5]^2 facing -z */
    const float tri[4 * 9] = {-1,   -1,    0, 1,     -1,    0, 1,     1,     0, -1,   -1,   0,
                              1,    1,     0, -1,    1,     0, -0.5f, -0.5f, 1, 0.5f, 0.5f, 1,
                              0.5f, -0.5f, 1, -0.5f, -0.5f, 1, -0.5f, 0.5f,  1, 0.5f, 0.5f, 1};
    gi_scene *s = triangle_scene(tri, 4);
    gi_material *m = calloc(2, sizeof *m);
    m[0] = s->materials[0];
    m[0].albedo[0] = m[0].albedo[1] = m[0].albedo[2] = 0.8f;
    m[0].albedo_texture = 0;
    m[1].albedo_texture = -1;
    m[1].emission[0] = m[1].emission[1] = m[1].emission[2] = 1.0f;
    free(s->materials);
    s->materials = m;
    s->material_count = 2;
    gi_texture tex = {NULL, 8, 1, calloc(8 * 4, sizeof(float))};
    for (int i = 4; i < 8; i++)
        for (int c = 0; c < 4; c++)
            tex.rgba[4 * i + c] = 1.0f;
    s->textures = &tex;
    s->texture_count = 1;
    for (uint32_t k = 0; k < 12; k++) {
        gi_vertex *v = &s->vertices[k];
        v->material = k < 6 ? 0 : 1;
        v->uv[0] = 0.5f * (v->position[0] + 1.0f);
        v->uv[1] = 0.5f * (v->position[1] + 1.0f);
    }
    vlf_settings p = defaults();
    p.l = 32, p.N = 32, p.density = 8, p.iterations = 1;
    vlf_field f;
    gi_error err;
    int ok = vlf_field_build(&f, s, 0.0f, &p, &err) == GI_OK;
    EXPECT(ok, "%s", err.text);
    if (ok) {
        vlf_field_propagate(&f, NULL, NULL, NULL);
        uint32_t nb = 0, nw = 0, bad = 0;
        double akd = 0.0, area = 0.0, worst = 0.0;
        for (uint32_t e = 0; e < f.elem_count; e++) {
            const vlf_face *fc = &f.faces[f.elem_face[e]];
            if (fc->emission[0] > 0.0f || !(f.elem_area[e] > 0.0f))
                continue;
            gi_vec3 q = gi_v3_add(fc->origin,
                                  gi_v3_add(gi_v3_scale(fc->t, f.elem_c[2 * e] / p.density),
                                            gi_v3_scale(fc->b, f.elem_c[2 * e + 1] / p.density)));
            float x = f.centre.x + f.radius * q.x;
            float half = 0.5f / (p.density / f.radius) + 1e-3f; /* half an element, world units */
            float kd = f.elem_kd[3 * e];
            akd += kd * f.elem_area[e], area += f.elem_area[e];
            float want = -1.0f;
            if (x + half < -0.125f && x - half > -0.875f)
                want = 0.0f, nb++;
            else if (x - half > 0.125f && x + half < 0.875f)
                want = 0.8f, nw++;
            if (want < 0.0f)
                continue;
            double shot = f.L_cur[3 * e], due = want * f.E_tot[3 * e] * GI_INV_PI;
            worst = fmax(worst, fabs(shot - due));
            if (fabsf(kd - want) > 1e-4f)
                bad++;
        }
        /* the texture's mean over the floor: u = (x + 1) / 2 over [0, 1] (clamped bilinear or
         * wrapped, the two halves are symmetric): 0.5 */
        double mean = area > 0.0 ? akd / area : 0.0;
        printf("texture: %u elements on the black half, %u on the white, %u with the wrong albedo; "
               "shot radiance off "
               "by at most %.2e; mean albedo %.4f (due 0.8 x 0.5 = 0.4)\n",
               nb, nw, bad, worst, mean);
        EXPECT(nb > 4 && nw > 4,
               "too few elements inside the halves (%u, %u): the test set-up is wrong", nb, nw);
        EXPECT(bad == 0, "%u elements with the wrong albedo", bad);
        EXPECT(worst < 1e-5, "shot radiance differs from albedo E / pi by %.3g", worst);
        EXPECT(fabs(mean - 0.4) < 0.008, "mean albedo %.4f, due 0.4", mean);
        vlf_field_free(&f);
    }
    s->textures = NULL;
    s->texture_count = 0;
    free(tex.rgba);
    gi_scene_free(s);
}

/* The hierarchical shortcut of the sort (§3.2): clusters of random
 * triangles, each a scene object inside a small ball, among single random
 * triangles (other objects) and pinwheels of cyclically overlapping sticks;
 * with hier_min = 4 the clusters whose box no other triangle reaches into
 * are sorted on their own: the faces along every ray equal Embree's hits
 * as without the shortcut (>= 99.5 % of the rays, and no more misses than
 * without it + 2), the shortcut was taken (groups > 0) and the pairs of
 * faces tested by Newell's ordering fall. */
static void test_hier(void)
{
    const uint32_t clusters = 12, per = 27, single = 16, cyclic = 8;
    uint32_t count = clusters * per + single + 6 * cyclic, seed = 4242u;
    gi_scene *base = random_triangles(single, cyclic, 777u);
    float *tri = calloc((size_t)count * 9, sizeof *tri), *w = tri;
    for (uint32_t k = 0; k < 3 * (single + 6 * cyclic); k++)
        put(&w, gi_v3(base->vertices[k].position[0], base->vertices[k].position[1],
                      base->vertices[k].position[2]));
    gi_scene_free(base);
    /* a cluster: 3 x 3 x 3 cells of 0.25, a random triangle in the ball of
     * radius 0.124 around each cell's centre (so none intersect) */
    for (uint32_t c = 0; c < clusters; c++) {
        gi_vec3 ctr = gi_v3(4.3f + (float)(c % 3) * 0.9f, 0.2f + (float)(c / 3) * 0.9f,
                            0.2f + (float)(c % 2) * 0.9f);
        for (uint32_t t = 0; t < per; t++) {
            gi_vec3 cell =
                gi_v3_add(ctr, gi_v3(0.25f * (float)(t % 3), 0.25f * (float)((t / 3) % 3),
                                     0.25f * (float)(t / 9)));
            for (int k = 0; k < 3; k++)
                put(&w, gi_v3_add(cell, gi_v3_scale(rand_dir(&seed), 0.124f)));
        }
    }
    gi_scene *s = triangle_scene(tri, count);
    free(tri);
    /* objects: the single and cyclic triangles object 0, each cluster its own */
    uint32_t first = single + 6 * cyclic, nobj = 1 + clusters;
    gi_object *obj = calloc(nobj, sizeof *obj);
    for (uint32_t o = 0; o < nobj; o++) {
        obj[o].node = 0;
        obj[o].first_triangle = o == 0 ? 0 : first + (o - 1) * per;
        obj[o].triangle_count = o == 0 ? first : per;
        obj[o].first_vertex = 3 * obj[o].first_triangle;
        obj[o].vertex_count = 3 * obj[o].triangle_count;
        memcpy(obj[o].local_bounds, s->objects[0].local_bounds, sizeof obj[o].local_bounds);
    }
    for (uint32_t t = first; t < count; t++)
        for (int k = 0; k < 3; k++)
            s->vertices[3 * t + (uint32_t)k].object = 1 + (t - first) / per;
    free(s->objects);
    s->objects = obj;
    s->object_count = nobj;
    gi_rt *rt = NULL;
    gi_error e;
    EXPECT(gi_rt_create(s, 0.0f, &rt, &e) == GI_OK, "embree: %s", e.text);
    if (!rt) {
        gi_scene_free(s);
        return;
    }
    uint32_t miss[2] = {0, 0}, hits[2] = {0, 0};
    uint64_t tests[2] = {0, 0}, groups[2] = {0, 0};
    for (int k = 0; k < 2; k++) {
        vlf_settings p = defaults();
        p.l = 16, p.N = 64, p.density = 8, p.bsp_levels = 0;
        p.hier_min = k ? 4 : 0;
        vlf_field f;
        gi_error err;
        gi_result rc = vlf_field_build(&f, s, 0.0f, &p, &err);
        EXPECT(rc == GI_OK, "%s", err.text);
        if (rc != GI_OK)
            continue;
        uint32_t agree, multi;
        hits[k] = order_against_embree(&f, rt, &agree, &multi);
        miss[k] = hits[k] - agree;
        tests[k] = f.st.sort_tests;
        groups[k] = f.st.sort_groups;
        printf("hier %-16s %u rays hit, %u meet 2+ faces; agree with Embree on %u (%.3f %%); %llu "
               "pairs tested, "
               "%llu objects sorted on their own (of %u x %u), %llu fallbacks, %llu cycle splits\n",
               k ? "shortcut on" : "shortcut off", hits[k], multi, agree,
               100.0 * agree / (hits[k] ? hits[k] : 1), (unsigned long long)tests[k],
               (unsigned long long)groups[k], clusters, p.l,
               (unsigned long long)f.st.sort_hier_fallbacks, (unsigned long long)f.st.sort_splits);
        EXPECT(multi > hits[k] / 10,
               "too few rays meet two faces (%u of %u): the test set-up is wrong", multi, hits[k]);
        EXPECT(agree >= hits[k] - hits[k] / 200,
               "depth order disagrees with Embree on %u of %u rays", hits[k] - agree, hits[k]);
        vlf_field_free(&f);
    }
    EXPECT(groups[1] > 0, "the shortcut was never taken");
    EXPECT(groups[0] == 0, "the shortcut was taken while off");
    EXPECT(miss[1] <= miss[0] + 2, "with the shortcut %u rays miss, without %u", miss[1], miss[0]);
    EXPECT(tests[1] < tests[0], "the shortcut did not save pair tests (%llu vs %llu)",
           (unsigned long long)tests[1], (unsigned long long)tests[0]);
    gi_rt_free(rt);
    gi_scene_free(s);
}

/* Propagation on the GPU (vlf_gpu.c): the same field propagated by the
 * CPU's sweeps and by the compute passes, on the glossy Cornell box (mirror
 * and glossy faces: sweeps, gathers, scattering) in the three storage
 * formats, on a sky-lit scene and on a textured one. The GPU's irradiance
 * atlas and tiles must lie within a relative L1 of 1e-4 (32f) / 2e-3 (16f, rgb9e5) of the
 * CPU's, and at least 10x closer than the CPU's own field one iteration
 * short (a wrong answer near the right one; the black map scores 100 %);
 * the flux counters agree within 1e-4. Prints both propagation times and
 * the GL renderer. */
static void gpu_case(vlf_gpu *gp, const char *scene, uint32_t prec, double bound)
{
    gi_scene *s = load(scene);
    if (!s)
        return;
    static const char *name[3] = {"32f", "16f", "rgb9e5"};
    vlf_settings p = defaults();
    p.l = 32, p.N = 32, p.density = 8, p.iterations = 4, p.precision = prec;
    vlf_field cpu, gpu, shortf;
    gi_error err;
    int ok = vlf_field_build(&cpu, s, 0.0f, &p, &err) == GI_OK;
    EXPECT(ok, "%s", err.text);
    ok = ok && vlf_field_build(&gpu, s, 0.0f, &p, &err) == GI_OK;
    EXPECT(ok, "%s", err.text);
    vlf_settings ps = p;
    ps.iterations = p.iterations - 1;
    ok = ok && vlf_field_build(&shortf, s, 0.0f, &ps, &err) == GI_OK;
    EXPECT(ok, "%s", err.text);
    if (!ok) {
        gi_scene_free(s);
        return;
    }
    EXPECT(vlf_field_propagate(&cpu, NULL, NULL, NULL) == GI_OK, "CPU propagation failed");
    EXPECT(vlf_field_propagate(&shortf, NULL, NULL, NULL) == GI_OK, "CPU propagation failed");
    vlf_gpu *g = gp;
    int gok = vlf_gpu_setup(g, &gpu, &err) == GI_OK;
    EXPECT(gok, "%s", err.text);
    if (gok) {
        gok = vlf_gpu_propagate(g, &gpu, NULL, NULL, &err) == GI_OK;
        EXPECT(gok, "%s", err.text);
    }
    if (gok) {
        double eE = rel_l1(gpu.E_tot, cpu.E_tot, cpu.elem_count);
        double eT = rel_l1(gpu.out_tot, cpu.out_tot, cpu.nd_cells);
        double sE = rel_l1(shortf.E_tot, cpu.E_tot, cpu.elem_count);
        double sT = cpu.nd_cells ? rel_l1(shortf.out_tot, cpu.out_tot, cpu.nd_cells) : 0.0;
        double dshot = fabs(gpu.st.flux_shot - cpu.st.flux_shot) / fmax(cpu.st.flux_shot, 1e-30);
        double drecv =
            fabs(gpu.st.flux_received - cpu.st.flux_received) / fmax(cpu.st.flux_received, 1e-30);
        printf("gpu %s %-6s: %u elements, %u tile cells; GPU against CPU: irradiance %.2e, tiles "
               "%.2e (one iteration "
               "short: %.2e, %.2e); shot %.2e, received %.2e; propagate CPU %.3f s, GPU %.3f s "
               "(set-up %.3f s, "
               "read-back %.3f s): CPU/GPU %.2f\n",
               scene, name[prec], cpu.elem_count, cpu.nd_cells, eE, eT, sE, sT, dshot, drecv,
               cpu.st.propagate_s, gpu.st.propagate_s, g->setup_s, g->readback_s,
               cpu.st.propagate_s / fmax(gpu.st.propagate_s + g->setup_s, 1e-9));
        EXPECT(eE < bound && eE * 10.0 < sE,
               "%s %s: GPU irradiance differs from the CPU's by %.3g (bound %.3g, "
               "one iteration short %.3g)",
               scene, name[prec], eE, bound, sE);
        if (cpu.nd_cells)
            EXPECT(eT < bound && eT * 10.0 < sT,
                   "%s %s: GPU tiles differ from the CPU's by %.3g (bound %.3g, one "
                   "iteration short %.3g)",
                   scene, name[prec], eT, bound, sT);
        EXPECT(dshot < 1e-4 && drecv < 1e-4, "%s: flux counters differ: shot %.3g, received %.3g",
               scene, dshot, drecv);
        EXPECT(gpu.st.samples == cpu.st.samples, "samples %llu vs %llu",
               (unsigned long long)gpu.st.samples, (unsigned long long)cpu.st.samples);
    }
    vlf_field_free(&cpu);
    vlf_field_free(&gpu);
    vlf_field_free(&shortf);
    gi_scene_free(s);
}

static void test_gpu(void)
{
    gi_error e;
    gi_gpu *ctx = gi_gpu_create(NULL, &e);
    EXPECT(ctx != NULL, "no GL context: %s", e.text);
    if (!ctx)
        return;
    EXPECT(gi_shader_register(gi_vlf_shaders, &e) == GI_OK, "shaders: %s", e.text);
    printf("gpu: GL renderer %s\n", gi_gpu_renderer(ctx));
    vlf_gpu g;
    gi_error err;
    int ok = vlf_gpu_init(&g, &err) == GI_OK;
    EXPECT(ok, "%s", err.text);
    if (ok) {
        gpu_case(&g, "scenes/cornell_glossy.gltf", VLF_PREC_32F, 1e-4);
        gpu_case(&g, "scenes/cornell_glossy.gltf", VLF_PREC_16F, 2e-3);
        gpu_case(&g, "scenes/cornell_glossy.gltf", VLF_PREC_RGB9E5, 2e-3);
        gpu_case(&g, "scenes/bunny_alone_env.glb", VLF_PREC_32F, 1e-4);
        gpu_case(&g, "scenes/teapot_plane.glb", VLF_PREC_32F, 1e-4); /* a double-sided teapot */
        vlf_gpu_free(&g);
    }
    gi_gpu_destroy(ctx);
}

/* Irradiance at world point x on a surface of unit normal n from the
 * panel scene's light (plugins/vlf/data/gen_scenes.py: a 0.5 x 0.5 square at
 * (0, 1.3, 1) facing the panel's centre, Le = 6), by 32 x 32 point patches
 * with both cosines; nothing stands between them. */
static double panel_light_E(gi_vec3 x, gi_vec3 n)
{
    gi_vec3 c = gi_v3(0.0f, 1.3f, 1.0f), ln = gi_v3_normalize(gi_v3(0.0f, -1.3f, -1.0f));
    gi_vec3 e1 = gi_v3(1, 0, 0), e2 = gi_v3_cross(ln, e1);
    double E = 0.0, dA = 0.25 / (32.0 * 32.0);
    for (int j = 0; j < 32; j++)
        for (int i = 0; i < 32; i++) {
            float u = ((float)i + 0.5f) / 32.0f - 0.5f, v = ((float)j + 0.5f) / 32.0f - 0.5f;
            gi_vec3 y =
                gi_v3_add(c, gi_v3_add(gi_v3_scale(e1, 0.5f * u), gi_v3_scale(e2, 0.5f * v)));
            gi_vec3 d = gi_v3_sub(y, x);
            double r2 = gi_v3_dot(d, d), r = sqrt(r2);
            double cx = gi_v3_dot(n, d) / r, cy = -gi_v3_dot(ln, d) / r;
            if (cx > 0.0 && cy > 0.0)
                E += 6.0 * cx * cy * dA / r2;
        }
    return E;
}

/* Double-sided materials (§3.1: values for both sides): the thin panel of
 * plugins/vlf/data/panel_double.gltf lit from its back side, 1 iteration. */
static void test_double(void)
{
    const char *names[2] = {"plugins/vlf/data/panel_double.gltf",
                            "plugins/vlf/data/panel_single.gltf"};
    double recv_double = -1.0;
    for (int sc = 0; sc < 2; sc++) {
        gi_scene *s = load(names[sc]);
        if (!s)
            continue;
        uint32_t orders[3] = {VLF_ORDER_FACES, VLF_ORDER_RAYS, VLF_ORDER_FACES},
                 perturbed[3] = {0, 0, 3};
        float *E_faces = NULL;
        for (int run = 0; run < (sc == 0 ? 3 : 1); run++) {
            vlf_settings p = defaults();
            p.iterations = 1;
            p.order = orders[run], p.perturbed = perturbed[run];
            vlf_field f;
            gi_error err;
            gi_result rc = vlf_field_build(&f, s, 0.0f, &p, &err);
            EXPECT(rc == GI_OK, "%s", err.text);
            if (rc != GI_OK)
                continue;
            vlf_field_propagate(&f, NULL, NULL, NULL);
            const vlf_stats *st = &f.st;
            CHECK_NEAR(st->flux_shot, st->flux_received + st->flux_back + st->flux_escaped,
                       1e-4 * st->flux_shot);
            /* the panel's sides: lit (normal toward the light, +z), dark (-z) */
            int lit = -1, dark = -1;
            for (uint32_t fi = 0; fi < f.face_count; fi++)
                if (f.faces[fi].emission[0] == 0.0f)
                    *(f.faces[fi].n.z > 0.0f ? &lit : &dark) = (int)fi;
            if (sc == 1) {
                /* single-sided: only the dark side exists; the light lands on its back */
                EXPECT(lit < 0 && dark >= 0 && f.faces[dark].twin < 0,
                       "single-sided panel: faces %d / %d", lit, dark);
                /* the light the double-sided panel's lit side received lands on its back */
                printf("double: single-sided panel: flux received %.4f, met a back side %.4f "
                       "(double-sided "
                       "received %.4f)\n",
                       st->flux_received, st->flux_back, recv_double);
                EXPECT(st->flux_received < 1e-3 * st->flux_back,
                       "single-sided: received %.4g, back %.4g", st->flux_received, st->flux_back);
                EXPECT(fabs(st->flux_back - recv_double) < 0.02 * recv_double,
                       "single-sided back %.4g, double-sided received %.4g", st->flux_back,
                       recv_double);
                vlf_field_free(&f);
                continue;
            }
            EXPECT(lit >= 0 && dark >= 0, "double-sided panel: faces %d / %d", lit, dark);
            if (lit < 0 || dark < 0) {
                vlf_field_free(&f);
                continue;
            }
            const vlf_face *fl = &f.faces[lit], *fd = &f.faces[dark];
            EXPECT(fl->twin == dark && fd->twin == lit && fl->back != fd->back && fl->W == fd->W &&
                       fl->H == fd->H,
                   "the two sides are not each other's twin");
            /* lit side: the mean irradiance of its upper and lower halves (3x apart)
             * (whole elements) each within 5 % of the light's irradiance at
             * their centres (single elements alias: the small light is seen
             * through a few directions only); dark side: nothing (no light
             * through the panel) */
            double sum[2] = {0, 0}, sum_ref[2] = {0, 0}, dark_max = 0.0;
            uint32_t n = 0;
            float texel = 1.0f / (p.density * p.density);
            for (uint32_t e = 0; e < fl->W * fl->H; e++) {
                uint32_t el = fl->first_elem + e, ed = fd->first_elem + e;
                EXPECT(f.elem_area[el] == f.elem_area[ed], "element areas of the two sides differ");
                dark_max = fmax(dark_max, f.E_tot[3 * (size_t)ed]);
                if (f.elem_area[el] < 0.99f * texel)
                    continue;
                gi_vec3 q = gi_v3_add(
                    fl->origin,
                    gi_v3_add(gi_v3_scale(fl->t, f.elem_c[2 * (size_t)el] / p.density),
                              gi_v3_scale(fl->b, f.elem_c[2 * (size_t)el + 1] / p.density)));
                gi_vec3 x = gi_v3_add(f.centre, gi_v3_scale(q, f.radius));
                int h = x.y > 0.0f;
                sum[h] += f.E_tot[3 * (size_t)el];
                sum_ref[h] += panel_light_E(x, fl->n);
                n++;
            }
            printf("double (order %s, perturbed %u): lit side %u whole elements, irradiance lower "
                   "half %.4f vs %.4f "
                   "(%+.2f %%), upper %.4f vs %.4f (%+.2f %%); dark side max E %.3g; flux received "
                   "%.4f, back %.4g\n",
                   p.order == VLF_ORDER_RAYS ? "rays" : "faces", p.perturbed, n, sum[0], sum_ref[0],
                   100.0 * (sum[0] / sum_ref[0] - 1.0), sum[1], sum_ref[1],
                   100.0 * (sum[1] / sum_ref[1] - 1.0), dark_max, st->flux_received, st->flux_back);
            EXPECT(n > 100, "only %u whole elements on the lit side", n);
            for (int h = 0; h < 2; h++)
                EXPECT(fabs(sum[h] / sum_ref[h] - 1.0) < 0.05,
                       "lit side half %d: irradiance %.4f vs %.4f", h, sum[h], sum_ref[h]);
            EXPECT(dark_max == 0.0, "light through the panel: %.3g on its dark side", dark_max);
            EXPECT(st->flux_back < 1e-6 * st->flux_received, "light met a back side: %.4g",
                   st->flux_back);
            if (run == 0) {
                E_faces = malloc((size_t)f.elem_count * 3 * sizeof *E_faces);
                if (E_faces)
                    memcpy(E_faces, f.E_tot, (size_t)f.elem_count * 3 * sizeof *E_faces);
                recv_double = st->flux_received;
            } else if (run == 1 && E_faces) {
                /* the per-ray sort keeps the two sides' fragments in the same order */
                double d = 0.0, tot = 0.0;
                for (size_t k = 0; k < (size_t)f.elem_count * 3; k++)
                    d += fabs(f.E_tot[k] - E_faces[k]), tot += fabs(E_faces[k]);
                printf("double: order rays against faces: relative L1 %.3g\n", d / tot);
                EXPECT(d <= 1e-6 * tot, "order rays differs from faces: relative L1 %.3g", d / tot);
            }
            vlf_field_free(&f);
        }
        free(E_faces);
        gi_scene_free(s);
    }
}

int main(int argc, char **argv)
{
    const char *part = argc > 1 ? argv[1] : "all";
    int all = strcmp(part, "all") == 0, any = 0;
    if (all || strcmp(part, "dirs") == 0)
        test_dirs(), any = 1;
    if (all || strcmp(part, "order") == 0)
        test_order(), any = 1;
    if (all || strcmp(part, "energy") == 0)
        test_energy(), any = 1;
    if (all || strcmp(part, "furnace") == 0)
        test_furnace(), any = 1;
    if (all || strcmp(part, "mirror") == 0)
        test_mirror(), any = 1;
    if (all || strcmp(part, "precision") == 0)
        test_precision(), any = 1;
    if (all || strcmp(part, "sun") == 0)
        test_sun(), any = 1;
    if (all || strcmp(part, "point") == 0)
        test_point(), test_point_mirror(), any = 1;
    if (all || strcmp(part, "albedo") == 0)
        test_albedo(), any = 1;
    if (all || strcmp(part, "texture") == 0)
        test_texture(), any = 1;
    if (all || strcmp(part, "hier") == 0)
        test_hier(), any = 1;
    if (all || strcmp(part, "gpu") == 0)
        test_gpu(), any = 1;
    if (all || strcmp(part, "double") == 0)
        test_double(), any = 1;
    if (!any) {
        fprintf(stderr,
                "vlf_tests: unknown part '%s' (dirs, order, energy, furnace, mirror, precision, "
                "sun, point, albedo, texture, hier, gpu, double)\n",
                part);
        return 2;
    }
    return gi_test_finish();
}
