# Issue 32, item 2: `study --fresh` interrupted during a run that is not
# compared ("compare": false) must not record the previous run's files as a
# new "ok" (before the fix the interrupted render counted as finished and
# its stale timings.json was taken); the resumed study redoes the run.
# cmake -DGIB=... -DROOT=... -DOUT=... -P study_fresh_interrupt.cmake
set(failures 0)
include(${CMAKE_CURRENT_LIST_DIR}/expect.cmake)
set(D ${OUT}/study_fresh_interrupt)
file(REMOVE_RECURSE ${D})
file(MAKE_DIRECTORY ${D})
# enough frames that the render is still going when the signal comes
file(WRITE ${D}/s.json "{\"name\": \"fresh\", \"scenes\": [\"scenes/cornell_box_coarse.gltf\"],
  \"size\": [16, 16], \"frames\": 400, \"warmup\": 0, \"compare\": false,
  \"methods\": [{\"method\": \"direct\", \"params\": {\"light_samples\": 1}}]}")
set(S ${D}/out)
execute_process(COMMAND ${GIB} -q study ${D}/s.json --out ${S} WORKING_DIRECTORY ${ROOT}
                RESULT_VARIABLE rc ERROR_VARIABLE err)
file(GLOB results ${S}/runs/*/result.json)
if(NOT rc EQUAL 0 OR NOT results)
    message(FATAL_ERROR "the first study failed (exit ${rc}) or left no result:\n${err}")
endif()
file(GLOB logs ${S}/runs/*/render.log)
file(REMOVE ${logs})
# --fresh: start the study, wait for the run's child (its log), SIGTERM the study
execute_process(COMMAND sh -c "\"$0\" study \"$2\" --out \"$1\" --fresh >\"$1.log\" 2>&1 & p=$!
                               i=0; while ! ls \"$1\"/runs/*/render.log >/dev/null 2>&1 && [ $i -lt 600 ]; do sleep 0.05; i=$((i+1)); done
                               kill -TERM $p; wait $p; echo $?"
                        ${GIB} ${S} ${D}/s.json
                WORKING_DIRECTORY ${ROOT} TIMEOUT 120 RESULT_VARIABLE rc OUTPUT_VARIABLE code)
string(STRIP "${code}" code)
file(READ ${S}.log log)
if(NOT rc EQUAL 0 OR NOT code STREQUAL "1")
    fail("the interrupted study exited ${code} (expected 1):\n${log}")
endif()
match("${log}" "study: interrupted \\(1 runs to redo\\)" "the run was not reported interrupted:\n${log}")
file(READ ${S}/runs.csv csv)
match_count("${csv}" ",interrupted," 1 "interrupted runs in runs.csv")
match_count("${csv}" ",ok," 0 "runs recorded ok after the interrupt")
file(GLOB results ${S}/runs/*/result.json ${S}/runs/*/timings.json)
if(results)
    fail("the interrupted run left the previous run's files: ${results}")
endif()
# resuming redoes the run
execute_process(COMMAND ${GIB} study ${D}/s.json --out ${S} WORKING_DIRECTORY ${ROOT}
                RESULT_VARIABLE rc ERROR_VARIABLE err)
match("${err}" "\\[1/1\\] ran " "the resumed study did not redo the run:\n${err}")
if(NOT rc EQUAL 0)
    fail("the resumed study exited ${rc}:\n${err}")
endif()

if(failures GREATER 0)
    message(FATAL_ERROR "${failures} fresh-interrupt expectation(s) failed")
endif()
message(STATUS "an interrupted --fresh run is redone, not taken from the previous run")
