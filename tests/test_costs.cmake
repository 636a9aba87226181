# The order ctest starts the tests in (docs/testing.md, "Time budget").
#
# `make test` runs ctest with two jobs on a clean clone, where ctest has no
# timings of earlier runs (Testing/Temporary/CTestCostData.txt) and so starts
# the tests in the order they are declared: the conformance suites, declared
# last and the longest, ran at the end with one job idle beside the last of
# them. A test's COST property is the timing ctest uses until it has its own:
# it starts the costliest first, and the short tests fill the other job.
#
# The costs are seconds, each test's time in one CI run (a clean clone,
# two jobs, LP_NUM_THREADS=0, the 2-core machine; 2026-11-29): the release
# suite's in GI_TEST_COSTS, the asan preset's (label unit, -O1, several
# times slower under the sanitizers, and in another order) in
# GI_TEST_COSTS_ASAN. Only their order matters; tests not listed (under
# 8 s) cost 0 and keep their declaration order after the listed ones.
# A new slow test belongs here; a name that no longer exists does nothing.
# RUN_SERIAL tests (integration.vlf_views) need no cost: ctest starts one
# only when nothing else runs, which after the fixtures' set-up tests (run
# first) is the end of the run, whatever their cost.
#
# gi_test_costs() sets COST on the tests of the table that the calling
# directory declared (a test's properties can only be set in the directory
# that added it), so every CMakeLists.txt that registers tests calls it at
# its end.
set(GI_TEST_COSTS
    conformance.vlf 533
    conformance.cssm_hrc 309
    conformance.csm 270
    conformance.held_out 137
    integration.cssm_escape 130
    integration.view_drag 74
    integration.slurm 73
    conformance.avg 71
    integration.avg_cli 67
    integration.vlf_gpu 63
    integration.vlf_reference 55
    integration.cssm_motion2 46
    python.api 41
    integration.diff 37
    integration.cssm_csm_direct_env 35
    integration.view_every_method 35
    integration.implicit_vis_leak 31
    integration.vlf_energy 31
    integration.vlf_furnace 30
    integration.report_browser 27
    integration.study_interrupt 26
    integration.gpu_bundle 25
    conformance.implicit_vis 25
    integration.cssm_motion 23
    integration.compare_study 22
    conformance.suite 22
    integration.cssm_gpu_bounce_cornell_box 21
    integration.cssm_gpu_texels_cornell_glossy 20
    integration.cssm_vis_trace 20
    integration.csm_local 20
    integration.implicit_vis_glossy 19
    integration.cssm_gpu_frame_box_light 19
    integration.cssm_gpu_gather_cornell_box 18
    integration.csm_cli 18
    integration.anim_study 17
    integration.vlf_raster 17
    integration.implicit_vis_truth_box 16
    integration.implicit_vis_gpu 16
    integration.avg_vpls 16
    integration.cssm_visibility 14)
# The asan preset's suite (the label unit), timed the same way under ASan.
set(GI_TEST_COSTS_ASAN
    integration.cssm_escape 228
    integration.view_drag 138
    integration.cssm_motion2 109
    integration.implicit_vis_remesh 107
    integration.vlf_gpu 99
    integration.cssm_csm_direct_env 69
    integration.vlf_furnace 59
    integration.vlf_energy 57
    integration.csm_local 54
    integration.cssm_texture 51
    integration.cssm_motion 46
    integration.implicit_vis_gpu 46
    unit.test_passes 36
    integration.cssm_csm_direct_all 33
    unit.test_csm_codec 30
    integration.avg_deform 26
    integration.avg_vpls 26
    integration.cssm_visibility 26
    integration.implicit_vis_direct 24
    integration.implicit_vis_threads 21
    unit.test_raytrace 21
    integration.cssm_compact_furnace 17
    integration.cssm_order 15
    integration.view_stale 15
    integration.cssm_furnace 14
    unit.fuzz_study_brief 14
    integration.implicit_vis_furnace 14
    integration.csm_visibility 14
    integration.cssm_csm_direct_cornell 13
    integration.study_identity 13
    unit.fuzz_scene_brief 11
    integration.view_light_drag 11
    integration.vlf_precision 10
    integration.avg_visibility 10
    integration.study_strict 9
    integration.avg_voxel 9)

function(gi_test_costs)
    set(table ${GI_TEST_COSTS})
    if(GIBENCH_SANITIZE)
        set(table ${GI_TEST_COSTS_ASAN})
    endif()
    list(LENGTH table n)
    math(EXPR last "${n} - 1")
    foreach(i RANGE 0 ${last} 2)
        math(EXPR j "${i} + 1")
        list(GET table ${i} name)
        list(GET table ${j} cost)
        if(TEST ${name})
            set_tests_properties(${name} PROPERTIES COST ${cost})
        endif()
    endforeach()
endfunction()
