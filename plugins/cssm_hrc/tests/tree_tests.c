/* cssm_tests' part on the hierarchy of cssm_hrc (§4.2):
 *   tree  the skip-pointer traversal equals a recursive depth-first
 *         traversal, for full traversals and for selective ones with
 *         pseudo-random refine decisions; spheres hold their texels,
 *         areas add up
 *   refine_limit  the precomputed limit of the refinement test decides as
 *         the tone-mapped comparison does (§4.3), at the float boundary and
 *         on random bounds */
#include "cssm_tests.h"

#include "check.h"

#include "gi/rng.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int cssm_test_decide(uint32_t node, uint32_t salt)
{
    return (gi_pcg_hash(node * 2654435761u ^ salt) & 3u) != 0;
}

static void recursive(const cssm_tree *t, int32_t i, uint32_t salt, int full, uint32_t *out,
                      uint32_t *n)
{
    const cssm_node *nd = &t->nodes[i];
    if (nd->child >= 0 && (full || cssm_test_decide((uint32_t)i, salt))) {
        /* the right child found independently: the left subtree holds 2 count - 1 nodes */
        int32_t left = nd->child;
        int32_t right = left + (int32_t)(2 * t->nodes[left].count - 1);
        recursive(t, left, salt, full, out, n);
        recursive(t, right, salt, full, out, n);
        return;
    }
    out[(*n)++] = (uint32_t)i;
}

void cssm_test_stackless(const cssm_tree *t, uint32_t salt, int full, uint32_t *out, uint32_t *n)
{
    int32_t i = 0;
    while (i >= 0) {
        const cssm_node *nd = &t->nodes[i];
        if (nd->child >= 0 && (full || cssm_test_decide((uint32_t)i, salt))) {
            i = nd->child;
            continue;
        }
        out[(*n)++] = (uint32_t)i;
        i = nd->skip;
    }
}

int cssm_test_tree(void)
{
    gi_scene *s = cssm_test_load("scenes/cornell_box.gltf");
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
        cssm_test_stackless(&t, salt, full, y, &ny);
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

/* One threshold: the limit agrees with powf(y, 1/2.2) > thr at the limit,
 * its float neighbours and at random bounds spread over many octaves. */
static int refine_limit_agrees(float thr, uint32_t *rng)
{
    const float e = 1.0f / 2.2f, lim = cssm_refine_limit(thr);
    int bad = 0;
    float y = lim;
    for (int k = 0; k < 4; k++)
        y = nextafterf(y, 0.0f);
    for (int k = 0; k < 9; k++, y = nextafterf(y, INFINITY))
        bad += y >= 0.0f && (y > lim) != (powf(y, e) > thr);
    for (int k = 0; k < 100000; k++) {
        float r = ldexpf(gi_rng_next_float(rng), (int)(gi_rng_next_u32(rng) % 60u) - 40);
        bad += (r > lim) != (powf(r, e) > thr);
    }
    CHECK_MSG(bad == 0, "threshold %g: %d bounds decided otherwise than powf", (double)thr, bad);
    return bad;
}

int cssm_test_refine_limit(void)
{
    const float thr[] = {0.1f, 0.02f, 0.5f, 1.0f, 0.0f, -0.1f, 0.3333f, 1e-6f};
    uint32_t rng = 7u;
    int bad = 0;
    for (size_t i = 0; i < sizeof thr / sizeof thr[0]; i++)
        bad += refine_limit_agrees(thr[i], &rng) != 0;
    printf("refine_limit: %zu thresholds, the limit decides as powf at the boundary and on 100000 "
           "random bounds each\n",
           sizeof thr / sizeof thr[0]);
    return bad != 0;
}
