# implicit_vis against the Embree path-traced reference on the Cornell box
# at 32x32, 4 bounces (direct + the plugin's 3 indirect), beside the trivial
# answers: black (relMSE 1 by its definition, mean of (t - r)^2 / (r^2 + eps))
# and the unshadowed, direct-only `direct` plugin. implicit_vis must stay
# under a relMSE limit (0.2) that both trivial answers exceed, and its image
# mean within 5 % of the reference's (measured at 64x64: relMSE 0.088, mean
# -1.0 %; direct 0.43, mean -25 %).
# Run by ctest as: cmake -DGIB=... -DSCENES=... -DOUT=... -DEXPECT=.../expect.cmake -P iv_reference.cmake
set(failures 0)
include(${EXPECT})
set(ENV{GIBENCH_CACHE} ${OUT}/iv_cache_reference)
file(MAKE_DIRECTORY ${OUT}/iv_cache_reference)

function(diff_metric test ref key out_var)
    execute_process(COMMAND ${GIB} diff ${test} ${ref} --json RESULT_VARIABLE rc OUTPUT_VARIABLE j)
    if(NOT rc EQUAL 0)
        message(FATAL_ERROR "gibench diff ${test} ${ref} failed (${rc})")
    endif()
    string(JSON v GET "${j}" ${key})
    set(${out_var} ${v} PARENT_SCOPE)
endfunction()

set(size --size 32x32)
expect(0 "" reference --scene ${SCENES}/cornell_box.gltf ${size} --spp 256 --max-bounces 4 --threads 1
       --out ${OUT}/iv_ref_cornell.exr)
expect(0 "" render --scene ${SCENES}/cornell_box.gltf --method implicit_vis ${size} --out ${OUT}/iv_cornell.exr)
expect(0 "" render --scene ${SCENES}/cornell_box.gltf --method direct ${size} --frames 4 --out ${OUT}/iv_direct_cornell.exr)
diff_metric(${OUT}/iv_cornell.exr ${OUT}/iv_ref_cornell.exr relmse iv_relmse)
diff_metric(${OUT}/iv_cornell.exr ${OUT}/iv_ref_cornell.exr mean_lum_diff_pct iv_mean)
diff_metric(${OUT}/iv_direct_cornell.exr ${OUT}/iv_ref_cornell.exr relmse direct_relmse)
message(STATUS "cornell_box: implicit_vis relMSE ${iv_relmse}, mean ${iv_mean} %; direct relMSE ${direct_relmse}; black 1")
# the limit lies between the method and both trivial answers (black: 1)
set(limit 0.2)
if(NOT iv_relmse LESS ${limit} OR NOT direct_relmse GREATER ${limit})
    message(SEND_ERROR "cornell_box: implicit_vis relMSE ${iv_relmse} should be < ${limit} < direct's ${direct_relmse} (and black's 1)")
    math(EXPR failures "${failures} + 1")
endif()
if(iv_mean LESS -5 OR iv_mean GREATER 5)
    message(SEND_ERROR "implicit_vis image mean ${iv_mean} % off the reference's by more than 5 %")
    math(EXPR failures "${failures} + 1")
endif()
if(failures GREATER 0)
    message(FATAL_ERROR "${failures} implicit_vis reference expectation(s) failed")
endif()
message(STATUS "implicit_vis against the reference: all expectations met")
