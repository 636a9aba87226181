# Sub-texel occluders of local lights (issue 28; README "Sub-texel
# occluders"): the held-out `punctual` room of seeds 3 and 5 (a point and a
# spot light, a block, a thin panel seen nearly edge-on from the spot) at
# 64^2, through `gibench conformance --held-out`, which scores csm against the
# bounce-matched pixel-centre path-traced truth and requires relMSE <= 1/2 of
# the better trivial answer (black, or the unshadowed `direct`). csm declares
# the departure `held_out` with remedy occluders=dilated, so the suite
# scores the remedy and reports the paper's nearest texel beside it
# (0.82 and 2.01, failing: light leaks into pixels both lights leave dark).
# Seed 10's room fails with occluders=dilated alone (0.0166, limit 0.0084:
# acne from normal_offset_local 0.25 on the thin panel); the remedy's
# normal_offset_local=0.5 passes it (README "Local-light acne").
# Run by ctest as:
#   cmake -DGIB=... -DOUT=... -DPY=python3 -DSCRIPT=.../held_out.py -P csm_sub_texel.cmake
set(failures 0)
set(ENV{GIBENCH_PLUGIN_PATH} "")
foreach(seed 3 5 10)
    set(dir ${OUT}/csm_sub_texel_s${seed})
    file(REMOVE_RECURSE ${dir})
    execute_process(COMMAND ${PY} ${SCRIPT} --seed ${seed} --out ${dir}
                    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
    if(NOT rc EQUAL 0)
        message(SEND_ERROR "seed ${seed}: held_out.py failed (exit ${rc}): ${out}${err}")
        math(EXPR failures "${failures} + 1")
        continue()
    endif()
    execute_process(COMMAND ${GIB} -q conformance --held-out ${dir} --method csm --variants punctual
                            --no-converge --size 64
                    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
    message("== seed ${seed}: exit ${rc}\n${out}${err}")
    # the trivial row must be there and pass (pass*: with the declared remedy)
    if(NOT rc EQUAL 0 OR NOT out MATCHES "punctual +trivial +pass")
        message(SEND_ERROR "seed ${seed}: csm fails the held-out punctual variant at 64^2")
        math(EXPR failures "${failures} + 1")
    endif()
endforeach()
if(failures GREATER 0)
    message(FATAL_ERROR "${failures} failure(s)")
endif()
