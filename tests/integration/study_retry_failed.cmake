# Issue 32, item 6: a run killed from outside (SIGKILL, as the out-of-memory
# killer sends) is a failed run that the summary calls external; a study
# with failed runs exits 1; resuming keeps the failure, --retry-failed
# redoes the failed run alone (the run that was ok stays cached).
# cmake -DGIB=... -DROOT=... -DOUT=... -P study_retry_failed.cmake
set(failures 0)
include(${CMAKE_CURRENT_LIST_DIR}/expect.cmake)
include(${CMAKE_CURRENT_LIST_DIR}/study_signal.cmake)
fresh_study_dir(study_retry_failed)
# a quick run, then one slow enough to be killed while it renders
coarse_study(${D}/s.json retry 1 "[{\"method\": \"direct\", \"params\": {\"light_samples\": 2}},
               {\"method\": \"direct\", \"params\": {\"light_samples\": 1}, \"frames\": 400}]")
# start the study, wait for the slow run's render, SIGKILL that render alone
signal_study("the study with a killed run" ${S} ${D}/s.json
             "k=$(ps -eo pid=,args= | grep -F \"$o/runs/\" | grep -F -- '--frames 400' | grep -v grep | awk '{print $1}'); [ -n \"$k\" ]"
             "kill -KILL $k")
set(log "${study_log}")
match("${log}" "study: failed \\(looks external\\): [^\n]*: killed \\(signal 9" "the killed run is not called external:\n${log}")
match("${log}" "gibench: study: 1 of 2 runs failed, 1 of them look external" "no verdict line:\n${log}")
file(READ ${S}/runs.csv csv)
match_count("${csv}" ",failed,killed \\(signal 9" 1 "killed runs in runs.csv")
# resuming keeps the failure (and exits 1 again)
run(1 study ${D}/s.json --out ${S})
match("${last_err}" "\\[2/2\\] failed " "resuming did not keep the failed run:\n${last_err}")
# --retry-failed redoes it, and only it
run(0 study ${D}/s.json --out ${S} --retry-failed)
match("${last_err}" "\\[1/2\\] cached " "--retry-failed redid a run that was ok:\n${last_err}")
match("${last_err}" "\\[2/2\\] ran " "--retry-failed did not redo the failed run:\n${last_err}")
file(READ ${S}/runs.csv csv)
match_count("${csv}" ",ok," 2 "runs ok after --retry-failed")
run(2 study ${D}/s.json --out ${S} --retry-failed --fresh)

if(failures GREATER 0)
    message(FATAL_ERROR "${failures} retry-failed expectation(s) failed")
endif()
message(STATUS "a killed run is an external failure; --retry-failed redoes it")
