/* The avg plugin's parts against independent computations (the plugin's
 * sources are compiled in; see plugins/avg/README.md "Tests"):
 *
 *   avg_tests voxel   the GPU voxelisation (all three voxelisers) against a
 *                     CPU triangle-box overlap voxelisation of the same
 *                     scene (Cornell box at t = 0, Cornell moving at
 *                     t = 1.3): every overlapped voxel filled, false
 *                     positives and per-voxel triangle counts reported; the
 *                     single-pass voxeliser also against the per-slice
 *                     conservative one: equal counts in every voxel, sums
 *                     within its fixed-point rounding;
 *   avg_tests march   rays marched through the grid on the GPU against
 *                     Embree rays (gi/raytrace.h) in the same scene: the AVG
 *                     hit voxel lies within one voxel of the real hit;
 *   avg_tests vpls    the VPL set of two frames of a static scene is
 *                     identical; it changes when the scene moves and comes
 *                     back when the scene does; the light VPLs of AVG and
 *                     exact tracing agree (same quasi-random numbers);
 *   avg_tests visibility  the light VPLs' shadow maps (core depth atlas,
 *                     paraboloid and perspective; and the maps of the
 *                     shadow_lod=0.1 copy on the Cornell box and Cornell
 *                     moving) against Embree shadow rays through the full
 *                     scene for every receiver pixel (the VPLs at hits lie
 *                     inside voxels, behind their surface, by design, and
 *                     are not comparable with exact rays);
 *   avg_tests shade   interleaved shading with M = 1 equals the plain sum
 *                     over all VPLs computed on the CPU from the G-buffer
 *                     (no visibility), and M = 16 without the filter equals
 *                     M times the sum over each pixel's own subset;
 *   avg_tests deform  the voxel comparison over the poses of a morphing
 *                     scene;
 *   avg_tests punctual  point and spot lights through their VPLs against
 *                     their closed-form light.
 * One file per subject (avg_test_<subject>.c; voxel and deform share
 * avg_test_voxel.c), the fixtures in avg_test_fixture.c (avg_tests.h). */
#include "avg_tests.h"

#include <stdio.h>
#include <string.h>

/* The subjects by their name on the command line. */
static const struct {
    const char *name;
    int (*run)(gi_gpu *gpu);
} subjects[] = {{"voxel", avg_test_voxel},          {"deform", avg_test_deform},
                {"march", avg_test_march},          {"vpls", avg_test_vpls},
                {"shade", avg_test_shade},          {"punctual", avg_test_punctual},
                {"visibility", avg_test_visibility}};

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: avg_tests voxel|deform|march|vpls|shade|visibility|punctual\n");
        return 2;
    }
    gi_error err;
    gi_gpu *gpu = gi_gpu_create(NULL, &err);
    if (!gpu) {
        fprintf(stderr, "no GL: %s\n", err.text);
        return 1;
    }
    if (gi_shader_register(gi_avg_shaders, &err) != GI_OK) {
        fprintf(stderr, "shaders: %s\n", err.text);
        return 1;
    }
    int failed = -1;
    for (size_t i = 0; i < sizeof subjects / sizeof subjects[0]; i++)
        if (!strcmp(argv[1], subjects[i].name))
            failed = subjects[i].run(gpu); /* every file's checks (check.h) */
    if (failed < 0) {
        fprintf(stderr, "unknown test '%s'\n", argv[1]);
        return 2;
    }
    gi_gpu_destroy(gpu);
    if (failed)
        fprintf(stderr, "%d failure(s)\n", failed);
    return failed ? 1 : 0;
}
