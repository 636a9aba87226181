# gibench view --script, a method that cannot follow a change (issue 16: "a
# method whose caps cannot follow the change says so on screen instead of
# showing stale light"). Under Xvfb, with the fake method fake_baked
# (tests/unit/fake_plugin.c, FAKE_BAKED; GIBENCH_PLUGIN_PATH=${FAKES}): it
# renders a constant grey (0.5), its caps lack GI_CAP_RIGID_MOTION, and its
# update() refuses moved lights ("lights are baked at prepare").
#  1. Cornell box, 64x64, overlay off (key O): Shift + drag the short block.
#     The viewer must print once "fake_baked cannot follow moving objects (no
#     GI_CAP_RIGID_MOTION): no image" (the overlay's message, on stderr too),
#     show black where it showed grey (window shots before and after, rmse
#     against black > 0.4 and = 0), refuse the screenshot of the stale
#     image (no after.exr, a warning), and still record the move in the
#     saved view.
#  2. lights.gltf, 32x32: key L, Shift + drag the bulb (the mouse light
#     drag): update() refuses, the viewer says "fake_baked cannot follow
#     the move (unsupported: lights are baked at prepare): no image" and
#     shows black.
# Run by ctest as: cmake -DGIB=... -DROOT=... -DOUT=... -DFAKES=... -P view_stale.cmake
# (labelled unit too: the asan build runs it with LeakSanitizer on).
include(${CMAKE_CURRENT_LIST_DIR}/view_common.cmake)
view_require_xvfb()
if(NOT EXISTS ${FAKES})
    message(FATAL_ERROR "no fake plugin folder ${FAKES} (the tests' build makes gimethod_fake_baked)")
endif()
set(ENV{GIBENCH_PLUGIN_PATH} ${FAKES})
set(W ${OUT}/view_stale)
file(REMOVE_RECURSE ${W})
file(MAKE_DIRECTORY ${W})

# black_rmse(<out var> <image>): the image's rmse against a black one
function(black_rmse outvar img)
    execute_process(COMMAND ${GIB} diff --black ${img} --json RESULT_VARIABLE rc OUTPUT_VARIABLE j ERROR_VARIABLE err)
    if(NOT rc EQUAL 0)
        message(FATAL_ERROR "gibench diff --black ${img}: exit ${rc}\n${err}")
    endif()
    string(JSON r GET "${j}" rmse)
    set(${outvar} ${r} PARENT_SCOPE)
endfunction()

# 1. an object moved under a method without GI_CAP_RIGID_MOTION
file(WRITE ${W}/object.txt "wait 1
key O
window-shot before.png
screenshot before
drag 40 48 50 48 left shift
wait 1
window-shot after.png
screenshot after
save-view after.json
")
view_run(${W}/object.txt --scene ${ROOT}/scenes/cornell_box.gltf --method fake_baked --size 64x64)
set(msg "view: fake_baked cannot follow moving objects \\(no GI_CAP_RIGID_MOTION\\): no image")
string(REGEX MATCHALL "${msg}" said "${VIEW_ERR}")
list(LENGTH said nsaid)
if(NOT VIEW_OUT MATCHES "picked object 1 'short_block'" OR NOT nsaid EQUAL 1)
    message(FATAL_ERROR "the drag of the short block under fake_baked did not say once that it cannot follow "
                        "(${nsaid} times):\n${VIEW_OUT}\n${VIEW_ERR}")
endif()
if(NOT EXISTS ${W}/before.exr OR EXISTS ${W}/after.exr OR NOT VIEW_ERR MATCHES "no screenshot after: fake_baked")
    message(FATAL_ERROR "the screenshot of the stale method was not refused (or the one before was not taken):\n"
                        "${VIEW_ERR}")
endif()
black_rmse(before ${W}/before.png)
black_rmse(after ${W}/after.png)
if(NOT before GREATER 0.4 OR NOT after EQUAL 0)
    message(FATAL_ERROR "the window against black: rmse ${before} before the move (expected the grey, > 0.4) and "
                        "${after} after (expected 0: no stale image)")
endif()
file(READ ${W}/after.json aj)
string(JSON aname GET "${aj}" nodes 0 name)
if(NOT aname STREQUAL "short_block")
    message(FATAL_ERROR "the saved view does not record the move of short_block (${aname})")
endif()

# 2. a light dragged with the mouse under a method whose update() refuses it
file(WRITE ${W}/light.txt "wait 1
key O
window-shot lbefore.png
key L
drag 16 9 24 13 left shift
wait 1
window-shot lafter.png
screenshot lafter
")
view_run(${W}/light.txt --scene ${ROOT}/tests/data/valid/lights.gltf --method fake_baked --size 32x32)
set(lmsg "view: fake_baked cannot follow the move \\(unsupported: lights are baked at prepare\\): no image")
string(REGEX MATCHALL "${lmsg}" lsaid "${VIEW_ERR}")
list(LENGTH lsaid nlsaid)
if(NOT VIEW_OUT MATCHES "picked light 0 'bulb'" OR NOT nlsaid EQUAL 1 OR EXISTS ${W}/lafter.exr)
    message(FATAL_ERROR "the light drag under fake_baked did not say once that it cannot follow (${nlsaid} times), "
                        "or a screenshot of it was written:\n${VIEW_OUT}\n${VIEW_ERR}")
endif()
black_rmse(lbefore ${W}/lbefore.png)
black_rmse(lafter ${W}/lafter.png)
if(NOT lbefore GREATER 0.4 OR NOT lafter EQUAL 0)
    message(FATAL_ERROR "the window against black: rmse ${lbefore} before the light move and ${lafter} after "
                        "(expected > 0.4 and 0)")
endif()
message(STATUS "view stale: object and light moves under fake_baked said so once each; window rmse against black "
               "${before} -> ${after} (object), ${lbefore} -> ${lafter} (light)")
