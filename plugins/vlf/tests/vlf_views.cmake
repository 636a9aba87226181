# Render time independent of the view (paper §4, §6; issue 12): vlf on the
# glossy Cornell box at 128x128 from four cameras in one run — the scene's
# camera, a close-up of the mirror block (three tile lookups a pixel), one
# of the red wall alone (diffuse: one atlas read a pixel) and one from
# above onto the glossy block — in two interleaved rounds of 8 frames
# after 2 warm-up frames each (the field is propagated once and taken from
# the cache after). Prints each view's fastest frame time over the rounds
# and its medians, and the ratio max / min of the fastest frames (the least
# disturbed by other work on a shared machine: medians moved by 2x between
# runs at load 5). It must stay under 4: measured 2.0-2.5 here (pixels of
# glossy and mirror faces read three tiles each, diffuse ones one atlas
# texel, so a view of one diffuse wall renders fastest), with a margin for
# a loaded 2-core machine. Each view's
# image must show the box (mean luminance > 0.01) and differ from the
# others (the views are really different).
# Two rounds (three until issue 29): 16 frames a view give its fastest
# frame as well, and CI time was needed for the raster test's new run.
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

set(views scene mirror red_wall above)
set(images "")
foreach(cam ${views})
    set(fast_${cam} 1e30)
endforeach()
# two rounds over the four views, interleaved, so that a change of the
# machine's load touches every view alike; each view's fastest frame over
# the rounds
foreach(round 1 2)
    foreach(cam ${views})
        # l = 128, not the default 512: the frame time read here does not depend on l, the propagation does (speed)
        set(args --scene ${SCENE} --method vlf --param l=128 --size 128x128 --frames 10 --warmup 2
                 --timings ${W}/${cam}.timings.json --out ${W}/${cam}.exr)
        if(NOT cam STREQUAL "scene")
            list(APPEND args --camera view:${W}/${cam}.json)
        endif()
        execute_process(COMMAND ${GIB} -q render ${args} RESULT_VARIABLE rc ERROR_VARIABLE err)
        if(NOT rc EQUAL 0)
            message(FATAL_ERROR "render ${args}: exit ${rc}\n${err}")
        endif()
        file(READ ${W}/${cam}.timings.json j)
        string(JSON ms GET "${j}" render render min_ms)
        string(JSON med_${cam}_${round} GET "${j}" render render median_ms)
        string(JSON renderer GET "${j}" gl_renderer)
        if(ms LESS fast_${cam})
            set(fast_${cam} ${ms})
        endif()
        if(NOT round EQUAL 1)
            continue()
        endif()
        execute_process(COMMAND ${GIB} diff --black ${W}/${cam}.exr --json RESULT_VARIABLE rc OUTPUT_VARIABLE dj)
        if(NOT rc EQUAL 0)
            message(FATAL_ERROR "gibench diff --black ${W}/${cam}.exr failed (${rc})")
        endif()
        string(JSON lum_${cam} GET "${dj}" mean_lum_ref)
        if(NOT lum_${cam} GREATER 0.01)
            message(FATAL_ERROR "view ${cam}: mean luminance ${lum_${cam}}: the box is not in view")
        endif()
        foreach(other ${images})
            execute_process(COMMAND ${GIB} diff ${W}/${cam}.exr ${other} --json RESULT_VARIABLE rc OUTPUT_VARIABLE dj)
            string(JSON rmse GET "${dj}" rmse)
            if(NOT rc EQUAL 0 OR NOT rmse GREATER 0.01)
                message(FATAL_ERROR "view ${cam}: the same image as ${other} (rmse ${rmse})")
            endif()
        endforeach()
        file(COPY_FILE ${W}/${cam}.exr ${W}/${cam}_first.exr)
        list(APPEND images ${W}/${cam}_first.exr)
    endforeach()
endforeach()
set(min 1e30)
set(max 0)
set(report "")
foreach(cam ${views})
    string(APPEND report " ${cam} fastest ${fast_${cam}} ms, medians ${med_${cam}_1} / ${med_${cam}_2} ms"
                         " (mean luminance ${lum_${cam}});")
    if(fast_${cam} LESS min)
        set(min ${fast_${cam}})
    endif()
    if(fast_${cam} GREATER max)
        set(max ${fast_${cam}})
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
message(STATUS "vlf frame time by view (glossy Cornell box, 128x128, 2 rounds of 8 frames, ${renderer}):${report} "
               "fastest frames max / min = ${r_int}.${r_frac}")
if(NOT ratio_milli LESS 4000)
    message(FATAL_ERROR "vlf frame time depends on the view: max / min = ${r_int}.${r_frac} (bound 4)")
endif()
