# Local lights on the held-out `punctual` room (issue 28; README "Sub-texel
# occluders", "Local-light acne"): a point and a spot light over a block and
# a thin single-sided panel, 64^2, through `gibench conformance --held-out`,
# which scores csm against the bounce-matched pixel-centre path-traced truth
# and requires relMSE <= 1/2 of the better trivial answer (black, or the
# unshadowed `direct`). csm declares the departure `held_out` with remedy
# occluders=dilated normal_offset_local=0.5 M_local=256, so the suite scores
# the remedy and reports the paper's nearest texel beside it. Each seed
# fails without one part of the remedy (relMSE, limit):
#  - seed 5, without occluders=dilated (nearest, M_local 256: 1.81, limit
#    0.398): light leaks through occluders narrower than a texel;
#  - seed 7, without M_local=256 (0.0058, limit 0.0028) or without
#    normal_offset_local=0.5 (0.0032): acne on the thin panel.
# Run by ctest as:
#   cmake -DGIB=... -DOUT=... -DPY=python3 -DSCRIPT=.../held_out.py -P csm_sub_texel.cmake
set(ENV{GIBENCH_PLUGIN_PATH} "")
foreach(seed 5 7)
    set(dir ${OUT}/csm_sub_texel_s${seed})
    file(REMOVE_RECURSE ${dir})
    execute_process(COMMAND ${PY} ${SCRIPT} --seed ${seed} --out ${dir}
                    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
    if(rc EQUAL 0)
        execute_process(COMMAND ${GIB} -q conformance --held-out ${dir} --method csm --variants punctual
                                --no-converge --size 64
                        RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
    endif()
    message("== seed ${seed}: exit ${rc}\n${out}${err}")
    # a failed set-up fails too; the trivial row must be there and pass
    # (pass*: with the declared remedy). SEND_ERROR goes on to the next
    # seed and makes `cmake -P` exit 1 at the end.
    if(NOT rc EQUAL 0 OR NOT out MATCHES "punctual +trivial +pass")
        message(SEND_ERROR "seed ${seed}: csm fails the held-out punctual variant at 64^2 (or its set-up)")
    endif()
endforeach()
