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
# two jobs, LP_NUM_THREADS=0, the 2-core machine; the run at 2b32bd4 on
# 2026-11-29, docs/testing.md "Time budget"): the release
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
    conformance.vlf 383
    conformance.cssm_hrc 303
    conformance.csm 222
    conformance.held_out 118
    integration.view_drag 68
    integration.slurm 65
    conformance.avg 55
    integration.avg_cli 54
    unit.fuzz_scene_brief 39
    integration.diff 36
    integration.vlf_reference 33
    python.api 32
    integration.implicit_vis_leak 29
    integration.vlf_views 28
    integration.view_every_method 27
    integration.study_interrupt 25
    integration.gpu_bundle 24
    integration.compare_study 18
    conformance.implicit_vis 18
    conformance.suite 18
    integration.report_browser 17
    integration.cssm_vis_trace 16
    integration.cssm_gpu_bounce_cornell_box 16
    integration.csm_cli 16
    integration.cssm_gpu_gather_cornell_box 16
    integration.implicit_vis_glossy 15
    integration.vlf_raster 15
    integration.cssm_gpu_texels_cornell_glossy 14
    integration.faults 14
    integration.implicit_vis_truth_box 14
    integration.cssm_gpu_frame_box_light 14
    integration.anim_study 12
    integration.cancel 12
    unit.fuzz_study_brief 9
    unit.test_csm_codec 9
    integration.vlf_image_mirror 9
    integration.tradeoff 9
    unit.test_reference_cornell 9
    integration.debug_buffers 8)
# The asan preset's suite (the label unit), timed the same way under ASan.
set(GI_TEST_COSTS_ASAN
    integration.cssm_escape 131
    integration.cssm_motion2 61
    integration.csm_local 48
    integration.cssm_csm_direct_env 47
    integration.implicit_vis_gpu 35
    integration.cssm_texture 34
    integration.cssm_motion 29
    unit.test_raytrace 22
    unit.test_csm_codec 22
    integration.vlf_gpu 21
    unit.test_passes 19
    integration.implicit_vis_direct 19
    integration.cssm_visibility 19
    integration.avg_vpls 18
    integration.avg_deform 18
    integration.cssm_csm_direct_all 17
    unit.fuzz_study_brief 15
    integration.implicit_vis_threads 13
    integration.implicit_vis_remesh 13
    integration.vlf_energy 11
    unit.fuzz_scene_brief 11
    integration.study_identity 11
    integration.implicit_vis_furnace 11
    integration.csm_visibility 9
    integration.view_stale 9
    integration.vlf_furnace 9
    integration.cssm_csm_direct_cornell 9
    integration.view_light_drag 8)

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
