# gibench view --script (issue 16): under Xvfb, a script switches the method,
# orbits the camera with a mouse drag, saves the view and takes a screenshot.
# Checks: exit 0; the method switched; the saved camera moved; a resized
# window renders at its new size; the
# screenshot equals `gibench render --view` of its view (within rmse 1e-4),
# while the screenshot of the first camera is far from it (so that the match
# is not one any image would pass).
# Run by ctest as: cmake -DGIB=... -DROOT=... -DOUT=... -P view_script.cmake
include(${CMAKE_CURRENT_LIST_DIR}/view_common.cmake)
view_require_xvfb()
set(W ${OUT}/view_script)
file(REMOVE_RECURSE ${W})
file(MAKE_DIRECTORY ${W})
file(WRITE ${W}/script.txt "# the start, then: switch method, orbit, save view, screenshot
wait 1
save-view before.json
screenshot before
key M
wait 1
drag 20 20 50 30
wait 2
save-view after.json
screenshot after
method direct
wait 1
key TAB
key PAGE_DOWN
wait 1
screenshot param
resize 48 40
wait 1
screenshot resized
")
view_run(${W}/script.txt --scene ${ROOT}/scenes/cornell_box.gltf --method direct --size 64x64)

foreach(f before.json before.exr before.png after.json after.exr after.png)
    if(NOT EXISTS ${W}/${f})
        message(FATAL_ERROR "the script wrote no ${f}")
    endif()
endforeach()
file(READ ${W}/before.json before)
file(READ ${W}/after.json after)
string(JSON m0 GET "${before}" method)
string(JSON m1 GET "${after}" method)
if(NOT m0 STREQUAL "direct" OR m1 STREQUAL "direct")
    message(FATAL_ERROR "key M did not switch the method: ${m0} then ${m1}")
endif()
# |eye after - eye before| in millimetres
set(d2 0)
foreach(i 0 1 2)
    string(JSON a GET "${before}" camera eye ${i})
    string(JSON b GET "${after}" camera eye ${i})
    milli(am "${a}")
    milli(bm "${b}")
    math(EXPR d2 "${d2} + (${am} - ${bm}) * (${am} - ${bm})")
endforeach()
# the drag orbits by 0.3 rad at several metres: the eye moves by far more than 0.1 m
if(d2 LESS 10000)
    message(FATAL_ERROR "the drag did not move the camera: |d eye|^2 = ${d2} mm^2")
endif()

# The screenshot against the batch render of its saved view ...
view_render_matches(${W}/after 1e-4)
set(match ${RENDER_RMSE})
# ... and the trivial answer, the image of the first view (and method), against it
view_diff(j ${W}/before.exr ${W}/after_batch.exr)
string(JSON other GET "${j}" rmse)
if(NOT other GREATER 0.001)
    message(FATAL_ERROR "the first view's image is as close to the batch render (rmse ${other}) as the screenshot"
                        " (${match}): the test cannot tell them apart")
endif()
message(STATUS "view script: method ${m0} -> ${m1}, eye moved (|d|^2 = ${d2} mm^2), screenshot vs render --view "
               "rmse ${match}, first view vs render --view rmse ${other}")

# Parameter keys: TAB selects direct's second parameter, PAGE_DOWN lowers
# it and rebuilds; the screenshot's view has the new value and render --view
# reproduces it.
file(READ ${W}/param.json pj)
string(JSON p0 GET "${pj}" params 1)
if(NOT p0 STREQUAL "env_samples=13")
    message(FATAL_ERROR "TAB + PAGE_DOWN on direct: params[1] is ${p0}, expected env_samples=13 (16 / 1.25)")
endif()
view_render_matches(${W}/param 1e-4)

# Resizing the window renders again at its size: the screenshot after
# "resize 48 40" is 48x40 and render --view reproduces it.
file(READ ${W}/resized.json rj)
string(JSON rw GET "${rj}" width)
string(JSON rh GET "${rj}" height)
if(NOT rw EQUAL 48 OR NOT rh EQUAL 40)
    message(FATAL_ERROR "after resize 48 40 the view is ${rw}x${rh}")
endif()
view_render_matches(${W}/resized 1e-4)

# Bad input: one line and exit 2 (a malformed script line names its line;
# a broken view file names what is wrong).
file(WRITE ${W}/bad_script.txt "wait 1\nkey NOSUCHKEY\n")
execute_process(COMMAND ${XVFB_RUN} -a ${GIB} view --script ${W}/bad_script.txt --scene ${ROOT}/scenes/cornell_box_coarse.gltf
        --method direct --size 32x32
    RESULT_VARIABLE rc ERROR_VARIABLE err OUTPUT_QUIET TIMEOUT 120)
if(NOT rc EQUAL 2 OR NOT err MATCHES "bad_script.txt:2: key")
    message(FATAL_ERROR "a malformed script line: exit ${rc}, expected 2 naming line 2\n${err}")
endif()
file(WRITE ${W}/bad_view.json "{\"gibench_view\": 1, \"scene\": \"x.gltf\"}")
execute_process(COMMAND ${GIB} render --view ${W}/bad_view.json --out ${W}/bad.exr RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 2 OR NOT err MATCHES "missing or bad method")
    message(FATAL_ERROR "render --view of a broken view: exit ${rc}, expected 2 naming the method\n${err}")
endif()
execute_process(COMMAND ${GIB} render --view ${W}/after.json --camera "#0" --out ${W}/bad.exr RESULT_VARIABLE rc
    ERROR_VARIABLE err)
if(NOT rc EQUAL 2)
    message(FATAL_ERROR "render --view with --camera: exit ${rc}, expected 2\n${err}")
endif()
