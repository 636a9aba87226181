# Files that gibench reads must be regular files: a FIFO or a device
# (/dev/zero) given as an image to diff, as compare --reference, or as a
# scene's environment map is refused at once (exit 2, one line) instead of
# blocking or reading forever. No GL needed.
# cmake -DGIB=... -DROOT=... -DOUT=... -P resource_files.cmake
set(failures 0)
include(${CMAKE_CURRENT_LIST_DIR}/expect.cmake)
set(D ${OUT}/resource_files)
file(REMOVE_RECURSE ${D})
file(MAKE_DIRECTORY ${D})

# refused(<name> <regex> <args...>): exit 2 within 10 s, one line matching regex.
function(refused name regex)
    execute_process(COMMAND ${GIB} ${ARGN} TIMEOUT 10 RESULT_VARIABLE rc OUTPUT_QUIET ERROR_VARIABLE err)
    expect_refusal(${name} "${regex}" "${rc}" "${err}")
    set(failures ${failures} PARENT_SCOPE)
endfunction()

set(SCENE ${ROOT}/scenes/cornell_box_coarse.gltf)
execute_process(COMMAND mkfifo ${D}/fifo.exr RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
    message(FATAL_ERROR "mkfifo failed")
endif()
execute_process(COMMAND ${GIB} reference --scene ${SCENE} --size 16x16 --spp 1 --out ${D}/ref16.exr
                RESULT_VARIABLE rc OUTPUT_QUIET ERROR_QUIET)
if(NOT rc EQUAL 0)
    message(FATAL_ERROR "could not make the 16x16 reference")
endif()

# diff: either image a FIFO or a device
refused(diff_fifo_test "fifo.exr: not a regular file" diff ${D}/fifo.exr ${D}/ref16.exr)
refused(diff_fifo_ref "fifo.exr: not a regular file" diff ${D}/ref16.exr ${D}/fifo.exr)
refused(diff_dev_zero "/dev/zero: not a regular file" diff ${D}/ref16.exr /dev/zero)
# compare --reference
refused(compare_fifo "fifo.exr: not a regular file" compare --scene ${SCENE} --methods direct --size 16x16
        --out ${D}/cmp --reference ${D}/fifo.exr)
refused(compare_dev_zero "/dev/zero: not a regular file" compare --scene ${SCENE} --methods direct --size 16x16
        --out ${D}/cmp --reference /dev/zero)
# a scene whose environment map is a FIFO
file(COPY ${ROOT}/scenes/cornell_box_coarse.bin DESTINATION ${D}/scene)
file(READ ${SCENE} gltf)
string(JSON gltf SET "${gltf}" scenes 0 extras "{\"gibench\": {\"environment\": {\"uri\": \"env.exr\"}}}")
file(WRITE ${D}/scene/cornell_box_coarse.gltf "${gltf}")
execute_process(COMMAND mkfifo ${D}/scene/env.exr)
refused(env_fifo "environment map 'env.exr'.*not a regular file" info ${D}/scene/cornell_box_coarse.gltf)

# Symbolic links in a scene's folder may not lead out of it: a buffer, an
# environment map or a folder linked to a file outside is refused; a link
# that stays inside is fine.
file(MAKE_DIRECTORY ${D}/outside ${D}/links)
file(COPY ${ROOT}/scenes/cornell_box_coarse.bin DESTINATION ${D}/outside)
file(COPY ${ROOT}/scenes/env/forest.exr DESTINATION ${D}/outside)
file(WRITE ${D}/links/plain.gltf "${gltf}")
string(JSON plain SET "${gltf}" scenes 0 extras "{}")
file(CREATE_LINK ${D}/outside/cornell_box_coarse.bin ${D}/links/cornell_box_coarse.bin SYMBOLIC)
file(WRITE ${D}/links/buffer.gltf "${plain}")
refused(buffer_symlink "/buffers/0/uri: URI 'cornell_box_coarse.bin' leaves the scene directory through a symbolic link"
        info ${D}/links/buffer.gltf)
file(MAKE_DIRECTORY ${D}/links_env)
file(COPY ${ROOT}/scenes/cornell_box_coarse.bin DESTINATION ${D}/links_env)
file(CREATE_LINK ${D}/outside/forest.exr ${D}/links_env/env.exr SYMBOLIC)
file(WRITE ${D}/links_env/env.gltf "${gltf}")
refused(env_symlink "environment/uri: URI 'env.exr' leaves the scene directory through a symbolic link"
        info ${D}/links_env/env.gltf)
file(MAKE_DIRECTORY ${D}/links_dir)
file(CREATE_LINK ${D}/outside ${D}/links_dir/sub SYMBOLIC)
string(JSON subdir SET "${plain}" buffers 0 uri "\"sub/cornell_box_coarse.bin\"")
file(WRITE ${D}/links_dir/dir.gltf "${subdir}")
refused(dir_symlink "URI 'sub/cornell_box_coarse.bin' leaves the scene directory through a symbolic link"
        info ${D}/links_dir/dir.gltf)
# a link that stays inside the folder, reached through a linked scene folder
file(MAKE_DIRECTORY ${D}/inside/data)
file(COPY ${ROOT}/scenes/cornell_box_coarse.bin DESTINATION ${D}/inside/data)
file(CREATE_LINK ${D}/inside/data/cornell_box_coarse.bin ${D}/inside/cornell_box_coarse.bin SYMBOLIC)
file(WRITE ${D}/inside/ok.gltf "${plain}")
file(CREATE_LINK ${D}/inside ${D}/inside_link SYMBOLIC)
foreach(scene ${D}/inside/ok.gltf ${D}/inside_link/ok.gltf)
    execute_process(COMMAND ${GIB} info ${scene} TIMEOUT 10 RESULT_VARIABLE rc OUTPUT_QUIET ERROR_VARIABLE err)
    if(NOT rc STREQUAL "0")
        fail("${scene}: a link inside the scene folder was refused: exit ${rc}: ${err}")
    endif()
endforeach()

if(failures GREATER 0)
    message(FATAL_ERROR "${failures} special file(s) not refused properly")
endif()
message(STATUS "FIFOs and devices are refused as images")
