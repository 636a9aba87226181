# Numbers on the command line fit what they become: an exposure of 1e39
# (inf as a float) or beyond -64..64 stops, a time past a float's range or
# with leading blanks is refused with exit 2 and one line, before any work.
# cmake -DGIB=... -DROOT=... -DOUT=... -P cli_strict.cmake
set(failures 0)
include(${CMAKE_CURRENT_LIST_DIR}/expect.cmake)
set(S ${ROOT}/scenes/cornell_box_coarse.gltf)
set(D ${OUT}/cli_strict)
file(REMOVE_RECURSE ${D})
foreach(ev 1e39 -1e39 65 nan)
    expect(2 "--exposure '${ev}' is not a number of stops in -64..64"
           render --scene ${S} --method direct --exposure ${ev} --out ${D}/r.png)
    expect(2 "--exposure '${ev}' is not a number of stops in -64..64"
           reference --scene ${S} --exposure ${ev} --out ${D}/r.exr)
    expect(2 "--exposure '${ev}' is not a number of stops in -64..64"
           compare --scene ${S} --methods direct --exposure ${ev} --out ${D}/c)
endforeach()
expect(2 "--time '1e39' is not a non-negative number" render --scene ${S} --method direct --time 1e39 --out ${D}/r.png)
expect(2 "--time ' 1' is not a non-negative number" render --scene ${S} --method direct --time " 1" --out ${D}/r.png)
expect(2 "light_samples=' 5' is not an integer"
       render --scene ${S} --method direct --param "light_samples= 5" --out ${D}/r.png)
if(EXISTS ${D})
    fail("a refused command wrote ${D}")
endif()
if(failures GREATER 0)
    message(FATAL_ERROR "${failures} command line(s) not refused properly")
endif()
message(STATUS "out-of-range numbers on the command line are refused")
