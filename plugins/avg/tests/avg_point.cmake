# avg's point-light shadow (issue 28): data/point_block.gltf, a closed room
# with a block lit only by a point light at about the block's height, so
# that the block's shadow lies more than 60 degrees from the vertical. At
# 32x32, direct light only (bounces=0) against the pixel-centre reference
# with one bounce, avg must put that shadow where the reference has it:
# shadow_region.py scores the light leaking into the shadow and the error
# elsewhere; black and the unshadowed `direct` both score about 1, avg must
# score at most 1/4 of the better (measured 0.058; before the fix the
# point light's VPLs covered the hemispheres above and below the light with
# 120 degree perspective maps and the shadow was missing: 1.069).
# Run by ctest as: cmake -DGIB=... -DHERE=... -DOUT=... -DEXPECT=.../expect.cmake -P avg_point.cmake

set(failures 0)
include(${EXPECT})

set(scene ${HERE}/data/point_block.gltf)
set(o ${OUT}/avg_point)
file(REMOVE ${o}_ref.pfm ${o}_avg.pfm ${o}_direct.pfm)
expect(0 "" reference --scene ${scene} --size 32x32 --spp 16 --max-bounces 1 --pixel center --out ${o}_ref.pfm)
expect(0 "" render --scene ${scene} --method avg --size 32x32 --param bounces=0 --out ${o}_avg.pfm)
expect(0 "" render --scene ${scene} --method direct --size 32x32 --out ${o}_direct.pfm)
execute_process(COMMAND /usr/bin/python3 ${HERE}/shadow_region.py ${o}_avg.pfm ${o}_ref.pfm ${o}_direct.pfm
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message(STATUS "avg point-light shadow, 32x32:\n${out}${err}")
if(rc EQUAL 2 OR NOT rc MATCHES "^[01]$")
    message(FATAL_ERROR "shadow_region.py could not score the images (${rc}): ${err}")
endif()
if(NOT rc EQUAL 0)
    fail("avg's point-light shadow on point_block: score above 1/4 of the better trivial answer")
endif()

end_checks()
