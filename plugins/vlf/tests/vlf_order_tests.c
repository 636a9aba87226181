/* The vlf plugin's direction set and depth order (paper §2.1, §3.2)
 * against independent computations (the plugin's CPU sources are compiled
 * in; see plugins/vlf/README.md "Tests"):
 *
 *   vlf_order_tests dirs   the direction set covers the sphere evenly (largest
 *                          angular gap to the nearest direction bounded), the
 *                          triangulation is a closed sphere (Euler, solid
 *                          angles sum to 4 pi, every direction in at least 3
 *                          triangles, each triangle counter-clockwise),
 *                          barycentric weights of random directions are
 *                          non-negative, sum to 1 and reproduce the
 *                          direction; a node gets weight 1 itself;
 *   vlf_order_tests locate the grid search of vlf_dirs_locate gives exactly
 *                          the brute force's triangle and weights (random
 *                          directions, nodes, edge midpoints and points just
 *                          off them, the grid's cell seams, axes, signed
 *                          zeros, unnormalised, zero and NaN directions) and
 *                          its lists are short;
 *   vlf_order_tests order  the depth order on random non-intersecting
 *                          triangles, pinwheels of cyclically overlapping
 *                          sticks among them: the faces along every ray of
 *                          every subfield, in order, equal the Embree hits
 *                          along the ray, for the face order (Newell with
 *                          splitting, with and without BSP cuts) and the
 *                          per-ray sort, while the plain sort by nearest
 *                          depth fails; the face order is the same on 1, 2
 *                          and 5 threads;
 *   vlf_order_tests hier   the hierarchical shortcut of the sort (objects in
 *                          boxes nothing else reaches into sorted on their
 *                          own) keeps the depth order right (Embree) and
 *                          saves tests. */
#include "vlf_field.h"
#include "vlf_test_util.h"

#include "gi/raytrace.h"
#include "gi/scene.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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

/* One direction through both searches: the same triangle, nodes and
 * weights, bit for bit. 1 when equal. */
static int locate_same(const vlf_dirs *d, gi_vec3 w)
{
    uint32_t n1[3], n2[3];
    float a1[3], a2[3];
    uint32_t t1 = vlf_dirs_locate(d, w, n1, a1), t2 = vlf_dirs_locate_all(d, w, n2, a2);
    return t1 == t2 && !memcmp(n1, n2, sizeof n1) && !memcmp(a1, a2, sizeof a1);
}

/* The directions of locate's test for set d into locate_same; the count of
 * disagreements. */
static uint32_t locate_cases(const vlf_dirs *d, uint32_t *tried)
{
    uint32_t bad = 0, seed = 777u, k = 0;
    for (int q = 0; q < 5000; q++, k++)
        bad += !locate_same(d, gi_v3_scale(rand_dir(&seed), q % 2 ? 1.0f : 3.5f));
    for (uint32_t t = 0; t < d->tri_count; t++)
        for (int j = 0; j < 3; j++) {
            gi_vec3 a = d->signed_dirs[d->tris[3 * t + j]];
            gi_vec3 b = d->signed_dirs[d->tris[3 * t + (j + 1) % 3]];
            gi_vec3 mid = gi_v3_normalize(gi_v3_add(a, b)), off = gi_v3_cross(a, b);
            bad += !locate_same(d, a) + !locate_same(d, mid);
            bad += !locate_same(d, gi_v3_add(mid, gi_v3_scale(off, 1e-6f)));
            bad += !locate_same(d, gi_v3_add(mid, gi_v3_scale(off, -1e-6f)));
            k += 4;
        }
    /* the seams of the grid's cells, and beside them */
    uint32_t n = d->grid_n;
    for (uint32_t f = 0; f < 6; f++)
        for (uint32_t i = 0; i <= n; i++)
            for (uint32_t j = 0; j <= 4 * n; j++) {
                float u = -1.0f + 2.0f * (float)i / (float)n, v = -1.0f + 0.5f * (float)j / n;
                for (int e = -1; e <= 1; e++) {
                    float p[3], ue = u + (float)e * 1e-7f;
                    p[f / 2] = (f & 1) ? -1.0f : 1.0f;
                    p[(f / 2 + 1) % 3] = (k & 1) ? ue : v;
                    p[(f / 2 + 2) % 3] = (k & 1) ? v : ue;
                    bad += !locate_same(d, gi_v3(p[0], p[1], p[2]));
                    k++;
                }
            }
    const gi_vec3 odd[] = {gi_v3(1, 0, 0),        gi_v3(-1, 0, 0),     gi_v3(0, 1, 0),
                           gi_v3(0, -1, 0),       gi_v3(0, 0, 1),      gi_v3(0, 0, -1),
                           gi_v3(-0.0f, 0, 1),    gi_v3(1, 1, 1),      gi_v3(-1, 1, -1),
                           gi_v3(0, 0, 0),        gi_v3(NAN, 0, 1),    gi_v3(1, NAN, 0),
                           gi_v3(INFINITY, 0, 0), gi_v3(1e-30f, 0, 0), gi_v3(1e30f, 1e30f, 0)};
    for (size_t q = 0; q < sizeof odd / sizeof odd[0]; q++, k++)
        bad += !locate_same(d, odd[q]);
    *tried = k;
    return bad;
}

static void test_locate(void)
{
    uint32_t ls[] = {4, 8, 32, 512};
    for (size_t li = 0; li < sizeof ls / sizeof ls[0]; li++) {
        vlf_dirs d;
        gi_error err;
        EXPECT(vlf_dirs_build(&d, ls[li], &err) == GI_OK, "%s", err.text);
        uint32_t tried = 0, bad = locate_cases(&d, &tried);
        uint32_t cells = 6 * d.grid_n * d.grid_n, longest = 0;
        for (uint32_t c = 0; c < cells; c++)
            longest = d.cell_start[c + 1] - d.cell_start[c] > longest
                          ? d.cell_start[c + 1] - d.cell_start[c]
                          : longest;
        double mean = (double)d.cell_start[cells] / cells;
        printf("locate l=%u: %u triangles, %u cells, lists %.1f on average, %u at most; %u of %u "
               "directions differ\n",
               ls[li], d.tri_count, cells, mean, longest, bad, tried);
        EXPECT(bad == 0, "l=%u: the grid differs from the brute force on %u of %u directions",
               ls[li], bad, tried);
        /* the grid must save work where it matters (l of the default) */
        EXPECT(ls[li] < 512 || mean < 0.02 * d.tri_count, "l=%u: lists of %.1f of %u triangles",
               ls[li], mean, d.tri_count);
        vlf_dirs_free(&d);
    }
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
    /* The fragment lists hold every face a line crosses, both sides (the
     * sort is geometric; sides are applied when light propagates), so the
     * truth is Embree's raw geometry, not the rays of the rule for sides. */
    EXPECT(gi_rt_create_ex(s, 0.0f, GI_RT_ALL_FACES, &rt, &e) == GI_OK, "embree: %s", e.text);
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
    /* The fragment lists hold every face a line crosses, both sides (the
     * sort is geometric; sides are applied when light propagates), so the
     * truth is Embree's raw geometry, not the rays of the rule for sides. */
    EXPECT(gi_rt_create_ex(s, 0.0f, GI_RT_ALL_FACES, &rt, &e) == GI_OK, "embree: %s", e.text);
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

int main(int argc, char **argv)
{
    static const vlf_test_part parts[] = {
        {"dirs", test_dirs}, {"locate", test_locate}, {"order", test_order}, {"hier", test_hier}};
    return vlf_test_main("vlf_order_tests", parts, sizeof parts / sizeof parts[0], argc, argv);
}
