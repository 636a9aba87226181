# compare refuses bad input before anything runs: exit 2, one line, and
# not even the output directory is made (no reference rendered, no child
# started). No GL needed; the asan preset runs it too.
# cmake -DGIB=... -DROOT=... -DOUT=... -P compare_strict.cmake
set(failures 0)
include(${CMAKE_CURRENT_LIST_DIR}/expect.cmake)
set(D ${OUT}/compare_strict)
file(REMOVE_RECURSE ${D})
file(MAKE_DIRECTORY ${D})
set(SCENE ${ROOT}/scenes/cornell_box_coarse.gltf)
# a 16x16 image to stand as a reference of the wrong size
execute_process(COMMAND ${GIB} reference --scene ${SCENE} --size 16x16 --spp 1 --out ${D}/ref16.exr
                RESULT_VARIABLE rc OUTPUT_QUIET ERROR_QUIET)
if(NOT rc EQUAL 0)
    message(FATAL_ERROR "could not make the 16x16 reference")
endif()

# refuse(<name> <regex> <args...>)
function(refuse name regex)
    execute_process(COMMAND ${GIB} compare --scene ${SCENE} --out ${D}/${name} ${ARGN} TIMEOUT 120
                    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
    string(STRIP "${err}" err)
    string(REGEX MATCHALL "\n" lines "${err}")
    list(LENGTH lines extra)
    if(NOT rc STREQUAL "2" OR extra GREATER 0 OR NOT err MATCHES "${regex}" OR EXISTS ${D}/${name})
        message(SEND_ERROR "${name}: expected exit 2, one line matching '${regex}' and no output; got exit ${rc}\n${err}")
        math(EXPR f "${failures} + 1")
        set(failures ${f} PARENT_SCOPE)
    endif()
endfunction()

# (an empty argument cannot pass through ARGN: this one is spelled out)
execute_process(COMMAND ${GIB} compare --scene ${SCENE} --out ${D}/empty_methods --methods "" TIMEOUT 120
                RESULT_VARIABLE rc OUTPUT_QUIET ERROR_VARIABLE err)
if(NOT rc STREQUAL "2" OR NOT err MATCHES "--methods '' has an empty method name" OR EXISTS ${D}/empty_methods)
    fail("--methods \"\": expected exit 2 and 'has an empty method name'; got exit ${rc}: ${err}")
endif()
refuse(empty_in_list "has an empty method name" --methods "direct,")
refuse(twice "--methods names 'direct' twice" --methods "direct,direct")
# an unknown method: the line lists the installed ones, as render's does
refuse(unknown_method "no method 'nope' \\(installed: [^)]*direct" --methods "direct,nope")
# --camera view:FILE (a view saved by gibench view) is taken as render,
# reference and studies take it: past the camera check, the next fault is
# the parameter's; a view that cannot be read is refused in one line
file(WRITE ${D}/view.json "{\"gibench_view\": 1, \"scene\": \"${SCENE}\", \"method\": \"direct\", \"params\": [],
  \"width\": 32, \"height\": 32, \"frames\": 1, \"seed\": 1, \"time\": 0, \"exposure\": 0,
  \"camera\": {\"eye\": [0, 1, 3.5], \"forward\": [0, 0, -1], \"up\": [0, 1, 0], \"yfov\": 0.7,
              \"znear\": 0.01, \"zfar\": 100}, \"nodes\": []}")
refuse(view_camera "--param direct: unknown parameter 'foo'" --methods direct
       --camera view:${D}/view.json --param direct.foo=1)
refuse(view_missing "compare: --camera .*none\\.json" --methods direct --camera view:${D}/none.json)
refuse(unknown_param "--param direct: unknown parameter 'foo'" --methods direct --param direct.foo=1)
refuse(param_range "light_samples=0 is outside" --methods direct --param direct.light_samples=0)
refuse(missing_reference "--reference ${D}/none.exr" --methods direct --reference ${D}/none.exr)
refuse(wrong_size_reference "is 16x16, the comparison is 32x32" --methods direct --size 32x32
       --reference ${D}/ref16.exr)

if(failures GREATER 0)
    message(FATAL_ERROR "${failures} bad compare command(s) not refused properly")
endif()
message(STATUS "bad compare input is refused before anything runs")
