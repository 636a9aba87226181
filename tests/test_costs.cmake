# The order ctest starts the tests in (docs/testing.md, "Time budget").
#
# `make test` runs ctest with two jobs on a clean clone, where ctest has no
# timings of earlier runs (Testing/Temporary/CTestCostData.txt) and so starts
# the tests in the order they are declared: the conformance suites, declared
# last and the longest, ran at the end with one job idle beside the last of
# them. A test's COST property is the timing ctest uses until it has its own:
# it starts the costliest first, and the short tests fill the other job.
#
# The costs are seconds, each test's time in one run of the release suite
# with two jobs on the 2-core machine shared with other work (about twice
# an idle machine's). Only their order matters; tests not listed (under
# 14 s) cost 0 and keep their declaration order after the listed ones.
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
    # conformance suites (tests/conformance/CMakeLists.txt, one per plugin)
    conformance.vlf 1198
    conformance.cssm_hrc 484
    conformance.csm 356
    conformance.avg 245
    conformance.held_out 209
    conformance.implicit_vis 116
    # tests/integration/CMakeLists.txt
    integration.view_drag 152
    integration.slurm 143
    integration.faults 125
    integration.compare_study 114
    integration.anim_study 113
    integration.view_every_method 84
    integration.report_browser 80
    integration.study_identity 76
    integration.view_script 70
    integration.tradeoff 69
    integration.cancel 65
    integration.results_tables 55
    integration.view_light_drag 48
    integration.study_files 47
    integration.view_stale 41
    integration.input_limits 37
    integration.cli 31
    integration.held_out_tables 29
    integration.cache_foreign 28
    integration.study_strict 27
    integration.study_stale_reference 26
    integration.cli_help 25
    integration.view_study 24
    integration.batch_env 21
    integration.scale_fit 21
    integration.study_nonfinite 19
    integration.study_interrupt 18
    integration.completion 15
    integration.stress_tables 15
    # plugins/<id>/tests/CMakeLists.txt
    integration.avg_cli 135
    integration.implicit_vis_leak 77
    integration.cssm_escape 63
    integration.vlf_gpu 58
    integration.implicit_vis_gpu 54
    integration.csm_cli 45
    integration.vlf_reference 45
    integration.cssm_env_reference_cssm 42
    integration.cssm_env_reference 34
    integration.implicit_vis_direct 33
    integration.implicit_vis_threads 33
    integration.implicit_vis_glossy 30
    integration.vlf_image_mirror 28
    integration.cssm_motion2 26
    integration.vlf_furnace 25
    integration.implicit_vis_reference 24
    integration.cssm_csm_direct_image_furnace 24
    integration.cssm_csm_direct_image_cornell 24
    integration.vlf_energy 22
    integration.cssm_csm_direct_env 20
    integration.implicit_vis_remesh 16
    integration.avg_vpls 15)

function(gi_test_costs)
    set(table ${GI_TEST_COSTS})
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
