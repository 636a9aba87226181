# One study at a time per --out: while a study runs (here on a hanging
# method), a second `gibench study ... --out` on the same folder exits 2 at
# once with one line naming the holder's pid, and builds nothing; once the
# first dies (SIGKILL, as a crash would), the folder is free again.
# cmake -DGIB=... -DROOT=... -DOUT=... -DFAKE_RUN=... -P study_lock.cmake
set(failures 0)
include(${CMAKE_CURRENT_LIST_DIR}/expect.cmake)
set(ENV{GIBENCH_PLUGIN_PATH} "${FAKE_RUN}")
set(D ${OUT}/study_lock)
file(REMOVE_RECURSE ${D})
file(MAKE_DIRECTORY ${D})
file(WRITE ${D}/hang.json "{\"name\": \"hang\", \"base\": \"${ROOT}\", \"scenes\": [\"scenes/cornell_box_coarse.gltf\"],
  \"size\": [8, 8], \"frames\": 1, \"warmup\": 0, \"compare\": false, \"timeout\": 60,
  \"methods\": [{\"method\": \"fake_hang\"}]}")
file(WRITE ${D}/quick.json "{\"name\": \"quick\", \"base\": \"${ROOT}\", \"scenes\": [\"scenes/cornell_box_coarse.gltf\"],
  \"size\": [8, 8], \"frames\": 1, \"warmup\": 0, \"compare\": false, \"methods\": [{\"method\": \"direct\"}]}")
set(S ${D}/out)

# the first study hangs in its run; the second is started on the same --out
# and must be answered at once; then the first is killed (no clean-up of
# its own) and a third study must get the lock.
execute_process(COMMAND sh -c "\"$0\" study \"$2\" --out \"$1\" >\"$1.first.log\" 2>&1 & p=$!
                               i=0; while ! ls \"$1\"/runs/*/render.log >/dev/null 2>&1 && [ $i -lt 600 ]; do sleep 0.1; i=$((i+1)); done
                               echo first=$p
                               timeout 20 \"$0\" study \"$2\" --out \"$1\" >\"$1.second.log\" 2>&1; echo second=$?
                               kill -KILL $p; wait $p
                               timeout 30 \"$0\" study \"$3\" --out \"$1\" >\"$1.third.log\" 2>&1; echo third=$?"
                        ${GIB} ${S} ${D}/hang.json ${D}/quick.json
                WORKING_DIRECTORY ${ROOT} TIMEOUT 100 RESULT_VARIABLE rc OUTPUT_VARIABLE out)
if(NOT rc EQUAL 0)
    fail("the driving script failed (${rc}): ${out}")
endif()
string(REGEX MATCH "first=([0-9]+)" m "${out}")
set(first_pid ${CMAKE_MATCH_1})
file(READ ${S}.second.log second)
if(NOT out MATCHES "second=2\n")
    fail("a second study on the same --out did not exit 2 at once (${out}):\n${second}")
endif()
match("${second}" "^gibench: study: [^\n]*out is in use by another study \\(pid ${first_pid} holds [^\n]*\\.gibench-study\\.lock\\)\n$"
      "the second study's one line does not name the holder's pid ${first_pid}:\n${second}")
if(second MATCHES "reference|run 1/|\\[1/")
    fail("the second study built something before refusing:\n${second}")
endif()
# the first died without releasing anything itself: the kernel did
file(READ ${S}.third.log third)
if(NOT out MATCHES "third=0\n")
    fail("after the holder was killed the folder stayed locked (${out}):\n${third}")
endif()
match("${third}" "study: wrote " "the third study did not finish:\n${third}")
file(READ ${S}/.gibench-study.lock holder)
string(STRIP "${holder}" holder)
if(NOT holder MATCHES "^[0-9]+$" OR holder STREQUAL first_pid)
    fail("the lock file holds '${holder}', not the last holder's pid")
endif()

if(failures GREATER 0)
    message(FATAL_ERROR "${failures} lock expectation(s) failed")
endif()
message(STATUS "a study's --out is locked while it runs and freed when it dies")
