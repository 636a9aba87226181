/* The implicit_vis plugin's CPU stages against independent computations
 * (the plugin's CPU files and iv_gpu.c are compiled in;
 * plugins/implicit_vis/README.md "Tests"):
 *
 *   iv_tests bins       direction -> bin -> the bin's centre lies in the bin;
 *                       the bins' solid angles sum to 4 pi;
 *   iv_tests hierarchy  every element in exactly one leaf; each node's area
 *                       the sum of its children's, its position their
 *                       area-weighted mean; the roots' areas sum to the
 *                       scene's surface area; leaves follow rigid motion
 *                       and morph targets (cornell_moving, cornell_deform);
 *   iv_tests links      every stored link lies in the bin of its direction;
 *                       brute force keeps in each bin exactly the nearest of
 *                       all elements in that bin (checked against a plain
 *                       scan); after refinement no leaf keeps a link longer
 *                       than one on its path to the root in the same bin;
 *   iv_tests furnace    closed emitting sphere (tests/data/conformance):
 *                       Le sum_{k <= n + 1} rho^k within 2 % for n = 0..3;
 *   iv_tests direct     Cornell box, direct light per element against Embree
 *                       (shadow rays to the area light): the method's error
 *                       must be at most half of the better trivial answer's
 *                       (black, or unshadowed); discs Embree sees fully
 *                       hidden from the light mostly get no light link;
 *   iv_tests brute      hierarchical and brute-force links give irradiance
 *                       within a stated tolerance on a small scene;
 *   iv_tests leak       Fig. 10(d): the share of the environment light the
 *                       792-vertex teapot blocks from the ground (Embree)
 *                       that the method lets through, with and without
 *                       splatting, the model as it is and re-meshed;
 *   iv_tests gpu        the GPU gather and pull-up (iv_gpu.c, Sec. 4.3.1)
 *                       against iv_illuminate on the same links: Cornell
 *                       box, furnace, environment, punctual lights, the
 *                       coverage modes; and the furnace through the GPU;
 *   iv_tests remesh     isotropic re-meshing (gi/algo/remesh.h, CGAL): every new
 *                       vertex on its embedding, triangle count and edge-
 *                       length spread before and after, the hierarchy and
 *                       the display grid of the re-meshed Cornell boxes;
 *   iv_tests threads    the links built on 2-4 threads are those built on
 *                       one, to the bit; create_links on 1 and 2 threads
 *                       timed side by side.
 *
 * This file holds main() and what several parts use (iv_tests.h); the
 * parts are in iv_tests_structure.c (bins, hierarchy, links),
 * iv_tests_light.c (furnace, direct, brute, leak), iv_tests_remesh.c,
 * iv_tests_threads.c and iv_tests_gpu.c. */
#include "iv_tests.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

gi_scene *iv_test_load(const char *path)
{
    gi_error err;
    gi_scene *s = gi_scene_load(path, &err);
    EXPECT(s != NULL, "cannot load %s: %s", path, err.text);
    return s;
}

/* Link modes of the next iv_test_frame_run / furnace_means (the plugin's defaults:
 * one bin per link, Eq. 5 covering); the environment (IV_BILINEAR 0 or 1,
 * IV_COVERAGE a share) overrides them, for exploring. */
int iv_test_bilinear = 0;
float iv_test_coverage = 0.0f;
int iv_test_weight = IV_WEIGHT_EQ5;
void iv_test_modes(iv_links *l)
{
    const char *b = getenv("IV_BILINEAR"), *c = getenv("IV_COVERAGE"), *w = getenv("IV_WEIGHT");
    l->bilinear = b ? atoi(b) : iv_test_bilinear;
    l->coverage = c ? (float)atof(c) : iv_test_coverage;
    l->weight = w ? atoi(w) : iv_test_weight;
}

/* How iv_test_frame_run re-meshes (IV_REMESH_*). */
int iv_test_remesher = IV_REMESH_GRID;

int iv_test_frame_run(iv_test_frame *f, const char *path, float edge, uint32_t N, uint32_t bounces,
                      int brute, int splat)
{
    memset(f, 0, sizeof *f);
    f->s = iv_test_load(path);
    if (!f->s)
        return 0;
    gi_error err;
    f->h = iv_hier_create(f->s, edge, iv_test_remesher, &err);
    EXPECT(f->h != NULL, "%s", err.text);
    if (!f->h)
        return 0;
    iv_hier_update(f->h, f->s, 0.0f);
    f->l = iv_links_create(f->h, N);
    iv_test_modes(f->l);
    f->E = malloc((size_t)f->h->elem_count * 6 * sizeof(float));
    iv_links_build(f->l, f->h, 1.0f, brute, splat);
    iv_links_refine_push(f->l, f->h);
    iv_lights li = {f->s, 0.0f, f->s->envmap, NULL};
    iv_illuminate(f->l, f->h, &li, bounces, f->E);
    return 1;
}

void iv_test_frame_free(iv_test_frame *f)
{
    free(f->E);
    iv_links_free(f->l);
    iv_hier_free(f->h);
    gi_scene_free(f->s);
}

int main(int argc, char **argv)
{
    const char *part = argc > 1 ? argv[1] : "all";
    int all = !strcmp(part, "all"), known = 0;
    if (all || !strcmp(part, "bins"))
        iv_test_bins(), known = 1;
    if (all || !strcmp(part, "hierarchy"))
        iv_test_hierarchy(), known = 1;
    if (all || !strcmp(part, "links"))
        iv_test_links(), known = 1;
    if (all || !strcmp(part, "furnace"))
        iv_test_furnace(), known = 1;
    if (all || !strcmp(part, "direct"))
        iv_test_direct(), known = 1;
    if (all || !strcmp(part, "leak"))
        iv_test_leak(), known = 1;
    if (all || !strcmp(part, "brute"))
        iv_test_brute(), known = 1;
    if (all || !strcmp(part, "threads"))
        iv_test_threads(), known = 1;
    if (all || !strcmp(part, "remesh"))
        iv_test_remesh(), known = 1;
    if (all || !strcmp(part, "gpu"))
        iv_test_gpu(), known = 1;
    if (all || !strcmp(part, "layout"))
        iv_test_layout(), known = 1;
    if (!known) {
        fprintf(stderr, "iv_tests: unknown part '%s'\n", part);
        return 2;
    }
    int failed = gi_test_failed; /* every file's checks (check.h) */
    if (failed)
        fprintf(stderr, "%d failure(s)\n", failed);
    return failed ? 1 : 0;
}
