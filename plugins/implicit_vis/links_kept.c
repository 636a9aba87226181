/* The implicit_vis method's pairs kept between two still segments
 * (keep_pairs; README "Pairs of still segments"). Algorithm 1 (line 5)
 * creates the hierarchical links anew every frame; which node pairs
 * Sec. 4.2.2 links, starting from two top-level nodes, depends only on the
 * positions, normals and areas of the nodes of those two trees
 * (iv_pair_decide). Where neither tree changed since the last build, the
 * recursion would list the same pairs in the same order: they are taken
 * from it. Every pair is still written into the bins (a moving segment
 * between two still ones takes their bins), so the links are the same to
 * the bit. */
#include "iv_internal.h"

#include <stdlib.h>
#include <string.h>

void iv_kept_free(iv_kept *k)
{
    if (!k)
        return;
    size_t tasks = k->roots + (size_t)k->roots * (k->roots - 1) / 2;
    for (size_t i = 0; k->list && i < tasks; i++)
        free(k->list[i].pairs);
    free(k->list), free(k->geom), free(k->still);
    free(k);
}

static iv_kept *kept_create(const iv_hier *h)
{
    iv_kept *k = calloc(1, sizeof *k);
    if (!k)
        return NULL;
    k->roots = h->root_count;
    size_t tasks = k->roots + (size_t)k->roots * (k->roots - 1) / 2;
    k->geom = calloc((size_t)h->node_count * 7 + 1, sizeof *k->geom);
    k->still = calloc(k->roots + 1, 1);
    k->list = calloc(tasks + 1, sizeof *k->list);
    if (!k->geom || !k->still || !k->list) {
        iv_kept_free(k);
        return NULL;
    }
    return k;
}

static void node_geom(const iv_hier *h, uint32_t i, float g[7])
{
    memcpy(g, &h->pos[3 * (size_t)i], 3 * sizeof(float));
    memcpy(g + 3, &h->nrm[3 * (size_t)i], 3 * sizeof(float));
    g[6] = h->area[i];
}

iv_kept *iv_kept_begin(iv_links *l, const iv_hier *h)
{
    if (!l->kept)
        l->kept = kept_create(h);
    iv_kept *k = l->kept;
    if (!k)
        return NULL;
    memset(k->still, k->valid ? 1 : 0, k->roots);
    for (uint32_t i = 0; i < h->node_count; i++) {
        float g[7];
        node_geom(h, i, g);
        float *old = &k->geom[7 * (size_t)i];
        /* compared to the bit: a still segment's nodes are recomputed from
         * the same transform into the same floats */
        if (memcmp(g, old, sizeof g) != 0) {
            k->still[l->root[i]] = 0;
            memcpy(old, g, sizeof g);
        }
    }
    k->valid = 0; /* until this build has listed every task's pairs */
    return k;
}

int iv_kept_usable(const iv_kept *k, uint32_t A, uint32_t B)
{
    return k->still[A] && (B == UINT32_MAX || k->still[B]);
}

int iv_kept_append(iv_kept *k, uint32_t t, const uint32_t *pairs, size_t n)
{
    iv_pair_list *p = &k->list[t];
    if (n == 0)
        return 1; /* a task that linked nothing: no list to grow (p->pairs may be NULL) */
    if (p->n + n > p->cap) {
        size_t c = p->cap ? p->cap : 256;
        while (c < p->n + n)
            c *= 2;
        uint32_t *q = realloc(p->pairs, c * 4 * sizeof *q);
        if (!q)
            return 0;
        p->pairs = q;
        p->cap = c;
    }
    memcpy(&p->pairs[4 * p->n], pairs, n * 4 * sizeof *pairs);
    p->n += n;
    return 1;
}
