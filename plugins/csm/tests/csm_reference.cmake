# The csm plugin against the one-bounce Embree reference (direct light
# only) at 32x32 on the teapot under its area light and on the Cornell box,
# with the unshadowed `direct` plugin for contrast: csm's relMSE must stay
# under a limit that direct's exceeds many times over (measured: teapot csm
# 0.17 with the thin shell, 0.20 open, direct 27.6; Cornell csm 0.043, direct 1.45; with bias = R, i.e.
# hardly any shadow, csm gives 26.6 and 0.22), and its image mean
# within 3 % of the reference's (teapot direct: +7.5 %).
# Run by ctest as: cmake -DGIB=... -DSCENES=... -DOUT=... -DEXPECT=.../expect.cmake -P csm_reference.cmake

set(failures 0)
include(${EXPECT})
set(ENV{GIBENCH_CACHE} ${OUT}/csm_cache_reference)
file(MAKE_DIRECTORY ${OUT}/csm_cache_reference)

function(diff_metric test ref key out_var)
    execute_process(COMMAND ${GIB} diff ${test} ${ref} --json RESULT_VARIABLE rc OUTPUT_VARIABLE j)
    if(NOT rc EQUAL 0)
        message(FATAL_ERROR "gibench diff ${test} ${ref} failed (${rc})")
    endif()
    string(JSON v GET "${j}" ${key})
    set(${out_var} ${v} PARENT_SCOPE)
endfunction()

set(limit_teapot_area 1.0)
set(limit_cornell_box 0.1)
foreach(scene teapot_area.glb cornell_box.gltf)
    string(REGEX REPLACE "\\..*" "" name ${scene})
    set(size --size 32x32)
    expect(0 "" reference --scene ${SCENES}/${scene} ${size} --spp 512 --max-bounces 1 --threads 1
           --out ${OUT}/csm_ref_${name}.exr)
    expect(0 "" render --scene ${SCENES}/${scene} --method csm ${size} --frames 16 --out ${OUT}/csm_vs_ref_${name}.exr)
    expect(0 "" render --scene ${SCENES}/${scene} --method direct --param light_samples=16 ${size} --frames 16
           --out ${OUT}/direct_vs_ref_${name}.exr)
    diff_metric(${OUT}/csm_vs_ref_${name}.exr ${OUT}/csm_ref_${name}.exr relmse csm_relmse)
    diff_metric(${OUT}/csm_vs_ref_${name}.exr ${OUT}/csm_ref_${name}.exr mean_lum_diff_pct csm_mean)
    diff_metric(${OUT}/direct_vs_ref_${name}.exr ${OUT}/csm_ref_${name}.exr relmse direct_relmse)
    diff_metric(${OUT}/direct_vs_ref_${name}.exr ${OUT}/csm_ref_${name}.exr mean_lum_diff_pct direct_mean)
    message(STATUS "${name}: csm relMSE ${csm_relmse}, mean ${csm_mean} %; direct relMSE ${direct_relmse}, mean ${direct_mean} %")
    if(NOT csm_relmse LESS ${limit_${name}} OR NOT direct_relmse GREATER ${limit_${name}})
        message(SEND_ERROR "${name}: csm relMSE ${csm_relmse} should be < ${limit_${name}} < direct's ${direct_relmse}")
        math(EXPR failures "${failures} + 1")
    endif()
    if(csm_mean LESS -3 OR csm_mean GREATER 3)
        message(SEND_ERROR "${name}: csm image mean ${csm_mean} % off the reference's by more than 3 %")
        math(EXPR failures "${failures} + 1")
    endif()
endforeach()

if(failures GREATER 0)
    message(FATAL_ERROR "${failures} csm reference expectation(s) failed")
endif()
message(STATUS "csm against the reference: all expectations met")
