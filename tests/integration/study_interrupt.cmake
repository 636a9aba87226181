# SIGTERM to a running study (as Ctrl-C would be): each run in progress is
# stopped with its process group (SIGTERM, SIGKILL after the grace period),
# no run is left behind or started, the report lists the runs as
# "interrupted", never "failed", and resuming redoes them.
# cmake -DGIB=... -DROOT=... -DOUT=... -DFAKE_RUN=... -P study_interrupt.cmake
set(failures 0)
include(${CMAKE_CURRENT_LIST_DIR}/expect.cmake)
include(${CMAKE_CURRENT_LIST_DIR}/study_signal.cmake)
set(ENV{GIBENCH_PLUGIN_PATH} "${FAKE_RUN}")
fresh_study_dir(study_interrupt)
# two hanging runs and one that is never reached before the signal
function(study_file timeout)
    file(WRITE ${D}/hang.json "{\"name\": \"hang\", \"base\": \"${ROOT}\", \"scenes\": [\"scenes/cornell_box_coarse.gltf\"],
  \"size\": [8, 8], \"frames\": 1, \"warmup\": 0, \"compare\": false, \"timeout\": ${timeout},
  \"methods\": [{\"method\": \"fake_hang\", \"params\": {}}, {\"method\": \"fake_hang\", \"label\": \"second\"},
               {\"method\": \"direct\"}]}")
endfunction()

foreach(jobs 1 2)
    set(S ${D}/out${jobs})
    study_file(600)
    # start the study, wait for its first run's log, SIGTERM the study alone
    signal_study("--jobs ${jobs}: the interrupted study" ${S} ${D}/hang.json "${RUN_STARTED}"
                 "sleep 1; kill -TERM $p" --jobs ${jobs})
    set(log "${study_log}")
    match("${log}" "study: interrupted \\(3 runs to redo\\)" "--jobs ${jobs}: no 'interrupted' line:\n${log}")
    # no render of this study is left running
    execute_process(COMMAND sh -c "ps -eo args | grep -F \"$0/runs/\" | grep -v grep" ${S} OUTPUT_VARIABLE left)
    if(NOT left STREQUAL "")
        fail("--jobs ${jobs}: runs left running after the study was interrupted:\n${left}")
    endif()
    file(READ ${S}/runs.csv csv)
    match_count("${csv}" ",interrupted," 3 "--jobs ${jobs}: interrupted runs in runs.csv")
    match_count("${csv}" ",failed," 0 "--jobs ${jobs}: failed runs in runs.csv")
    file(GLOB results ${S}/runs/*/result.json)
    if(results)
        fail("--jobs ${jobs}: an interrupted run left a result: ${results}")
    endif()
    # resuming redoes every run: the hangs time out now, direct finishes
    # (6 s: the timeout holds for direct too, whose 8x8 render with a cold
    # shader cache took over 2 s of wall time under a load of 12)
    study_file(6)
    execute_process(COMMAND ${GIB} study ${D}/hang.json --out ${S} --jobs ${jobs} WORKING_DIRECTORY ${ROOT}
                    TIMEOUT 120 RESULT_VARIABLE rc OUTPUT_QUIET ERROR_VARIABLE err)
    file(READ ${S}/runs.csv csv)
    match_count("${csv}" ",failed,\"?timed out after" 2 "--jobs ${jobs}: the hangs were not redone on resume:\n${csv}")
    match_count("${csv}" ",ok," 1 "--jobs ${jobs}: the run never started was not run on resume:\n${csv}")
    match_count("${csv}" ",interrupted," 0 "--jobs ${jobs}: interrupted runs after resuming")
endforeach()

if(failures GREATER 0)
    message(FATAL_ERROR "${failures} interrupt expectation(s) failed")
endif()
message(STATUS "an interrupted study stops its runs and redoes them on resume")
