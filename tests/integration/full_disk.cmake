# Outputs on a full disk: every writer of images, heat maps and JSON fails
# with exit 1 and one line, and leaves neither a file under the final name
# nor a temporary file. Needs root to mount a small tmpfs; otherwise the
# test prints why and is skipped.
# cmake -DGIB=... -DROOT=... -DOUT=... -P full_disk.cmake
set(failures 0)
include(${CMAKE_CURRENT_LIST_DIR}/expect.cmake)
include(${CMAKE_CURRENT_LIST_DIR}/tmpfs.cmake)
set(M ${OUT}/full_disk)
set(SRC ${OUT}/full_disk_src)
small_tmpfs(${M})
file(REMOVE_RECURSE ${SRC})
file(MAKE_DIRECTORY ${SRC})

# Inputs on the ordinary disk.
execute_process(COMMAND ${GIB} reference --scene ${ROOT}/scenes/cornell_box_coarse.gltf --size 32x32 --spp 4
                        --out ${SRC}/ref.exr RESULT_VARIABLE rc OUTPUT_QUIET ERROR_QUIET)
if(NOT rc EQUAL 0)
    execute_process(COMMAND umount ${M})
    message(FATAL_ERROR "could not make the input image")
endif()
# Fill the tmpfs to the last block.
execute_process(COMMAND dd if=/dev/zero of=${M}/fill bs=4096 OUTPUT_QUIET ERROR_QUIET)

# refuse(<output file name in the full tmpfs> <args...>)
function(refuse name)
    execute_process(COMMAND ${GIB} ${ARGN} TIMEOUT 300 RESULT_VARIABLE rc OUTPUT_QUIET ERROR_VARIABLE err)
    string(STRIP "${err}" err)
    # the last line is the verdict; earlier lines may be progress or warnings
    string(REGEX REPLACE ".*\n" "" last "${err}")
    file(GLOB left ${M}/.*tmp* ${M}/${name})
    if(NOT rc EQUAL 1 OR NOT last MATCHES "No space left on device" OR left)
        message(SEND_ERROR "${ARGN}: expected exit 1, 'No space left on device' and no file; got exit ${rc}\n"
                           "${err}\nleft in the tmpfs: ${left}")
        math(EXPR f "${failures} + 1")
        set(failures ${f} PARENT_SCOPE)
    endif()
endfunction()

refuse(heat.png diff ${SRC}/ref.exr ${SRC}/ref.exr --heatmap ${M}/heat.png)
refuse(flip.png diff ${SRC}/ref.exr ${SRC}/ref.exr --flip-map ${M}/flip.png)
foreach(ext png exr pfm)
    refuse(direct.${ext} render --scene ${ROOT}/scenes/cornell_box_coarse.gltf --method direct --size 32x32
           --out ${M}/direct.${ext})
endforeach()
refuse(ref.exr reference --scene ${ROOT}/scenes/cornell_box_coarse.gltf --size 32x32 --spp 2 --out ${M}/ref.exr)
refuse(ref.png reference --scene ${ROOT}/scenes/cornell_box_coarse.gltf --size 32x32 --spp 2 --out ${M}/ref.png)
refuse(stats.json reference --scene ${ROOT}/scenes/cornell_box_coarse.gltf --size 32x32 --spp 2
       --out ${SRC}/ref2.exr --stats ${M}/stats.json)

execute_process(COMMAND umount ${M})
if(failures GREATER 0)
    message(FATAL_ERROR "${failures} write(s) to a full disk did not fail cleanly")
endif()
message(STATUS "writes to a full disk fail cleanly")
