# The results' tables regenerate from what is committed: each tables script
# runs on its committed study folder (runs.csv, frames.csv and the small
# files beside them; no EXR images, which are not committed) and must print
# exactly the committed tables.md.
# Run by ctest as: cmake -DPYTHON=... -DGIB=... -DROOT=... -DOUT=... -P tables_test.cmake

cmake_policy(SET CMP0007 NEW) # list(GET) keeps the empty "extra arguments" field
set(failures 0)
# study folder, script, extra arguments
set(cases "avg|plugins/avg/tables.py|${GIB}" "csm|plugins/csm/tables.py|" "csm_local|plugins/csm/tables.py|"
          "vlf|plugins/vlf/tables.py|" "cssm_hrc|plugins/cssm_hrc/tables.py|"
          "implicit_vis|plugins/implicit_vis/tables.py|" "avg/speed|plugins/avg/speed_table.py|"
          "stress|harness/studies/stress_tables.py|")
# The five-way comparison at 64x64 sets the other sizes' studies beside it
# where they are committed, as scripts/regenerate_results.sh does, and draws
# the speed-up against size (compared with the committed chart below).
set(sizes "")
foreach(z 128 256)
    if(EXISTS ${ROOT}/results/compare_all_${z}/runs.csv)
        string(APPEND sizes " --size-dir results/compare_all_${z}")
    endif()
endforeach()
if(sizes)
    string(APPEND sizes " --chart ${OUT}/speedup_vs_size.svg")
endif()
list(APPEND cases "compare_all|harness/studies/compare_all_tables.py|${sizes}")
foreach(z 128 256)
    if(EXISTS ${ROOT}/results/compare_all_${z}/runs.csv)
        list(APPEND cases "compare_all_${z}|harness/studies/compare_all_tables.py|")
    endif()
endforeach()
foreach(c ${cases})
    string(REPLACE "|" ";" parts "${c}")
    list(GET parts 0 study)
    list(GET parts 1 script)
    list(LENGTH parts n)
    set(extra "")
    if(n GREATER 2)
        list(GET parts 2 extra)
    endif()
    string(REPLACE "/" "_" name "${study}")
    set(got ${OUT}/tables_${name}.md)
    separate_arguments(extra UNIX_COMMAND "${extra}")
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

if(sizes)
    execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files ${OUT}/speedup_vs_size.svg
                            ${ROOT}/results/compare_all/speedup_vs_size.svg RESULT_VARIABLE same)
    if(NOT same EQUAL 0)
        message(SEND_ERROR "results/compare_all/speedup_vs_size.svg differs from the one "
                           "compare_all_tables.py draws from the committed studies")
        math(EXPR failures "${failures} + 1")
    endif()
endif()

# Issue 34: every measured number in a results README must be one the
# tables script prints (scripts/readme_numbers.py states the rule).
# Every results folder with a study (results/gpu/ has none).
set(checked avg csm csm_local compare_all stress cssm_hrc vlf implicit_vis)
foreach(z 128 256)
    if(EXISTS ${ROOT}/results/compare_all_${z}/runs.csv)
        list(APPEND checked compare_all_${z})
    endif()
endforeach()
set(folders "")
foreach(study ${checked})
    list(APPEND folders ${ROOT}/results/${study})
endforeach()
# and results/README.md itself, against every study's tables.md and the
# generated startup.md and reference_speed.md
list(APPEND folders ${ROOT}/results)
execute_process(COMMAND ${PYTHON} ${ROOT}/scripts/readme_numbers.py ${folders}
    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message(STATUS "${out}")
if(NOT rc EQUAL 0)
    message(SEND_ERROR "results READMEs quote numbers no script prints (exit ${rc}):\n${out}${err}")
    math(EXPR failures "${failures} + 1")
endif()
# The checker must catch a changed number: a copy of a README with one
# value altered has to fail, or this test fails. Cases: folder|text|changed
# text|the number the checker must name (a table cell, a stale prose value
# issue 34 found, a prose number).
# The stress case quotes the previous run's value (changes.md's "before"
# column) outside a "What changed" section.
set(mutations "csm_local|145.6 : 1|147.6 : 1|147.6" "implicit_vis|relMSE 0.378, image mean|relMSE 0.387, image mean|0.387"
              "stress|direct 5.41 to 20.1 ms|direct 1.71 to 20.1 ms|: 1.71 is not"
              "avg|(+2860.0 % against|(+2870.0 % against|2870.0 %"
              ".|0.97 → 1.29 → 1.8, avg|0.97 → 1.2917 → 1.8, avg|1.2917")
foreach(m ${mutations})
    string(REPLACE "|" ";" parts "${m}")
    list(GET parts 0 study)
    list(GET parts 1 from)
    list(GET parts 2 to)
    list(GET parts 3 want)
    file(READ ${ROOT}/results/${study}/README.md text)
    string(FIND "${text}" "${from}" at)
    if(at LESS 0)
        message(SEND_ERROR "results/${study}/README.md no longer holds ${from}; update the mutation check")
        math(EXPR failures "${failures} + 1")
        continue()
    endif()
    string(REPLACE "${from}" "${to}" text "${text}")
    string(REPLACE "." "top" tag "${study}")
    file(WRITE ${OUT}/README_mutated_${tag}.md "${text}")
    execute_process(COMMAND ${PYTHON} ${ROOT}/scripts/readme_numbers.py
                            ${ROOT}/results/${study}:${OUT}/README_mutated_${tag}.md
        RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
    string(FIND "${out}" "${want}" hit)
    if(NOT rc EQUAL 1 OR hit LESS 0)
        message(SEND_ERROR "readme_numbers.py did not flag ${to} in results/${study} (exit ${rc}):\n${out}${err}")
        math(EXPR failures "${failures} + 1")
    else()
        message(STATUS "results/${study}: a README with ${to} fails the check, as it must")
    endif()
endforeach()
if(failures GREATER 0)
    message(FATAL_ERROR "${failures} check(s) failed")
endif()
