# A study names a saved view as its camera (issue 16): "camera":
# "view:FILE.json" takes the view's camera and its moved objects (not its
# method, size or parameters). A tiny study (Cornell box, 16x16, direct, a
# 4 spp reference) with a hand-written view whose camera is off the scene's
# and whose short block is moved and turned. Checks:
#  - the run's image equals `gibench render --camera view:FILE` (rmse <= 1e-6),
#    and is far (rmse > 1e-3) from the scene camera's image (the trivial answer);
#  - the study's bounce-matched reference is closer to the run's image than
#    to the scene camera's (its camera is the view's too);
#  - the view's content is part of the run's identity: an edited view under
#    the same name makes another run id (--dry-run);
#  - a missing view file or one moving a node the scene lacks: exit 2, one
#    line naming /camera.
# Needs no window: the view file is written here.
# cmake -DGIB=... -DROOT=... -DOUT=... -P view_study.cmake
include(${CMAKE_CURRENT_LIST_DIR}/view_common.cmake)
set(W ${OUT}/view_study)
file(REMOVE_RECURSE ${W})
file(MAKE_DIRECTORY ${W})
set(SCENE ${ROOT}/scenes/cornell_box_coarse.gltf)
function(write_view path tx name)
    file(WRITE ${path} "{\"gibench_view\": 1, \"scene\": \"${SCENE}\", \"method\": \"csm\", \"params\": [\"N=8\"],
  \"width\": 64, \"height\": 64, \"frames\": 3, \"seed\": 7, \"time\": 0, \"exposure\": 1,
  \"camera\": {\"eye\": [4.5, 3.5, -6.0], \"forward\": [-0.25, -0.1, 1.0], \"up\": [0, 1, 0], \"yfov\": 0.7,
              \"znear\": 0.01, \"zfar\": 100},
  \"nodes\": [{\"node\": 1, \"name\": \"${name}\", \"translation\": [${tx}, 0.0, 1.69],
              \"rotation\": [0, 0.2588190451, 0, 0.9659258263], \"scale\": [1, 1, 1]}]}")
endfunction()
write_view(${W}/v.json 1.2 short_block)
function(write_study path camera)
    file(WRITE ${path} "{\"name\": \"vs\", \"scenes\": [\"${SCENE}\"], \"size\": [16, 16], \"frames\": 1, \"warmup\": 0,
  \"camera\": \"${camera}\", \"reference\": {\"spp\": 4, \"max_bounces\": 2}, \"methods\": [{\"method\": \"direct\"}]}")
endfunction()
write_study(${W}/s.json "view:${W}/v.json")
execute_process(COMMAND ${GIB} -q study ${W}/s.json --out ${W}/out RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
    message(FATAL_ERROR "the study with camera view:v.json: exit ${rc}\n${err}")
endif()
file(GLOB run ${W}/out/runs/*/image.exr)
file(GLOB ref ${W}/out/references/*_b1_*.exr)
list(LENGTH run nrun)
list(LENGTH ref nref)
if(NOT nrun EQUAL 1 OR NOT nref EQUAL 1)
    message(FATAL_ERROR "the study left ${nrun} run images and ${nref} bounce-matched references (expected 1, 1)")
endif()
foreach(cam "view:${W}/v.json" "")
    set(args --scene ${SCENE} --method direct --size 16x16 --frames 1 --warmup 0 --seed 1)
    if(cam)
        list(APPEND args --camera ${cam})
        set(out ${W}/render_view.exr)
    else()
        set(out ${W}/render_scene_camera.exr)
    endif()
    execute_process(COMMAND ${GIB} -q render ${args} --out ${out} RESULT_VARIABLE rc ERROR_VARIABLE err)
    if(NOT rc EQUAL 0)
        message(FATAL_ERROR "render ${args}: exit ${rc}\n${err}")
    endif()
endforeach()
view_diff(j ${run} ${W}/render_view.exr)
string(JSON same GET "${j}" rmse)
view_diff(j ${run} ${W}/render_scene_camera.exr)
string(JSON other GET "${j}" rmse)
if(same GREATER 0.000001 OR NOT other GREATER 0.001)
    message(FATAL_ERROR "the study's run against render --camera view:v.json: rmse ${same} (at most 1e-6); "
                        "against the scene's camera: ${other} (more than 1e-3)")
endif()
view_diff(j ${run} ${ref})
string(JSON ref_run GET "${j}" rmse)
view_diff(j ${W}/render_scene_camera.exr ${ref})
string(JSON ref_scene GET "${j}" rmse)
if(NOT ref_run LESS ref_scene)
    message(FATAL_ERROR "the study's reference is no closer to the view's image (rmse ${ref_run}) than to the "
                        "scene camera's (${ref_scene}): its camera is not the view's")
endif()

# the view's content in the run's identity
execute_process(COMMAND ${GIB} study ${W}/s.json --dry-run OUTPUT_VARIABLE p1 RESULT_VARIABLE rc1)
write_view(${W}/v.json 1.4 short_block)
execute_process(COMMAND ${GIB} study ${W}/s.json --dry-run OUTPUT_VARIABLE p2 RESULT_VARIABLE rc2)
string(REGEX MATCH "run [^:]+" r1 "${p1}")
string(REGEX MATCH "run [^:]+" r2 "${p2}")
if(NOT rc1 EQUAL 0 OR NOT rc2 EQUAL 0 OR NOT r1 OR r1 STREQUAL r2)
    message(FATAL_ERROR "an edited view under the same name kept the run id (${r1}, ${r2}; exits ${rc1}, ${rc2})")
endif()

# bad views: one line naming /camera, exit 2
write_study(${W}/bad1.json "view:${W}/no_such_view.json")
write_view(${W}/badnode.json 1.2 no_such_node)
write_study(${W}/bad2.json "view:${W}/badnode.json")
foreach(bad bad1 bad2)
    execute_process(COMMAND ${GIB} study ${W}/${bad}.json --dry-run RESULT_VARIABLE rc ERROR_VARIABLE err
        OUTPUT_QUIET)
    if(NOT rc EQUAL 2 OR NOT err MATCHES "/camera")
        message(FATAL_ERROR "${bad}: exit ${rc}, expected 2 naming /camera\n${err}")
    endif()
endforeach()
message(STATUS "study camera view: run vs render --camera view: rmse ${same}, vs the scene camera ${other}; "
               "reference vs run ${ref_run}, vs the scene camera ${ref_scene}")
