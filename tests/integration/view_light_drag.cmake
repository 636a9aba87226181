# gibench view --script, a punctual light dragged with the mouse (issue 16):
# under Xvfb, tests/data/valid/lights.gltf with direct at 32x32 (the default
# camera: eye (0, 1.5, 8.366) looking down -Z, yfov pi/4). Key L selects the
# first light (bulb, at (0, 3, 0), which the camera sees at window pixel
# (16, 9.07)); Shift + drag from (16, 9) to (24, 13) moves it in the plane
# facing the camera through it (depth 8.366): a window pixel there is
# 2 x 8.366 x tan(pi/8) / 32 = 0.2166 m, so the bulb goes to
# (8 x 0.2166, 3 - 4 x 0.2166, 0) = (1.733, 2.134, 0), where the camera
# sees it at (24, 13), under the mouse. Checks:
#  - exit 0; the drag picked the light, not an object;
#  - the saved view records bulb_node at (1.733, 2.134, 0) within 5 mm;
#  - the screenshot equals `gibench render --view` of its view within
#    rmse 1e-4 (the tolerance of view_drag), while the same view without the
#    move (the trivial answer: the light where the file has it) is farther
#    than 1e-3 from the batch render;
#  - without a light selected the same Shift + drag moves no light.
# Run by ctest as: cmake -DGIB=... -DROOT=... -DOUT=... -P view_light_drag.cmake
# (labelled unit too: the asan build runs it with LeakSanitizer on).
include(${CMAKE_CURRENT_LIST_DIR}/view_common.cmake)
view_require_xvfb()
set(W ${OUT}/view_light_drag)
file(REMOVE_RECURSE ${W})
file(MAKE_DIRECTORY ${W})
set(SCENE ${ROOT}/tests/data/valid/lights.gltf)
file(WRITE ${W}/light.txt "# select the bulb, drag it, screenshot
wait 1
key L
drag 16 9 24 13 left shift
wait 1
screenshot dragged
")
view_run(${W}/light.txt --scene ${SCENE} --method direct --size 32x32)
if(NOT VIEW_OUT MATCHES "picked light 0 'bulb'[^\n]*move" OR VIEW_OUT MATCHES "picked object")
    message(FATAL_ERROR "Shift + drag with the light selected did not pick the light (and only it):\n${VIEW_OUT}")
endif()
file(READ ${W}/dragged.json lj)
string(JSON n LENGTH "${lj}" nodes)
string(JSON lname GET "${lj}" nodes 0 name)
if(NOT n EQUAL 1 OR NOT lname STREQUAL "bulb_node")
    message(FATAL_ERROR "the saved view moves ${n} nodes, the first ${lname}; expected bulb_node only")
endif()
set(want 1733 2134 0)
set(got "")
foreach(i 0 1 2)
    string(JSON x GET "${lj}" nodes 0 translation ${i})
    milli(xm "${x}")
    list(APPEND got ${xm})
    list(GET want ${i} w)
    math(EXPR d "${xm} - ${w}")
    if(d GREATER 5 OR d LESS -5)
        message(FATAL_ERROR "the dragged light is at ${got}.. mm; expected 1733;2134;0 within 5 mm")
    endif()
endforeach()
view_render_matches(${W}/dragged 1e-4)
set(match ${RENDER_RMSE})
# the trivial answer: the same view with the light where the file has it
string(JSON uj REMOVE "${lj}" nodes)
file(WRITE ${W}/unmoved.json "${uj}")
execute_process(COMMAND ${GIB} -q render --view ${W}/unmoved.json --out ${W}/unmoved.exr RESULT_VARIABLE rc
    ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
    message(FATAL_ERROR "render --view unmoved.json: exit ${rc}\n${err}")
endif()
view_diff(j ${W}/unmoved.exr ${W}/dragged_batch.exr)
string(JSON other GET "${j}" rmse)
if(NOT other GREATER 0.001)
    message(FATAL_ERROR "the unmoved light's image is as close to the batch render (rmse ${other}) as the screenshot"
                        " (${match}): the test cannot tell them apart")
endif()

# No light selected: the same drag picks what is under the mouse (here
# nothing but the far wall of the sky), and no light moves.
file(WRITE ${W}/none.txt "wait 1\ndrag 16 9 24 13 left shift\nwait 1\nsave-view none.json\n")
view_run(${W}/none.txt --scene ${SCENE} --method direct --size 32x32)
file(READ ${W}/none.json nj)
string(FIND "${nj}" "bulb_node" at)
if(VIEW_OUT MATCHES "picked light" OR NOT at EQUAL -1)
    message(FATAL_ERROR "with no light selected, Shift + drag moved the light:\n${VIEW_OUT}\n${nj}")
endif()
message(STATUS "view light drag: bulb at ${got} mm; screenshot vs render --view rmse ${match}, "
               "unmoved light vs render --view rmse ${other}")
