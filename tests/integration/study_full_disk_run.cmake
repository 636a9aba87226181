# Issue 32, item 6: a run whose disk fills while it writes its image is a
# failed run that the summary calls external (the render's own log, on the
# same disk, may say nothing), the study exits 1, and --retry-failed redoes
# it once there is room. The run's directory is a link into a small full
# tmpfs; needs root to mount it, else the test prints why and is skipped.
# cmake -DGIB=... -DROOT=... -DOUT=... -P study_full_disk_run.cmake
set(failures 0)
include(${CMAKE_CURRENT_LIST_DIR}/expect.cmake)
include(${CMAKE_CURRENT_LIST_DIR}/tmpfs.cmake)
set(D ${OUT}/study_full_disk_run)
set(M ${OUT}/study_full_disk_run_tmpfs)
small_tmpfs(${M})
file(REMOVE_RECURSE ${D})
file(MAKE_DIRECTORY ${D}/out/runs)
file(WRITE ${D}/s.json "{\"name\": \"full\", \"base\": \"${ROOT}\", \"scenes\": [\"scenes/cornell_box_coarse.gltf\"],
  \"size\": [16, 16], \"frames\": 1, \"warmup\": 0, \"compare\": false,
  \"methods\": [{\"method\": \"direct\", \"params\": {\"light_samples\": 1}}]}")
execute_process(COMMAND ${GIB} study ${D}/s.json --dry-run WORKING_DIRECTORY ${ROOT} OUTPUT_VARIABLE plan)
string(REGEX MATCH "\nrun ([^:]+):" ignored "${plan}")
set(id ${CMAKE_MATCH_1})
file(MAKE_DIRECTORY ${M}/run)
file(CREATE_LINK ${M}/run ${D}/out/runs/${id} SYMBOLIC)
execute_process(COMMAND dd if=/dev/zero of=${M}/fill bs=4096 OUTPUT_QUIET ERROR_QUIET)
run(1 study ${D}/s.json --out ${D}/out)
match("${last_err}" "study: failed \\(looks external\\): ${id}: [^\n]*No space left on device"
      "the run on the full disk is not called external:\n${last_err}")
match("${last_err}" "1 of 1 runs failed, 1 of them look external" "no verdict:\n${last_err}")
file(REMOVE ${M}/fill)
run(0 study ${D}/s.json --out ${D}/out --retry-failed)
match("${last_err}" "\\[1/1\\] ran " "--retry-failed did not redo the run:\n${last_err}")
execute_process(COMMAND umount ${M})

if(failures GREATER 0)
    message(FATAL_ERROR "${failures} full-disk run expectation(s) failed")
endif()
message(STATUS "a run on a full disk is an external failure; --retry-failed redoes it")
