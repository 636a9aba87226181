# The gibench command-line contract: exit 0 / 1 / 2 with a one-line reason.
# Run by ctest as: cmake -DGIB=... -DSCENES=... -DDATA=... -DOUT=... -P cli_test.cmake

set(failures 0)

include(${CMAKE_CURRENT_LIST_DIR}/expect.cmake)

expect(0 "direct" methods)
expect(0 "\"id\": \"direct\"" methods --json)
expect(0 "light_samples" methods)
# A quality knob's steps (methods --json) are the values the held-out sweep runs: each a
# new value, none past the range repeated (vlf's l = 512 of [8, 1024] has one step, 1024).
execute_process(COMMAND ${GIB} methods --json RESULT_VARIABLE rc OUTPUT_VARIABLE mj)
string(JSON nm LENGTH "${mj}")
math(EXPR nm "${nm} - 1")
foreach(i RANGE ${nm})
    string(JSON id GET "${mj}" ${i} id)
    string(JSON np LENGTH "${mj}" ${i} params)
    math(EXPR np "${np} - 1")
    foreach(k RANGE ${np})
        string(JSON q ERROR_VARIABLE none GET "${mj}" ${i} params ${k} quality steps)
        if(NOT none STREQUAL "NOTFOUND")
            continue()
        endif()
        string(JSON prev GET "${mj}" ${i} params ${k} default)
        string(JSON ns LENGTH "${q}")
        if(ns EQUAL 0) # a knob marked as not converging (GI_QUALITY_NONE): no steps
            continue()
        endif()
        math(EXPR ns "${ns} - 1")
        foreach(s RANGE ${ns})
            string(JSON v GET "${q}" ${s})
            if(v VERSION_EQUAL prev OR v STREQUAL prev) # "1024.0" and the default "1024" alike
                string(JSON name GET "${mj}" ${i} params ${k} name)
                fail("methods --json: ${id} ${name}: step ${s} repeats ${prev} (steps ${q})")
            endif()
            set(prev ${v})
        endforeach()
    endforeach()
endforeach()
expect(0 "13264 triangles" info ${SCENES}/cornell_box.gltf)
expect(0 "\"triangles\": 13264" info ${SCENES}/cornell_box.gltf --json)
expect(0 "environment" info ${SCENES}/bunny_env.glb)
expect(2 "unknown command 'frobnicate'" frobnicate)
expect(2 "info: no scene given" info)
expect(2 "no-such-file.gltf" info ${OUT}/no-such-file.gltf)
expect(2 "render: --scene is required" render --method direct --out ${OUT}/x.exr)
expect(2 "render: --size '0x4'" render --scene ${SCENES}/cornell_box.gltf --method direct --size 0x4 --out ${OUT}/x.exr)
expect(2 "render: --out '${OUT}/x.bmp': use a .exr, .pfm or .png" render --scene ${SCENES}/cornell_box.gltf --method direct --out ${OUT}/x.bmp)
expect(2 "render: no method 'nope' (installed: " render --scene ${SCENES}/cornell_box.gltf --method nope --out ${OUT}/x.exr)
expect(2 "direct: unknown parameter 'bogus'" render --scene ${SCENES}/cornell_box.gltf --method direct --param bogus=1 --out ${OUT}/x.exr)
expect(2 "direct: light_samples=0 is outside" render --scene ${SCENES}/cornell_box.gltf --method direct --param light_samples=0 --out ${OUT}/x.exr)
expect(2 "has no camera 'nope'" render --scene ${SCENES}/cornell_box.gltf --method direct --camera nope --out ${OUT}/x.exr)
expect(2 "render: --frames 'many'" render --scene ${SCENES}/cornell_box.gltf --method direct --frames many --out ${OUT}/x.exr)
expect(2 "render: unknown argument '--fast'" render --fast)
# A malformed scene is bad input (2), with the loader's message.
file(GLOB malformed ${DATA}/malformed/*.gltf)
list(GET malformed 0 one_bad)
expect(2 ": /" render --scene ${one_bad} --method direct --out ${OUT}/x.exr)
# An output directory that does not exist is a run-time failure (1).
expect(1 "${OUT}/missing-dir/x.exr" render --scene ${SCENES}/cornell_box_coarse.gltf --method direct --size 8x8 --out ${OUT}/missing-dir/x.exr)
# Every scene renders with the direct baseline and gives a finite image.
set(STRESS_SCENES stress/two_rooms_thin.gltf stress/two_rooms_thick.gltf stress/light_in_hull.gltf
    stress/hulls_overlap.gltf stress/glossy.gltf stress/moving_light.gltf stress/moving_camera.gltf
    stress/scale_t00116.gltf stress/scale_t57090.gltf)
foreach(scene cornell_box_coarse.gltf cornell_glossy.gltf bunny_env.glb teapot_plane.glb teapot_area.glb u_room.gltf cornell_moving.gltf
              ${STRESS_SCENES})
    string(REPLACE "/" "_" tag "${scene}")
    expect(0 "" render --scene ${SCENES}/${scene} --method direct --size 32x32 --frames 2 --out ${OUT}/all_${tag}.exr --timings ${OUT}/all_${tag}.json)
    file(READ ${OUT}/all_${tag}.json j)
    if(NOT j MATCHES "\"nonfinite_pixels\": 0")
        message(SEND_ERROR "${scene}: non-finite pixels in the direct render")
        math(EXPR failures "${failures} + 1")
    endif()
endforeach()
# A render on a scene its caps do not cover runs, warning with what is left out.
expect(0 "warning: render: avg does not handle environment light in " render --scene ${SCENES}/bunny_env.glb --method avg --size 16x16 --param vpls=16 --out ${OUT}/avg_env.exr)
expect(0 "warning: render: csm does not handle deforming meshes" render --scene ${SCENES}/cornell_deform.gltf --method csm --size 16x16 --param N=2 --param M=8 --param M_local=8 --param N_local=1 --out ${OUT}/csm_deform.exr)
# An animated render advances time and calls update.
expect(0 "" render --scene ${SCENES}/cornell_moving.gltf --method direct --size 32x32 --frames 3 --animate 2 --out ${OUT}/moving.png)
foreach(sc moving_light moving_camera hulls_overlap)
    expect(0 "" render --scene ${SCENES}/stress/${sc}.gltf --method direct --size 32x32 --frames 3 --animate 2 --out ${OUT}/${sc}.png)
endforeach()

# Plugins are also found on GIBENCH_PLUGIN_PATH; broken ones are refused
# with a warning naming the file and the reason, and the rest still load.
set(ENV{GIBENCH_PLUGIN_PATH} "${FAKE_PLUGINS}")
expect(0 "fake_good" methods)
expect(0 "plugin refused: ${FAKE_PLUGINS}/gimethod_fake_missing_fn.so: method 'fake_missing_fn' lacks the required function render()" methods)
expect(0 "direct" methods)
unset(ENV{GIBENCH_PLUGIN_PATH})

if(failures GREATER 0)
    message(FATAL_ERROR "${failures} command-line expectation(s) failed")
endif()
message(STATUS "all command-line expectations met")
