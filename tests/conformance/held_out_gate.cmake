# The held-out gate of CI (docs/conformance.md "The held-out family"): every
# method on the fixed CI seeds' variants at 32^2, both furnace orientations,
# beats black and `direct` by 2x; the knob sweeps are too slow for CI (run
# them by hand: `gibench conformance --held-out 1 --variants ceiling`).
# Each run prints its table; the test fails when any check fails.
set(failures 0)
set(ENV{GIBENCH_PLUGIN_PATH} "")
string(REPLACE "@" ";" runs "${RUNS}") # runs: SEED/VARIANTS[/OPTION], @ between them
foreach(run ${runs})
    string(REPLACE "/" ";" parts "${run}") # seed/variants/extra
    list(GET parts 0 seed)
    list(GET parts 1 variants)
    list(LENGTH parts n)
    set(extra)
    if(n GREATER 2)
        list(GET parts 2 extra)
    endif()
    execute_process(COMMAND ${GIB} -q conformance --held-out ${seed} --variants ${variants} --size 32 ${extra}
                    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
    message("== seed ${seed}, variants ${variants} ${extra}: exit ${rc}\n${out}${err}")
    if(NOT rc EQUAL 0)
        math(EXPR failures "${failures} + 1")
    endif()
endforeach()
if(failures GREATER 0)
    message(FATAL_ERROR "${failures} held-out run(s) failed (see the tables above)")
endif()
