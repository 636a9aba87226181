/* The implicit_vis test of the link table's layout (issue 29; README
 * "One link stored once"): the links the plugin makes now are those it
 * made before the table was laid out for the writes, to the bit. Every
 * case hashes what the illumination reads of the links (iv_links_pack:
 * per receiving and light link its bin, its other end, its share of the
 * bin and its length; the offsets; the build's counters) and compares the
 * hash with the one the old layout gave (main at fc8a191), so a change of
 * which link a bin keeps, of a tie, of a coverage sum or of a length fails. */
#include "iv_tests.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static uint64_t fnv(uint64_t x, const void *p, size_t n)
{
    const unsigned char *c = p;
    for (size_t i = 0; i < n; i++)
        x = (x ^ c[i]) * 1099511628211ull;
    return x;
}

typedef struct layout_case {
    const char *scene;
    uint32_t N;
    float t;
    int weight, bilinear, splat, brute;
    float coverage;
    uint32_t threads;
    uint64_t hash; /* what the old layout gave */
} layout_case;

static uint64_t links_hash(const iv_links *l, const iv_hier *h)
{
    size_t n = (size_t)l->leaf_off[h->elem_count] + l->light_off[h->elem_count];
    uint32_t *w = malloc(4 * (n ? n : 1) * sizeof *w);
    uint32_t *off = malloc(((size_t)h->elem_count + 1) * 2 * sizeof *off);
    EXPECT(w && off, "out of memory for %zu links", n);
    uint64_t x = 14695981039346656037ull;
    if (w && off) {
        iv_links_pack(l, h, w, off);
        x = fnv(x, w, 4 * n * sizeof *w);
        x = fnv(x, off, ((size_t)h->elem_count + 1) * 2 * sizeof *off);
        uint64_t c[3] = {l->tries, l->created, l->receiving};
        x = fnv(x, c, sizeof c);
    }
    free(w), free(off);
    return x;
}

static void layout_case_run(const layout_case *c)
{
    gi_scene *s = iv_test_load(c->scene);
    if (!s)
        return;
    gi_error err;
    iv_hier *h = iv_hier_create(s, 0.0f, IV_REMESH_GRID, &err);
    EXPECT(h != NULL, "%s: %s", c->scene, err.text);
    iv_links *l = h ? iv_links_create(h, c->N) : NULL;
    EXPECT(!h || l, "%s: out of memory for the links", c->scene);
    if (l) {
        iv_hier_update(h, s, c->t);
        l->weight = c->weight;
        l->bilinear = c->bilinear;
        l->coverage = c->coverage;
        l->threads = c->threads;
        iv_links_build(l, h, 1.0f, c->brute, c->splat);
        iv_links_refine_push(l, h);
        uint64_t got = links_hash(l, h);
        printf("%s N %u t %.2f weight %d bilinear %d splat %d brute %d coverage %.2g threads %u: "
               "%llu links, hash 0x%016llx (old layout 0x%016llx)\n",
               strrchr(c->scene, '/') + 1, c->N, (double)c->t, c->weight, c->bilinear, c->splat,
               c->brute, (double)c->coverage, c->threads, (unsigned long long)l->receiving,
               (unsigned long long)got, (unsigned long long)c->hash);
        EXPECT(got == c->hash, "%s: the links differ from the old layout's", c->scene);
    }
    iv_links_free(l);
    iv_hier_free(h);
    gi_scene_free(s);
}

/* keep_pairs (README "Pairs of still segments"): builds at t0, then at t1
 * (a segment moved: the still pairs' lists are taken, the others tested
 * anew), then at t1 again (nothing moved: every list taken), each giving
 * the links of a build from scratch at that time, to the bit. */
static uint64_t kept_build(iv_links *l, iv_hier *h, const gi_scene *s, float t)
{
    iv_hier_update(h, s, t);
    iv_links_build(l, h, 1.0f, 0, 0);
    iv_links_refine_push(l, h);
    return links_hash(l, h);
}

static void kept_case(const char *path, uint32_t threads)
{
    gi_scene *s = iv_test_load(path);
    if (!s)
        return;
    gi_error err;
    iv_hier *h = iv_hier_create(s, 0.0f, IV_REMESH_GRID, &err);
    EXPECT(h != NULL, "%s: %s", path, err.text);
    iv_links *k = h ? iv_links_create(h, 4) : NULL, *f = h ? iv_links_create(h, 4) : NULL;
    EXPECT(!h || (k && f), "%s: out of memory for the links", path);
    if (k && f) {
        k->keep_pairs = 1;
        k->threads = f->threads = threads;
        uint64_t fresh1 = kept_build(f, h, s, 0.5f);
        EXPECT(f->kept_tries == 0, "keep_pairs off: %llu pair tests kept",
               (unsigned long long)f->kept_tries);
        uint64_t got0 = kept_build(k, h, s, 0.0f);
        EXPECT(got0 != fresh1 && k->kept_tries == 0,
               "first build: the same links at t 0 and 0.5, or %llu tests kept",
               (unsigned long long)k->kept_tries);
        uint64_t got1 = kept_build(k, h, s, 0.5f);
        printf("keep_pairs, %u thread(s): t 0.5 after 0: %llu of %llu pair tests kept, hash "
               "0x%016llx (from scratch 0x%016llx)\n",
               threads, (unsigned long long)k->kept_tries, (unsigned long long)k->tries,
               (unsigned long long)got1, (unsigned long long)fresh1);
        EXPECT(got1 == fresh1, "a segment moved: the links differ from a build from scratch");
        EXPECT(k->kept_tries > 0 && k->kept_tries < k->tries,
               "a segment moved: %llu of %llu tests kept (some, not all)",
               (unsigned long long)k->kept_tries, (unsigned long long)k->tries);
        uint64_t got2 = kept_build(k, h, s, 0.5f);
        EXPECT(got2 == fresh1 && k->kept_tries == k->tries,
               "nothing moved: hash %016llx, %llu of %llu tests kept", (unsigned long long)got2,
               (unsigned long long)k->kept_tries, (unsigned long long)k->tries);
    }
    iv_links_free(k), iv_links_free(f);
    iv_hier_free(h);
    gi_scene_free(s);
}

void iv_test_layout(void)
{
    static const char *box = GI_SOURCE_DIR "/scenes/cornell_box_coarse.gltf",
                      *deform = GI_SOURCE_DIR "/scenes/cornell_deform.gltf";
    const layout_case cases[] = {
        /* the defaults (Eq. 5, one bin per link) on a deformed frame, one thread and two */
        {deform, 8, 1.5f, IV_WEIGHT_EQ5, 0, 0, 0, 0.0f, 1, 0xccf93f1e3056c1a9ull},
        {deform, 8, 1.5f, IV_WEIGHT_EQ5, 0, 0, 0, 0.0f, 2, 0xccf93f1e3056c1a9ull},
        /* Eq. 4 over the nearest surface (coverage sums), splatting */
        {box, 8, 0.0f, IV_WEIGHT_SURFACE, 0, 1, 0, 0.0f, 2, 0x6481f136591a8edaull},
        /* bilinear links, coverage share */
        {deform, 6, 0.5f, IV_WEIGHT_EQ5, 1, 0, 0, 0.7f, 1, 0x2792617b57d833ffull},
        /* brute force */
        {box, 6, 0.0f, IV_WEIGHT_BIN, 0, 0, 1, 0.0f, 1, 0x6e1ea6bc3ed6c9c7ull},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++)
        layout_case_run(&cases[i]);
    kept_case(GI_SOURCE_DIR "/scenes/cornell_moving.gltf", 2);
}
