/* Tests of the cssm_hrc plugin's parts (plugins/cssm_hrc/README.md "Tests"),
 * with its sources compiled in:
 *   traversal   every traversal visits every texel exactly once (Cornell
 *               box charts, the furnace sphere's surface samples); zig-zag
 *               and spiral steps stay between neighbouring texels of a
 *               chart except at a stated few jumps
 *   order       Table 2: the walk order over the same chart texels changes
 *               the segments little, the greedy walk's surface samples
 *               much (order_tests.c)
 *   tree        the skip-pointer traversal equals a recursive depth-first
 *               traversal, for full traversals and for selective ones
 *               with pseudo-random refine decisions; spheres hold their
 *               texels, areas add up
 *   visibility  CSSM visibility against Embree occlusion between random
 *               Cornell-box texel / surface-point pairs, against the
 *               always-visible and never-visible answers
 *   furnace     inside a closed emitting sphere (Le = 1, rho = 0.5) the
 *               atlas holds Le sum_{k<=n} rho^k and a final gather
 *               Le sum_{k<=n+1} rho^k, within 2 %, for n = 1, 2, 3
 *   hull        the core's convex hulls (qhull) and their overlap test
 *               (GJK): overlapping pairs found, separated and near-touching
 *               ones (gap 1e-3) not, against the closed-form answers of
 *               boxes and against the bounding spheres of point clouds
 *   motion      §3.3: the moving Cornell box (the bunny moves), maps made
 *               at t = 0, the bunny moved to t = 1.5 s (D T^-1, nothing
 *               made again): visibility against Embree on the moved scene
 *               for pairs near the bunny, against always / never visible
 *               and the unmoved scene's visibility
 *   compact     the compact nodes of §4.2.1: random round trips within the
 *               stated bounds, conservative spheres and cones on the
 *               Cornell box tree, exact pointers, equal traversals, the
 *               packed pull against the float pull
 *   compact_furnace  the furnace with nodes=compact
 *   compact_limit    65 535 nodes pack, 65 537 are refused
 *   escape      env=cssm (§4.7 with the texels' own maps): on bunny_env
 *               and teapot_plane the escape test of a texel's cube map
 *               against Embree occlusion for random texel / direction
 *               pairs (against always / never escapes), the per-texel
 *               environment irradiance against the traced estimate with the
 *               same directions (against black and unshadowed), and what
 *               the escape intervals cost in compression (Cornell box too)
 * Usage: cssm_tests PART. Exit 0 on success, 1 with a message otherwise.
 * This file holds the driver and the scene loading; the parts are in
 * atlas_tests.c (traversal, texture), tree_tests.c (tree),
 * compact_tests.c (compact, compact_limit), visibility_tests.c,
 * furnace_tests.c (furnace, compact_furnace), motion_tests.c (hull,
 * motion, motion2) and env_tests.c (escape). */
#include "cssm_tests.h"

#include "gpu_fixture.h"

#include <stdio.h>
#include <string.h>

gi_scene *cssm_test_load(const char *rel)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", GI_SOURCE_DIR, rel);
    gi_error err;
    gi_scene *s = gi_scene_load(path, &err);
    if (!s)
        fprintf(stderr, "FAIL: %s\n", err.text);
    return s;
}

int cssm_test_load_gpu(const char *rel, gi_gpu **gpu, gi_scene **s, gi_gpu_scene **gs)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", GI_SOURCE_DIR, rel);
    return gpu_fixture_load(path, gpu, s, gs) && *gs;
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: cssm_tests "
                        "traversal|order|tree|visibility|furnace|hull|motion|motion2|texture|"
                        "compact|compact_furnace|"
                        "compact_limit|escape|representative|refine_limit\n");
        return 2;
    }
    int r;
    if (!strcmp(argv[1], "traversal"))
        r = cssm_test_traversal();
    else if (!strcmp(argv[1], "order"))
        r = cssm_test_order();
    else if (!strcmp(argv[1], "tree"))
        r = cssm_test_tree();
    else if (!strcmp(argv[1], "refine_limit"))
        r = cssm_test_refine_limit();
    else if (!strcmp(argv[1], "visibility"))
        r = cssm_test_visibility();
    else if (!strcmp(argv[1], "furnace"))
        r = cssm_test_furnace(0);
    else if (!strcmp(argv[1], "compact_furnace"))
        r = cssm_test_furnace(1);
    else if (!strcmp(argv[1], "compact"))
        r = cssm_test_compact();
    else if (!strcmp(argv[1], "compact_limit"))
        r = cssm_test_compact_limit();
    else if (!strcmp(argv[1], "hull"))
        r = cssm_test_hull();
    else if (!strcmp(argv[1], "motion"))
        r = cssm_test_motion();
    else if (!strcmp(argv[1], "motion2"))
        r = cssm_test_motion2();
    else if (!strcmp(argv[1], "texture"))
        r = cssm_test_texture();
    else if (!strcmp(argv[1], "escape"))
        r = cssm_test_env();
    else if (!strcmp(argv[1], "representative"))
        r = cssm_test_representative();
    else {
        fprintf(stderr, "cssm_tests: unknown part '%s'\n", argv[1]);
        return 2;
    }
    const int failed = gi_test_failed; /* every file's checks (check.h) */
    if (r || failed) {
        fprintf(stderr, "cssm_tests %s: %d check(s) failed\n", argv[1], failed + r);
        return 1;
    }
    printf("cssm_tests %s: ok\n", argv[1]);
    return 0;
}
