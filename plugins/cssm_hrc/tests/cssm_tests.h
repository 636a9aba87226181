/* What the files of cssm_tests share (cssm_tests.c lists the parts):
 * the scenes, the GL fixture of the visibility, motion and escape parts
 * (fixture.c), the tree traversals of the tree and compact parts
 * (tree_tests.c), and each file's parts. check.h's counters are shared by
 * all the files. */
#ifndef CSSM_TESTS_H
#define CSSM_TESTS_H

#include "cssm.h"
#include "motion.h"

#include "gi/gpu.h"
#include "gi/raytrace.h"
#include "gi/scene.h"

#ifndef GI_SOURCE_DIR
#define GI_SOURCE_DIR "."
#endif

/* The scene at GI_SOURCE_DIR/rel; NULL (the message printed) when it
 * does not load. */
gi_scene *cssm_test_load(const char *rel);
/* The scene at GI_SOURCE_DIR/rel uploaded to a new GL context
 * (gpu_fixture.h); 0 when any step fails (counted as a failed check). */
int cssm_test_load_gpu(const char *rel, gi_gpu **gpu, gi_scene **s, gi_gpu_scene **gs);

/* ------------------------------------------------------------ fixture.c */

/* A scene with the GL context, Embree at t0 (and t1 where it differs:
 * the moved scene), the atlas (32^2) at t0 and its spiral order; the maps
 * `m` are the caller's, and with movers the motion `mo` (motion_open). */
#define MOTION_MAX_MOVERS 2
typedef struct cssm_fixture {
    gi_scene *s;
    gi_gpu *gpu;
    gi_gpu_scene *gs;
    gi_rt *rt0, *rt1;
    cssm_atlas a;
    uint32_t *order;
    cssm_maps m;
    cssm_motion mo;
    gi_vec3 c0[MOTION_MAX_MOVERS], c1[MOTION_MAX_MOVERS]; /* the movers' sphere centres at t0, t1 */
    float radius[MOTION_MAX_MOVERS];
} cssm_fixture;

/* 0 on success; on failure the message is printed and
 * cssm_fixture_close frees what was made. */
int cssm_fixture_open(cssm_fixture *f, const char *rel, float t0, float t1);
void cssm_fixture_close(cssm_fixture *f);
/* A receiver point x on texel i (a random point p of the texel) and the
 * centre of sender j's cube map now: 0 when the two do not face each
 * other (the gathers never ask such pairs). */
int cssm_fixture_pair(const cssm_fixture *f, uint32_t j, uint32_t i, uint32_t *rng, gi_vec3 *p,
                      gi_vec3 *x, gi_vec3 *eye);
/* Whether Embree (rt) finds the segment eye-x free. */
int cssm_fixture_truth(const cssm_fixture *f, const gi_rt *rt, gi_vec3 eye, gi_vec3 x);

/* ------------------------------------------------------- tree_tests.c */

/* The skip-pointer traversal of the float tree, refining where
 * cssm_test_decide says so (everywhere when full); the nodes of the cut
 * into out[*n]. */
void cssm_test_stackless(const cssm_tree *t, uint32_t salt, int full, uint32_t *out, uint32_t *n);
/* A pseudo-random but fixed refine decision per node. */
int cssm_test_decide(uint32_t node, uint32_t salt);

/* ---------------------------------------------------------- the parts */

int cssm_test_traversal(void);      /* atlas_tests.c */
int cssm_test_order(void);          /* order_tests.c */
int cssm_test_texture(void);        /* atlas_tests.c */
int cssm_test_tree(void);           /* tree_tests.c */
int cssm_test_refine_limit(void);   /* tree_tests.c */
int cssm_test_compact(void);        /* compact_tests.c */
int cssm_test_compact_limit(void);  /* compact_tests.c */
int cssm_test_visibility(void);     /* visibility_tests.c */
int cssm_test_furnace(int compact); /* furnace_tests.c */
int cssm_test_representative(void); /* furnace_tests.c */
int cssm_test_hull(void);           /* motion_tests.c */
int cssm_test_motion(void);         /* motion_tests.c */
int cssm_test_motion2(void);        /* motion_tests.c */
int cssm_test_env(void);            /* env_tests.c */

#endif
