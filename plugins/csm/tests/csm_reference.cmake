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

set(limit_teapot_area 1.0)
set(limit_cornell_box 0.1)
foreach(scene teapot_area.glb cornell_box.gltf)
    string(REGEX REPLACE "\\..*" "" name ${scene})
    expect_beats_reference(csm ${SCENES}/${scene} LIMIT ${limit_${name}} MEAN 3 SPP 512 BOUNCES 1
                           METHOD_ARGS --frames 16 DIRECT_ARGS --param light_samples=16 --frames 16)
endforeach()

if(failures GREATER 0)
    message(FATAL_ERROR "${failures} csm reference expectation(s) failed")
endif()
message(STATUS "csm against the reference: all expectations met")
