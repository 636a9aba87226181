# gibench view's panels, zoom, live error and two-method split (issue 33),
# in one scripted session under Xvfb (64x64 image, the panels right of it).
# Checks:
#  1. the panels are shown beside the image, not over it: the window is the
#     image plus the panels' width, and its image region equals the batch
#     render of the same view (`gibench render --view`) to 1/255;
#  2. zoom: after "zoom 4 32 32" the region shows batch pixel (24 + x/4,
#     24 + y/4) at window pixel (x, y), and the read-out under the mouse is
#     that of the expected pixel;
#  3. a split between direct and a second method (csm): the left of the
#     divider is direct's batch render, the right csm's;
#  4. the live relMSE: lower at a later reference pass than at the first,
#     and the same number `gibench diff` gives for the pair it was taken of.
# Run by ctest as: cmake -DGIB=... -DROOT=... -DOUT=... -DPYTHON=... -P view_panels.cmake
include(${CMAKE_CURRENT_LIST_DIR}/view_common.cmake)
view_require_xvfb()
if(NOT PYTHON)
    message(STATUS "SKIPPED: no python3 for the pixel checks")
    return()
endif()
set(W ${OUT}/view_panels)
file(REMOVE_RECURSE ${W})
file(MAKE_DIRECTORY ${W})
set(SCENE ${ROOT}/scenes/cornell_box_coarse.gltf)
# accumulate=false: every frame of direct is the same image, so that the
# window and the batch render of one frame can be compared
file(WRITE ${W}/script.txt "wait 1
screenshot shot
window-shot full.png
window-shot region.png image
zoom 4 32 32
move 40 24
window-shot zoomed.png image
print-state
zoom 0.25 32 32
move 34 30
print-state
move 40 24
print-state
split2 csm
wait 1
window-shot split.png image
print-state
split2 none
key LEFT
wait-spp 1
print-state early
wait-spp 128
print-state late
")
view_run(${W}/script.txt --scene ${SCENE} --method direct --param accumulate=false --size 64x64
    --panels on)
string(REGEX MATCHALL "state: [^\n]*" states "${VIEW_OUT}")
list(LENGTH states n)
if(NOT n EQUAL 6)
    message(FATAL_ERROR "expected 6 state lines, got ${n}:\n${VIEW_OUT}")
endif()

function(state_field outvar line key)
    if(NOT line MATCHES " ${key}=([^ ]*)")
        message(FATAL_ERROR "no ${key}= in: ${line}")
    endif()
    set(${outvar} "${CMAKE_MATCH_1}" PARENT_SCOPE)
endfunction()

function(check_png what)
    execute_process(COMMAND ${PYTHON} ${CMAKE_CURRENT_LIST_DIR}/view_png.py ${ARGN}
        RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
    if(NOT rc EQUAL 0)
        message(FATAL_ERROR "${what}: ${out}${err}")
    endif()
    message(STATUS "${what}: ${out}")
endfunction()

# 1. the panels beside the image: the window 64 + 340 wide, its image region the batch render
file(READ ${W}/full.png hdr OFFSET 16 LIMIT 8 HEX)
string(SUBSTRING "${hdr}" 0 8 whex)
math(EXPR ww "0x${whex}")
if(NOT ww EQUAL 404)
    message(FATAL_ERROR "the window with panels is ${ww} wide, expected 64 + 340")
endif()
list(GET states 0 sz)
state_field(region "${sz}" region)
state_field(panels "${sz}" panels)
if(NOT region STREQUAL "64x64" OR NOT panels STREQUAL "1")
    message(FATAL_ERROR "panels ${panels}, image region ${region}: expected 1, 64x64")
endif()
execute_process(COMMAND ${GIB} -q render --view ${W}/shot.json --out ${W}/batch.png
    RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
    message(FATAL_ERROR "gibench render --view shot.json: exit ${rc}\n${err}")
endif()
check_png("the image region against the batch render" same ${W}/region.png ${W}/batch.png)

# 2. zoom: 4x about (32, 32) puts image pixel 24 + x/4 at window pixel x
check_png("zoom 4" zoom ${W}/zoomed.png ${W}/batch.png 4 24 24)
list(GET states 1 s1)
list(GET states 2 sf)
state_field(cz "${sz}" cursor)
state_field(pz "${sz}" pixel_method)
state_field(p1 "${s1}" pixel_method)
state_field(pf "${sf}" pixel_method)
if(NOT cz STREQUAL "34,30" OR NOT pz STREQUAL p1 OR pz STREQUAL pf)
    message(FATAL_ERROR "the read-out at window (40, 24) zoomed 4x about (32, 32): pixel ${cz} = ${pz}; "
                        "expected pixel 34,30 = ${p1} (unzoomed, the pixel there is ${pf})")
endif()

# 3. the split: direct left of the divider (column 32), csm right of it
list(GET states 3 s3)
state_field(m2 "${s3}" method2)
state_field(sp "${s3}" split)
if(NOT m2 STREQUAL "csm" OR NOT sp STREQUAL "3")
    message(FATAL_ERROR "after split2 csm: method2 ${m2}, split ${sp}")
endif()
file(READ ${W}/shot.json shot_json)
string(JSON csm_view SET "${shot_json}" method "\"csm\"")
string(JSON csm_view SET "${csm_view}" params "[]")
state_field(f2 "${s3}" frame2) # the frames csm accumulated in the window
string(JSON csm_view SET "${csm_view}" frames "${f2}")
file(WRITE ${W}/csm.json "${csm_view}")
execute_process(COMMAND ${GIB} -q render --view ${W}/csm.json --out ${W}/csm.png
    RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
    message(FATAL_ERROR "gibench render --view csm.json: exit ${rc}\n${err}")
endif()
check_png("split direct | csm" split ${W}/split.png ${W}/batch.png ${W}/csm.png 31 34)

# 4. the live relMSE (after a camera step restarted the reference): lower at
# the later reference pass, and the number gibench diff gives for the pair
list(GET states 4 s4)
list(GET states 5 s5)
state_field(spp0 "${s4}" spp)
state_field(e0 "${s4}" relmse)
state_field(spp1 "${s5}" spp)
state_field(e1 "${s5}" relmse)
math(EXPR twice "2 * ${spp0}")
if(spp1 LESS twice)
    message(FATAL_ERROR "the reference had ${spp0} spp at the first state and ${spp1} at the second: "
                        "too close to compare")
endif()
if(NOT e1 LESS e0)
    message(FATAL_ERROR "the live relMSE did not fall as the reference converged: ${e0} at ${spp0} spp, "
                        "${e1} at ${spp1} spp")
endif()
foreach(p early late)
    if(p STREQUAL "early")
        set(e ${e0})
    else()
        set(e ${e1})
    endif()
    view_diff(j ${W}/${p}_method.exr ${W}/${p}_ref.exr)
    string(JSON d GET "${j}" relmse)
    check_png("relMSE ${p}: the viewer's against gibench diff's" close ${e} ${d} 1e-6)
endforeach()
message(STATUS "live relMSE ${e0} at ${spp0} spp, ${e1} at ${spp1} spp (gibench diff agrees)")
