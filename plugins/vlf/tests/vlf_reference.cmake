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

set(limit_cornell_box 0.1)
set(limit_cornell_glossy 0.14)
set(trivial_cornell_box 0.3)     # 3 x the limit
set(trivial_cornell_glossy 0.35)  # 2.5 x the limit
foreach(name cornell_box cornell_glossy)
    expect_beats_reference(vlf ${SCENES}/${name}.gltf LIMIT ${limit_${name}} TRIVIAL ${trivial_${name}} BLACK
                           MEAN 10 SPP 256 BOUNCES 8 DIRECT_ARGS --frames 4)
endforeach()

if(failures GREATER 0)
    message(FATAL_ERROR "${failures} vlf reference expectation(s) failed")
endif()
message(STATUS "vlf against the reference: all expectations met")
