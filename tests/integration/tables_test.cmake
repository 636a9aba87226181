# The results' tables regenerate from what is committed: each tables script
# runs on its committed study folder (runs.csv, frames.csv and the small
# files beside them; no EXR images, which are not committed) and must print
# exactly the committed tables.md.
# Run by ctest as: cmake -DPYTHON=... -DGIB=... -DROOT=... -DOUT=... -P tables_test.cmake

cmake_policy(SET CMP0007 NEW) # list(GET) keeps the empty "extra arguments" field
set(failures 0)
# study folder, script, extra arguments
set(cases "avg|plugins/avg/tables.py|${GIB}" "csm|plugins/csm/tables.py|" "csm_local|plugins/csm/tables.py|"
          "vlf|plugins/vlf/tables.py|" "stress|harness/studies/stress_tables.py|"
          "compare_all|harness/studies/compare_all_tables.py|")
foreach(c ${cases})
    string(REPLACE "|" ";" parts "${c}")
    list(GET parts 0 study)
    list(GET parts 1 script)
    list(LENGTH parts n)
    set(extra "")
    if(n GREATER 2)
        list(GET parts 2 extra)
    endif()
    set(got ${OUT}/tables_${study}.md)
    execute_process(COMMAND ${PYTHON} ${ROOT}/${script} ${ROOT}/results/${study} ${extra}
        WORKING_DIRECTORY ${ROOT} RESULT_VARIABLE rc OUTPUT_FILE ${got} ERROR_VARIABLE err)
    if(NOT rc EQUAL 0)
        message(SEND_ERROR "${script} results/${study}: exit ${rc}\n${err}")
        math(EXPR failures "${failures} + 1")
        continue()
    endif()
    execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files ${got} ${ROOT}/results/${study}/tables.md
        RESULT_VARIABLE same)
    if(NOT same EQUAL 0)
        execute_process(COMMAND diff -u ${ROOT}/results/${study}/tables.md ${got} OUTPUT_VARIABLE d)
        message(SEND_ERROR "${script} results/${study} differs from results/${study}/tables.md:\n${d}")
        math(EXPR failures "${failures} + 1")
    else()
        message(STATUS "results/${study}/tables.md: regenerated identically by ${script}")
    endif()
endforeach()
if(failures GREATER 0)
    message(FATAL_ERROR "${failures} table(s) do not regenerate")
endif()
