/* cssm_tests' parts on the compact nodes of cssm_hrc (§4.2.1, compact.c):
 *   compact        random round trips within the stated bounds,
 *                  conservative spheres and cones on the Cornell box tree,
 *                  exact pointers, equal traversals, the packed pull
 *                  against the float pull
 *   compact_limit  65 535 nodes pack, 65 537 are refused */
#include "cssm_tests.h"

#include "check.h"

#include "gi/rng.h"
#include "gi/sampling.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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

/* The skip-pointer traversal of the tree part over packed nodes. */
static void stackless_compact(const cssm_ctree *ct, uint32_t salt, int full, uint32_t *out,
                              uint32_t *n)
{
    int32_t i = 0;
    while (i >= 0) {
        cssm_node_view v;
        cssm_ctree_view(ct, (uint32_t)i, &v);
        if (v.child >= 0 && (full || cssm_test_decide((uint32_t)i, salt))) {
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

/* The random nodes' ranges: the centre box, radius and area. */
static const float box_lo[3] = {-1.0f, 0.0f, 2.0f}, box_hi[3] = {3.0f, 0.5f, 2.25f};
static const float r_lo = 1e-3f, r_hi = 4.0f, a_lo = 1e-5f, a_hi = 10.0f;

/* What the round trips found: counts of nodes beyond the bounds, the
 * largest errors, the intensity's signed error. */
typedef struct round_trips {
    uint32_t bad_c, bad_r, loose_r, bad_n, bad_k, loose_k, bad_a, bad_i, bad_p;
    float max_n, max_i, max_dk;
    double bias_i;
    uint32_t bias_n;
} round_trips;

/* Random node i: centre in the box, radius and area log-uniform, any
 * normal, cones of every width (every 7th everything), intensities over
 * 42 binary orders (some channels 0), pointers (some none, node 1 the
 * extremes). */
static cssm_node_view random_node(const cssm_ctree *ct, uint32_t i, uint32_t *rng)
{
    cssm_node_view v = {0};
    float p[3];
    for (int k = 0; k < 3; k++)
        p[k] = box_lo[k] + (box_hi[k] - box_lo[k]) * gi_rng_next_float(rng);
    v.c = gi_v3(p[0], p[1], p[2]);
    v.r = rnd_log(rng, r_lo, r_hi * 0.5f);
    v.n = gi_sample_uniform_sphere(gi_rng_next_float(rng), gi_rng_next_float(rng));
    v.cos_cone =
        (i % 7) == 0 ? -1.0f : 1.0f - 2.0f * gi_rng_next_float(rng) * gi_rng_next_float(rng);
    v.area = rnd_log(rng, a_lo, a_hi);
    float mag = ct->iscale * exp2f(-40.0f + 42.0f * gi_rng_next_float(rng));
    for (int k = 0; k < 3; k++)
        v.I[k] =
            (gi_pcg_hash(i * 3u + (uint32_t)k) % 5u) == 0 ? 0.0f : mag * gi_rng_next_float(rng);
    v.child = (i % 5) == 0 ? -1 : (int32_t)(gi_rng_next_u32(rng) % CSSM_COMPACT_MAX_NODES);
    v.skip = (i % 3) == 0 ? -1 : (int32_t)(gi_rng_next_u32(rng) % CSSM_COMPACT_MAX_NODES);
    if (i == 1)
        v.child = (int32_t)CSSM_COMPACT_MAX_NODES - 1, v.skip = 0;
    return v;
}

/* Compares the decoded node d with the true one v into the tally (rstep
 * and astep: one code of the radius and the area). */
static void judge_round_trip(const cssm_node_view *v, const cssm_node_view *d, float rstep,
                             float astep, round_trips *t)
{
    float dc[3] = {d->c.x - v->c.x, d->c.y - v->c.y, d->c.z - v->c.z};
    for (int k = 0; k < 3; k++)
        t->bad_c += fabsf(dc[k]) > 0.5f * (box_hi[k] - box_lo[k]) / 255.0f * 1.0001f + 1e-6f;
    float need = v->r + gi_v3_length(gi_v3_sub(v->c, d->c));
    t->bad_r += d->r < need;
    t->loose_r += d->r > fmaxf(need, r_lo) * rstep * 1.0001f;
    float an = angle_between(v->n, d->n);
    t->max_n = fmaxf(t->max_n, an);
    t->bad_n += an > 1e-3f;
    if (v->cos_cone <= -1.0f) {
        t->bad_k += d->cos_cone > -1.0f;
    } else {
        /* compared as cosines: the decoded cone must reach the true
         * cone's angle plus the normal's rounding, and stay within one
         * code (pi / 255) of it */
        float kneed = acosf(v->cos_cone) + an;
        t->bad_k += kneed < (float)GI_PI && d->cos_cone > cosf(kneed) + 1e-6f;
        t->loose_k += kneed + (float)GI_PI / 255.0f < (float)GI_PI &&
                      d->cos_cone < cosf(kneed + (float)GI_PI / 255.0f) - 1e-6f;
        t->max_dk = fmaxf(t->max_dk, acosf(fmaxf(-1.0f, d->cos_cone)) - kneed);
    }
    t->bad_a += fabsf(logf(d->area / v->area)) > 0.5f * astep * 1.001f;
    float mx = fmaxf(v->I[0], fmaxf(v->I[1], v->I[2]));
    for (int k = 0; k < 3; k++) {
        float e = fabsf(d->I[k] - v->I[k]);
        t->bad_i += e > mx / 31.5f * 1.0001f;
        if (mx > 0.0f) {
            t->max_i = fmaxf(t->max_i, e / mx);
            t->bias_i += (double)(d->I[k] - v->I[k]) / mx, t->bias_n++;
        }
    }
    t->bad_p += d->child != v->child || d->skip != v->skip;
}

/* §4.2.1 encoding: random nodes round trip within the stated bounds
 * (centre half a step per axis; sphere and cone of the decoded node hold
 * the true ones, at most one code larger; area within half a log step;
 * intensity within 1/31.5 of its largest channel, zero on average;
 * pointers exact). 1 when the set-up fails. */
static int compact_round_trips(void)
{
    gi_error err;
    cssm_ctree ct;
    const uint32_t N = 20000;
    if (cssm_ctree_setup(&ct, N, box_lo, box_hi, r_lo, r_hi, a_lo, a_hi, &err) != GI_OK) {
        fprintf(stderr, "FAIL: %s\n", err.text);
        return 1;
    }
    ct.iscale = 3.0f;
    const float rstep = powf(r_hi / r_lo, 1.0f / 255.0f), astep = logf(a_hi / a_lo) / 255.0f;
    uint32_t rng = gi_rng_init(7, 0, 0xc0au);
    round_trips t = {0};
    for (uint32_t i = 0; i < N; i++) {
        cssm_node_view v = random_node(&ct, i, &rng), d;
        cssm_ctree_encode(&ct, i, &v);
        cssm_ctree_view(&ct, i, &d);
        judge_round_trip(&v, &d, rstep, astep, &t);
    }
    CHECK_MSG(!t.bad_c, "%u centres off by more than half a step", t.bad_c);
    CHECK_MSG(!t.bad_r && !t.loose_r,
              "radius: %u smaller than the true sphere needs, %u more than one code larger",
              t.bad_r, t.loose_r);
    CHECK_MSG(!t.bad_n, "%u normals off by more than 1e-3 rad", t.bad_n);
    CHECK_MSG(!t.bad_k && !t.loose_k,
              "cone: %u narrower than the true cone, %u more than one code wider", t.bad_k,
              t.loose_k);
    CHECK_MSG(!t.bad_a, "%u areas off by more than half a log step", t.bad_a);
    CHECK_MSG(!t.bad_i, "%u intensity channels off by more than 1/31.5 of the largest", t.bad_i);
    CHECK_MSG(!t.bad_p, "%u pointers changed", t.bad_p);
    /* the dithered rounding: a mean signed error within a few standard
     * errors of 0 (one step is at most 1/31.5, a uniform error's sd 1/109) */
    t.bias_i /= t.bias_n;
    CHECK_MSG(fabs(t.bias_i) < 4.0 / (109.0 * sqrt((double)t.bias_n)) + 1e-4,
              "intensity rounding biased by %.5f", t.bias_i);
    printf("compact: %u random nodes: normal error at most %.2e rad (%.4f deg), cone widened by at "
           "most %.4f rad, "
           "intensity error at most %.4f of the largest channel (mean signed %+.5f), radius step "
           "x%.4f, area step x%.4f\n",
           N, (double)t.max_n, (double)t.max_n * 180.0 / GI_PI, (double)t.max_dk, (double)t.max_i,
           t.bias_i, (double)rstep, (double)expf(astep));
    cssm_ctree_free(&ct);
    return 0;
}

/* On the packed tree ct of t: every texel inside its node's decoded
 * sphere and cone, pointers equal to the float tree's, and the log radius
 * code against a linear one (mean over-estimates of both returned). */
static void compact_tree_bounds(const cssm_tree *t, const cssm_atlas *a, const cssm_ctree *ct,
                                double *over_log_out, double *over_lin_out)
{
    uint32_t outside = 0, out_cone = 0, ptr = 0;
    double over_log = 0.0, over_lin = 0.0;
    float rmax = ct->rtab[255];
    for (uint32_t i = 0; i < t->count; i++) {
        cssm_node_view f = float_view(t, (int32_t)i), d;
        cssm_ctree_view(ct, i, &d);
        ptr += d.child != f.child || d.skip != f.skip || d.first != f.first || d.count != f.count ||
               d.rep != f.rep;
        float need = 0.0f;
        for (uint32_t k = f.first; k < f.first + f.count; k++) {
            const cssm_texel *x = &a->texels[t->leaves[k]];
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
    over_log /= t->count;
    over_lin /= t->count;
    CHECK_MSG(!outside, "%u texels outside their node's decoded sphere", outside);
    CHECK_MSG(!out_cone, "%u texel normals outside their node's decoded cone", out_cone);
    CHECK_MSG(!ptr,
              "%u nodes whose pointers, leaves or visibility texel differ from the float tree's",
              ptr);
    CHECK_MSG(over_log < over_lin,
              "the log radius code (%.3f) is not tighter than a linear one (%.3f)", over_log,
              over_lin);
    *over_log_out = over_log;
    *over_lin_out = over_lin;
}

/* Skip-pointer traversals over packed nodes equal to those over float
 * nodes (64 selective, 1 full). */
static void compact_traversals(const cssm_tree *t, const cssm_ctree *ct)
{
    uint32_t *x = malloc(t->count * sizeof *x), *y = malloc(t->count * sizeof *y);
    uint32_t differ = 0;
    for (uint32_t salt = 0; salt < 65; salt++) {
        uint32_t nx = 0, ny = 0;
        int full = salt == 64;
        cssm_test_stackless(t, salt, full, x, &nx);
        stackless_compact(ct, salt, full, y, &ny);
        differ += nx != ny || memcmp(x, y, nx * sizeof *x);
    }
    CHECK_MSG(
        !differ,
        "%u of 65 skip-pointer traversals over packed nodes differ from those over float nodes",
        differ);
    free(x);
    free(y);
}

/* The packed pull (re-encoded at each node) against the float pull x
 * area: the mean, worst and root errors relative to the largest channel. */
static void compact_pull(const cssm_tree *t, const cssm_atlas *a, cssm_ctree *ct, double *mean_out,
                         double *worst_out, double *root_out)
{
    float *tl = malloc(3 * a->count * sizeof *tl), *nl = malloc(3 * t->count * sizeof *nl);
    for (uint32_t i = 0; i < a->count; i++)
        for (int k = 0; k < 3; k++)
            tl[3 * i + k] = a->texels[i].albedo[k] + 10.0f * a->texels[i].emission[k];
    cssm_tree_pull(t, a, tl, nl);
    cssm_ctree_pull(ct, a, tl);
    /* each re-encoding errs by at most 1/31.5 of the node's largest channel
     * (at most its channel sum S); the nodes of one level below a node sum
     * to its S, so a node of height h errs by at most (h + 1) S / 31.5 */
    uint32_t *height = calloc(t->count, sizeof *height), over = 0;
    double worst = 0.0, mean = 0.0, root = 0.0;
    for (int32_t i = (int32_t)t->count - 1; i >= 0; i--) {
        const cssm_node *nd = &t->nodes[i];
        if (nd->child >= 0)
            height[i] = 1 + (height[nd->child] > height[t->nodes[nd->child].skip]
                                 ? height[nd->child]
                                 : height[t->nodes[nd->child].skip]);
        cssm_node_view d;
        cssm_ctree_view(ct, (uint32_t)i, &d);
        float mx = 0.0f, sum = 0.0f;
        for (int k = 0; k < 3; k++)
            mx = fmaxf(mx, nl[3 * i + k] * nd->area), sum += nl[3 * i + k] * nd->area;
        for (int k = 0; k < 3; k++) {
            double e = fabs(d.I[k] - nl[3 * i + k] * nd->area);
            over += e > (height[i] + 1) * sum / 31.5 * 1.001;
            worst = fmax(worst, e / mx);
            mean += e / mx / (3.0 * t->count);
            if (i == 0)
                root = fmax(root, e / mx);
        }
    }
    free(height);
    CHECK_MSG(!over, "packed pull: %u channels beyond the bound (h + 1) S / 31.5", over);
    free(tl);
    free(nl);
    *mean_out = mean;
    *worst_out = worst;
    *root_out = root;
}

/* §4.2.1 encoding: the random round trips; on the Cornell box tree:
 * every texel inside its node's decoded sphere and cone, pointers equal
 * to the float tree's, skip-pointer traversals over packed nodes equal to
 * those over float nodes, the packed pull against the float pull, and the
 * log radius code against a linear one. */
int cssm_test_compact(void)
{
    if (compact_round_trips())
        return 1;
    /* the Cornell box's tree */
    gi_scene *s = cssm_test_load("scenes/cornell_box.gltf");
    if (!s)
        return 1;
    gi_error err;
    cssm_atlas a;
    cssm_tree t;
    cssm_ctree ct;
    if (cssm_atlas_build(s, 0.0f, 32, 0, &a, &err) != GI_OK ||
        cssm_tree_build(&a, &t, &err) != GI_OK || cssm_ctree_build(&t, &a, &ct, &err) != GI_OK) {
        fprintf(stderr, "FAIL: %s\n", err.text);
        gi_scene_free(s);
        return 1;
    }
    double over_log, over_lin, mean, worst, root;
    compact_tree_bounds(&t, &a, &ct, &over_log, &over_lin);
    compact_traversals(&t, &ct);
    compact_pull(&t, &a, &ct, &mean, &worst, &root);
    printf(
        "compact: Cornell box 32^2, %u nodes (%zu bytes each as floats + radiance, %zu packed): "
        "texels inside "
        "decoded spheres and cones, pointers exact, 65 traversals equal; radius over-estimate log "
        "%.3f, linear "
        "%.3f (mean); packed pull error mean %.4f, worst %.4f, root %.4f of the largest channel\n",
        t.count, sizeof(cssm_node) + 3 * sizeof(float), sizeof(cssm_pnode), over_log, over_lin,
        mean, worst, root);
    cssm_ctree_free(&ct);
    cssm_tree_free(&t);
    cssm_atlas_free(&a);
    gi_scene_free(s);
    return 0;
}

/* 16-bit pointers: a tree of 65 535 nodes (32 768 texels) packs with
 * every pointer exact, one of 65 537 (32 769 texels) is refused with a
 * one-line error. */
int cssm_test_compact_limit(void)
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
