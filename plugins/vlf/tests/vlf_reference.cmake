# The vlf plugin against the Embree reference with its bounce count
# (B = max_bounces + 1 = 8) at 32x32 on the Cornell box and on the glossy
# Cornell box (mirror tall block, Phong short block), with two trivial
# answers scored on the same reference: the unshadowed `direct` plugin and a
# black image. vlf's relMSE must stay under a limit that both trivial
# answers exceed 3x (Cornell) and 2.5x (glossy) over, and its image mean within 10 %
# of the reference's. Measured (32x32, defaults): see plugins/vlf/README.md.
# Run by ctest as: cmake -DGIB=... -DSCENES=... -DOUT=... -DEXPECT=.../expect.cmake -P vlf_reference.cmake

set(failures 0)
include(${EXPECT})

function(diff_metric test ref key out_var)
    execute_process(COMMAND ${GIB} diff ${test} ${ref} --json RESULT_VARIABLE rc OUTPUT_VARIABLE j)
    if(NOT rc EQUAL 0)
        message(FATAL_ERROR "gibench diff ${test} ${ref} failed (${rc})")
    endif()
    string(JSON v GET "${j}" ${key})
    set(${out_var} ${v} PARENT_SCOPE)
endfunction()

set(limit_cornell_box 0.1)
set(limit_cornell_glossy 0.14)
set(trivial_cornell_box 0.3)     # 3 x the limit
set(trivial_cornell_glossy 0.35)  # 2.5 x the limit
foreach(name cornell_box cornell_glossy)
    set(size --size 32x32)
    expect(0 "" reference --scene ${SCENES}/${name}.gltf ${size} --spp 256 --max-bounces 8 --threads 1
           --out ${OUT}/vlf_ref_${name}.exr)
    expect(0 "" render --scene ${SCENES}/${name}.gltf --method vlf ${size} --out ${OUT}/vlf_vs_ref_${name}.exr)
    expect(0 "" render --scene ${SCENES}/${name}.gltf --method direct ${size} --frames 4
           --out ${OUT}/vlf_direct_${name}.exr)
    # the black image: the reference zeroed
    execute_process(COMMAND oiiotool ${OUT}/vlf_ref_${name}.exr --mulc 0,0,0,1 -o ${OUT}/vlf_black_${name}.exr
                    RESULT_VARIABLE rc)
    if(NOT rc EQUAL 0)
        message(FATAL_ERROR "oiiotool could not write the black image (${rc})")
    endif()
    diff_metric(${OUT}/vlf_vs_ref_${name}.exr ${OUT}/vlf_ref_${name}.exr relmse vlf_relmse)
    diff_metric(${OUT}/vlf_vs_ref_${name}.exr ${OUT}/vlf_ref_${name}.exr mean_lum_diff_pct vlf_mean)
    diff_metric(${OUT}/vlf_direct_${name}.exr ${OUT}/vlf_ref_${name}.exr relmse direct_relmse)
    diff_metric(${OUT}/vlf_black_${name}.exr ${OUT}/vlf_ref_${name}.exr relmse black_relmse)
    message(STATUS "${name}: vlf relMSE ${vlf_relmse}, mean ${vlf_mean} %; unshadowed direct relMSE ${direct_relmse}; black ${black_relmse}")
    if(NOT vlf_relmse LESS ${limit_${name}})
        message(SEND_ERROR "${name}: vlf relMSE ${vlf_relmse} not below ${limit_${name}}")
        math(EXPR failures "${failures} + 1")
    endif()
    if(direct_relmse LESS ${trivial_${name}} OR black_relmse LESS ${trivial_${name}})
        message(SEND_ERROR "${name}: a trivial answer scores under ${trivial_${name}} (2.5-3 x the limit): direct ${direct_relmse}, black ${black_relmse}")
        math(EXPR failures "${failures} + 1")
    endif()
    if(vlf_mean LESS -10 OR vlf_mean GREATER 10)
        message(SEND_ERROR "${name}: vlf image mean ${vlf_mean} % off the reference's by more than 10 %")
        math(EXPR failures "${failures} + 1")
    endif()
endforeach()

if(failures GREATER 0)
    message(FATAL_ERROR "${failures} vlf reference expectation(s) failed")
endif()
message(STATUS "vlf against the reference: all expectations met")
