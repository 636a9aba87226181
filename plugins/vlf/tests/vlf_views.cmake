# Render time independent of the view (paper §4, §6; issue 12): vlf on the
# glossy Cornell box at 128x128 from four cameras in one run — the scene's
# camera, a close-up of the mirror block (three tile lookups a pixel), one
# of the red wall alone (diffuse: one atlas read a pixel) and one from
# above onto the glossy block — 12 frames each after 2 warm-up frames (the
# field is propagated once and taken from the cache after). Prints each
# view's median frame time and the ratio max / min, which must stay under
# 3 (a generous bound: llvmpipe on a loaded 2-core machine); each view's
# image must show the box (mean luminance > 0.01) and differ from the
# others (the views are really different).
# Run by ctest as: cmake -DGIB=... -DSCENES=... -DOUT=... -P vlf_views.cmake

set(W ${OUT}/vlf_views)
file(REMOVE_RECURSE ${W})
file(MAKE_DIRECTORY ${W})
set(SCENE ${SCENES}/cornell_glossy.gltf)
function(write_view name eye forward)
    file(WRITE ${W}/${name}.json "{\"gibench_view\": 1, \"scene\": \"${SCENE}\", \"method\": \"vlf\", \"params\": [],
  \"width\": 128, \"height\": 128, \"frames\": 1, \"seed\": 1, \"time\": 0, \"exposure\": 0,
  \"camera\": {\"eye\": [${eye}], \"forward\": [${forward}], \"up\": [0, 1, 0], \"yfov\": 0.8,
              \"znear\": 0.01, \"zfar\": 100}, \"nodes\": []}")
endfunction()
write_view(mirror "1.6, 2.0, 0.6" "0.45, -0.1, 0.6")
write_view(red_wall "3.0, 2.7, 1.2" "1, 0, 0.1")
write_view(above "2.2, 5.0, 0.8" "0, -1, 0.35")

set(min 1e30)
set(max 0)
set(report "")
set(images "")
foreach(cam scene mirror red_wall above)
    set(args --scene ${SCENE} --method vlf --size 128x128 --frames 14 --warmup 2 --timings ${W}/${cam}.timings.json
             --out ${W}/${cam}.exr)
    if(NOT cam STREQUAL "scene")
        list(APPEND args --camera view:${W}/${cam}.json)
    endif()
    execute_process(COMMAND ${GIB} -q render ${args} RESULT_VARIABLE rc ERROR_VARIABLE err)
    if(NOT rc EQUAL 0)
        message(FATAL_ERROR "render ${args}: exit ${rc}\n${err}")
    endif()
    file(READ ${W}/${cam}.timings.json j)
    string(JSON ms GET "${j}" render render median_ms)
    string(JSON renderer GET "${j}" gl_renderer)
    execute_process(COMMAND ${GIB} diff --black ${W}/${cam}.exr --json RESULT_VARIABLE rc OUTPUT_VARIABLE dj)
    if(NOT rc EQUAL 0)
        message(FATAL_ERROR "gibench diff --black ${W}/${cam}.exr failed (${rc})")
    endif()
    string(JSON lum GET "${dj}" mean_lum_ref)
    if(NOT lum GREATER 0.01)
        message(FATAL_ERROR "view ${cam}: mean luminance ${lum}: the box is not in view")
    endif()
    foreach(other ${images})
        execute_process(COMMAND ${GIB} diff ${W}/${cam}.exr ${other} --json RESULT_VARIABLE rc OUTPUT_VARIABLE dj)
        string(JSON rmse GET "${dj}" rmse)
        if(NOT rc EQUAL 0 OR NOT rmse GREATER 0.01)
            message(FATAL_ERROR "view ${cam}: the same image as ${other} (rmse ${rmse})")
        endif()
    endforeach()
    list(APPEND images ${W}/${cam}.exr)
    string(APPEND report " ${cam} ${ms} ms (mean luminance ${lum});")
    if(ms LESS min)
        set(min ${ms})
    endif()
    if(ms GREATER max)
        set(max ${ms})
    endif()
endforeach()
# the ratio in thousandths (CMake's math is integer only): the times in microseconds
foreach(v max min)
    string(REGEX MATCH "^([0-9]+)(\\.([0-9]*))?" m ${${v}})
    set(i ${CMAKE_MATCH_1})
    set(fr "${CMAKE_MATCH_3}000")
    string(SUBSTRING ${fr} 0 3 fr)
    math(EXPR ${v}_us "${i} * 1000 + 1${fr} - 1000")
endforeach()
math(EXPR ratio_milli "${max_us} * 1000 / ${min_us}")
math(EXPR r_int "${ratio_milli} / 1000")
math(EXPR r_frac "${ratio_milli} % 1000")
string(LENGTH "${r_frac}" n)
if(n EQUAL 1)
    set(r_frac "00${r_frac}")
elseif(n EQUAL 2)
    set(r_frac "0${r_frac}")
endif()
message(STATUS "vlf frame time by view (glossy Cornell box, 128x128, median of 12 frames, ${renderer}):${report} "
               "max / min = ${r_int}.${r_frac}")
if(NOT ratio_milli LESS 3000)
    message(FATAL_ERROR "vlf frame time depends on the view: max / min = ${r_int}.${r_frac} (bound 3)")
endif()
