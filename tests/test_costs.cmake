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
# two jobs, the 2-core machine shared with other work; 2026-11-28, main at
# cce0819): the release suite's in GI_TEST_COSTS, the asan preset's (label
# unit, several times slower under the sanitizers, and in another order)
# in GI_TEST_COSTS_ASAN. Only their order matters; tests not listed (under
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
    conformance.vlf 285
    conformance.cssm_hrc 159
    conformance.csm 136
    conformance.held_out 86
    conformance.avg 83
    integration.slurm 71
    integration.avg_cli 55
    unit.fuzz_scene_brief 46
    integration.cssm_escape 36
    integration.view_drag 32
    integration.vlf_views 32
    python.api 30
    integration.gpu_bundle 28
    integration.vlf_reference 28
    integration.vlf_gpu 26
    integration.compare_study 21
    integration.csm_cli 19
    integration.study_interrupt 18
    integration.implicit_vis_leak 17
    conformance.suite 17
    integration.report_browser 17
    integration.view_every_method 17
    integration.implicit_vis_glossy 16
    integration.cssm_motion2 15
    integration.cancel 15
    integration.diff 15
    conformance.implicit_vis 15
    integration.vlf_furnace 15
    integration.vlf_energy 13
    integration.faults 12
    integration.cli 11
    integration.implicit_vis_truth_box 11
    integration.anim_study 11
    integration.cssm_vis_trace 10
    integration.cssm_gpu_gather_cornell_box 9
    integration.tradeoff 9
    unit.fuzz_study_brief 9
    integration.debug_buffers 9
    integration.vlf_image_mirror 9
    integration.implicit_vis_gpu 8)
# The asan preset's suite (the label unit), timed the same way under ASan.
set(GI_TEST_COSTS_ASAN
    integration.csm_local 74
    integration.vlf_gpu 65
    integration.view_drag 64
    integration.cssm_escape 58
    integration.implicit_vis_gpu 46
    integration.implicit_vis_remesh 26
    integration.cssm_motion2 25
    integration.vlf_energy 24
    integration.implicit_vis_direct 23
    integration.vlf_furnace 23
    integration.avg_deform 21
    integration.study_strict 18
    integration.cssm_csm_direct_env 18
    integration.implicit_vis_threads 16
    integration.study_identity 15
    integration.cssm_texture 14
    integration.avg_vpls 13
    integration.cssm_csm_direct_all 12
    integration.input_limits 12
    unit.fuzz_study_brief 12
    unit.test_passes 11
    unit.fuzz_scene_brief 10
    integration.cssm_motion 10
    integration.implicit_vis_furnace 10
    unit.test_csm_codec 10
    integration.avg_visibility 10
    integration.cssm_order 10
    integration.csm_visibility 9
    integration.view_stale 9
    integration.view_light_drag 9
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
