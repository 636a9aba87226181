# Shared set-up of the tests that signal a running study (study_interrupt,
# study_fresh_interrupt, study_retry_failed): include()d after expect.cmake.

# signal_study(<what> <out dir> <study file> <ready> <signal> [study options...]):
# starts `gibench study FILE --out OUT [options]` in ${ROOT} in the
# background (its output in OUT.log), polls every 0.05 s, for at most 60 s,
# until the shell test `ready` holds (in it $o is OUT), runs the shell
# command `signal` ($p: the study's process id; variables `ready` set are
# seen), and waits for the study, which must exit 1 (a failure named by
# `what` otherwise). Leaves the study's output in study_log.
function(signal_study what out file ready signal)
    execute_process(COMMAND sh -c "g=$0 o=$1 f=$2; shift 2
                                   \"$g\" study \"$f\" --out \"$o\" \"$@\" >\"$o.log\" 2>&1 & p=$!
                                   i=0; while ! { ${ready}; } && [ $i -lt 1200 ]; do sleep 0.05; i=$((i+1)); done
                                   ${signal}; wait $p; echo $?"
                            ${GIB} ${out} ${file} ${ARGN}
                    WORKING_DIRECTORY ${ROOT} TIMEOUT 120 RESULT_VARIABLE rc OUTPUT_VARIABLE code)
    string(STRIP "${code}" code)
    file(READ ${out}.log log)
    if(NOT rc EQUAL 0 OR NOT code STREQUAL "1")
        fail("${what} exited ${code} (expected 1):\n${log}")
    endif()
    set(study_log "${log}" PARENT_SCOPE)
    set(failures ${failures} PARENT_SCOPE)
endfunction()

# The `ready` test of a study whose first run has started: a render log.
set(RUN_STARTED "ls \"$o\"/runs/*/render.log >/dev/null 2>&1")

# fresh_study_dir(<name>): D = ${OUT}/<name>, emptied; S = ${D}/out, the
# study's output folder.
macro(fresh_study_dir name)
    set(D ${OUT}/${name})
    file(REMOVE_RECURSE ${D})
    file(MAKE_DIRECTORY ${D})
    set(S ${D}/out)
endmacro()

# coarse_study(<file> <name> <frames> <methods>): writes a study of the
# coarse Cornell box at 16 x 16, no warm-up, not compared, with `methods`
# (its JSON list).
function(coarse_study file name frames methods)
    file(WRITE ${file} "{\"name\": \"${name}\", \"base\": \"${ROOT}\", \"scenes\": [\"scenes/cornell_box_coarse.gltf\"],
  \"size\": [16, 16], \"frames\": ${frames}, \"warmup\": 0, \"compare\": false,
  \"methods\": ${methods}}")
endfunction()
