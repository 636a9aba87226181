# Issue 32, item 2: `study --fresh` interrupted during a run that is not
# compared ("compare": false) must not record the previous run's files as a
# new "ok" (before the fix the interrupted render counted as finished and
# its stale timings.json was taken); the resumed study redoes the run.
# cmake -DGIB=... -DROOT=... -DOUT=... -P study_fresh_interrupt.cmake
set(failures 0)
include(${CMAKE_CURRENT_LIST_DIR}/expect.cmake)
include(${CMAKE_CURRENT_LIST_DIR}/study_signal.cmake)
fresh_study_dir(study_fresh_interrupt)
# enough frames that the render is still going when the signal comes
coarse_study(${D}/s.json fresh 400 "[{\"method\": \"direct\", \"params\": {\"light_samples\": 1}}]")
execute_process(COMMAND ${GIB} -q study ${D}/s.json --out ${S} WORKING_DIRECTORY ${ROOT}
                RESULT_VARIABLE rc ERROR_VARIABLE err)
file(GLOB results ${S}/runs/*/result.json)
if(NOT rc EQUAL 0 OR NOT results)
    message(FATAL_ERROR "the first study failed (exit ${rc}) or left no result:\n${err}")
endif()
file(GLOB logs ${S}/runs/*/render.log)
file(REMOVE ${logs})
# --fresh: start the study, wait for the run's child (its log), SIGTERM the study
signal_study("the interrupted study" ${S} ${D}/s.json "${RUN_STARTED}" "kill -TERM $p" --fresh)
set(log "${study_log}")
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
