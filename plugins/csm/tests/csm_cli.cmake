# The csm plugin through the gibench command: a finite render of the bunny,
# the on-disk cache (a second run hits it; a damaged file is recomputed with
# a warning), and bad parameters exit 2.
# Run by ctest as: cmake -DGIB=... -DSCENES=... -DOUT=... -DEXPECT=.../expect.cmake -P csm_cli.cmake

set(failures 0)
include(${EXPECT})

set(cache ${OUT}/csm_cache)
file(REMOVE_RECURSE ${cache})
file(MAKE_DIRECTORY ${cache})
set(ENV{GIBENCH_CACHE} ${cache})
set(args render --scene ${SCENES}/bunny_env.glb --method csm --size 48x48 --frames 2 --param N=8 --param M=64)

expect(0 "" ${args} --out ${OUT}/csm_bunny_1.exr --timings ${OUT}/csm_bunny_1.json)
expect_json(${OUT}/csm_bunny_1.json "\"nonfinite_pixels\": 0" "\"cache_hit\": 0" "\"segments_per_texel\""
           "\"maps\": 128" "\"depth_render\"" "\"compress\"" "\"upload\"")
file(GLOB cached ${cache}/csm-*.bin)
list(LENGTH cached n_cached)
if(NOT n_cached EQUAL 2)
    message(SEND_ERROR "expected 2 cache files (bunny, ground), found ${n_cached}")
    math(EXPR failures "${failures} + 1")
endif()
expect(0 "" ${args} --out ${OUT}/csm_bunny_2.exr --timings ${OUT}/csm_bunny_2.json)
expect_json(${OUT}/csm_bunny_2.json "\"nonfinite_pixels\": 0" "\"cache_hit\": 1")

# A damaged cache file: a warning naming it, recomputed, and rewritten.
list(GET cached 0 victim)
file(WRITE ${victim} "GICSMZ this is not a CSM")
expect(0 "unusable cache file" ${args} --out ${OUT}/csm_bunny_3.exr --timings ${OUT}/csm_bunny_3.json)
expect_json(${OUT}/csm_bunny_3.json "\"nonfinite_pixels\": 0" "\"cache_hit\": 0")
expect(0 "" ${args} --out ${OUT}/csm_bunny_4.exr --timings ${OUT}/csm_bunny_4.json)
expect_json(${OUT}/csm_bunny_4.json "\"cache_hit\": 1")

# Other options run and stay finite.
expect(0 "" ${args} --param filter=pcf --param depth=z3 --param enumeration=zigzag --param S=5
       --out ${OUT}/csm_bunny_pcf.exr --timings ${OUT}/csm_bunny_pcf.json)
expect_json(${OUT}/csm_bunny_pcf.json "\"nonfinite_pixels\": 0")
expect(0 "" ${args} --param depth=sphere --param enumeration=diagonal --out ${OUT}/csm_bunny_sphere.exr
       --timings ${OUT}/csm_bunny_sphere.json)
expect_json(${OUT}/csm_bunny_sphere.json "\"nonfinite_pixels\": 0" "\"cache_hit\": 0")
expect(0 "" ${args} --param filter=rr --param enumeration=scanline --out ${OUT}/csm_bunny_rr.exr
       --timings ${OUT}/csm_bunny_rr.json)
expect_json(${OUT}/csm_bunny_rr.json "\"nonfinite_pixels\": 0")

# open_surfaces and shell_thickness are in the cache key: each makes new
# files for both objects (bunny, ground).
file(GLOB cached ${cache}/csm-*.bin)
list(LENGTH cached n_before)
expect(0 "" ${args} --param open_surfaces=open --out ${OUT}/csm_bunny_open.exr --timings ${OUT}/csm_bunny_open.json)
expect_json(${OUT}/csm_bunny_open.json "\"nonfinite_pixels\": 0" "\"cache_hit\": 0")
expect(0 "" ${args} --param shell_thickness=0.01 --out ${OUT}/csm_bunny_shell.exr --timings ${OUT}/csm_bunny_shell.json)
expect_json(${OUT}/csm_bunny_shell.json "\"nonfinite_pixels\": 0" "\"cache_hit\": 0")
file(GLOB cached ${cache}/csm-*.bin)
list(LENGTH cached n_after)
math(EXPR n_new "${n_after} - ${n_before}")
if(NOT n_new EQUAL 4)
    message(SEND_ERROR "open_surfaces=open and shell_thickness=0.01: expected 4 new cache files, found ${n_new}")
    math(EXPR failures "${failures} + 1")
endif()

# Table 2's visibility benchmark (mode=random|coherent) on the bunny alone:
# every mode counts S samples per surface pixel (the same pixels), and
# random and coherent directions estimate the same average visibility (the
# image is the visible fraction on the bunny) from different directions.
# --no-cache leaves no file behind.
function(milli json key out) # first channel of a JSON number list, in thousandths
    file(READ ${json} j)
    string(JSON v GET "${j}" ${key} 0)
    if(NOT v MATCHES "^([0-9]+)(\\.([0-9]*))?")
        message(FATAL_ERROR "${json}: ${key} = '${v}' is not a number >= 0")
    endif()
    string(SUBSTRING "${CMAKE_MATCH_3}000" 0 3 frac)
    math(EXPR m "${CMAKE_MATCH_1} * 1000 + 1${frac} - 1000")
    set(${out} ${m} PARENT_SCOPE)
endfunction()
file(GLOB before ${cache}/csm-*.bin)
set(vis render --scene ${SCENES}/bunny_alone_env.glb --method csm --size 24x24 --param N=8 --param M=32
    --param S=256 --no-cache)
foreach(mode shade random coherent)
    expect(0 "" ${vis} --param mode=${mode} --out ${OUT}/csm_vis_${mode}.exr --timings ${OUT}/csm_vis_${mode}.json)
    expect_json(${OUT}/csm_vis_${mode}.json "\"nonfinite_pixels\": 0" "\"cache_hit\": 0" "\"cache\": false")
    file(READ ${OUT}/csm_vis_${mode}.json j)
    string(JSON spf_${mode} GET "${j}" stats samples_per_frame)
endforeach()
if(NOT spf_shade GREATER 0 OR NOT spf_random EQUAL spf_shade OR NOT spf_coherent EQUAL spf_shade)
    message(SEND_ERROR "samples_per_frame differs between modes or is 0: ${spf_shade} ${spf_random} ${spf_coherent}")
    math(EXPR failures "${failures} + 1")
endif()
milli(${OUT}/csm_vis_random.json mean_rgb v_random)
milli(${OUT}/csm_vis_coherent.json mean_rgb v_coherent)
math(EXPR d "${v_random} - ${v_coherent}")
if(d LESS -30 OR d GREATER 30 OR v_random EQUAL v_coherent)
    message(SEND_ERROR "image means (the background shows the map in both): random ${v_random}, coherent "
                       "${v_coherent} (thousandths): expected within 0.03 of each other but not equal")
    math(EXPR failures "${failures} + 1")
endif()
file(GLOB after ${cache}/csm-*.bin)
if(NOT before STREQUAL after)
    message(SEND_ERROR "--no-cache wrote cache files: ${after}")
    math(EXPR failures "${failures} + 1")
endif()
expect(2 "csm: " ${args} --param mode=fast --out ${OUT}/x.exr)

# Bad parameters.
expect(2 "csm: N=1 is outside" ${args} --param N=1 --out ${OUT}/x.exr)
expect(2 "csm: M=2000 is outside" ${args} --param M=2000 --out ${OUT}/x.exr)
expect(2 "csm: " ${args} --param filter=box --out ${OUT}/x.exr)
expect(2 "csm: " ${args} --param enumeration=spiral --out ${OUT}/x.exr)
expect(2 "csm: S=0 is outside" ${args} --param S=0 --out ${OUT}/x.exr)
expect(2 "csm: " ${args} --param open_surfaces=closed --out ${OUT}/x.exr)
expect(2 "csm: shell_thickness=0 is outside" ${args} --param shell_thickness=0 --out ${OUT}/x.exr)
expect(2 "csm: unknown parameter 'K'" ${args} --param K=3 --out ${OUT}/x.exr)

# Local lights (§4.2): the teapot's area light and the cross scene's linear
# and point lights; cube maps cached per (light, object), keyed on the
# light's geometry.
set(lcache ${OUT}/csm_cache_local)
file(REMOVE_RECURSE ${lcache})
file(MAKE_DIRECTORY ${lcache})
set(ENV{GIBENCH_CACHE} ${lcache})
set(largs render --method csm --size 32x32 --frames 2 --param M_local=32)
expect(0 "" ${largs} --param N_local=2 --scene ${SCENES}/teapot_area.glb --out ${OUT}/csm_teapot_area.exr
       --timings ${OUT}/csm_teapot_area.json)
expect_json(${OUT}/csm_teapot_area.json "\"nonfinite_pixels\": 0" "\"cache_hit\": 0" "\"lights\": 1"
            "\"maps\": 0" "\"maps_local\": 48" "\"depth_render\"" "\"compress\"" "\"upload\"")
expect(0 "" ${largs} --param N_local=2 --scene ${SCENES}/teapot_area.glb --out ${OUT}/csm_teapot_area2.exr
       --timings ${OUT}/csm_teapot_area2.json)
expect_json(${OUT}/csm_teapot_area2.json "\"cache_hit\": 1")
# receivers=planar: the ground and the (planar) light get no CSM: 24 cube
# faces of the teapot only
expect(0 "receiver-only" -v ${largs} --param N_local=2 --scene ${SCENES}/teapot_area.glb --param receivers=planar
       --out ${OUT}/csm_teapot_planar.exr --timings ${OUT}/csm_teapot_planar.json)
expect_json(${OUT}/csm_teapot_planar.json "\"receiver_only_objects\": 2" "\"maps_local\": 24")
# semi-local: the orthographic maps (teapot, ground, light: 3 x 16), no cube maps
expect(0 "" ${largs} --param N_local=2 --scene ${SCENES}/teapot_area.glb --param lights=semilocal --param N=4 --param M=32
       --param filter=pcf --out ${OUT}/csm_teapot_semi.exr --timings ${OUT}/csm_teapot_semi.json)
expect_json(${OUT}/csm_teapot_semi.json "\"nonfinite_pixels\": 0" "\"maps\": 48" "\"maps_local\": 0")
# the Cornell box in semi-local mode: the light lies inside the walls' bounds
expect(0 "inside the bounds of object walls" ${largs} --param N_local=2 --scene ${SCENES}/cornell_box.gltf --param lights=semilocal
       --param N=4 --param M=32 --out ${OUT}/csm_cornell_semi.exr)
# linear (4 x 1 points: 24 faces for ground, box_a, box_b) and point light
# (6 faces for those and the bar); rr filter, hilbert order
set(DATA ${SCENES}/../plugins/csm/data)
expect(0 "" ${largs} --param N_local=4 --scene ${DATA}/csm_cross.glb --param filter=rr
       --param light_enumeration=hilbert --out ${OUT}/csm_cross.exr --timings ${OUT}/csm_cross.json)
expect_json(${OUT}/csm_cross.json "\"nonfinite_pixels\": 0" "\"lights\": 2" "\"maps_local\": 96")
file(GLOB before ${lcache}/csm-local-*.bin)
list(LENGTH before n_before)
# the same meshes with the point light moved: the linear light's maps hit,
# the point light's 4 are new
expect(0 "" ${largs} --param N_local=4 --scene ${DATA}/csm_cross_moved.glb --param filter=rr
       --param light_enumeration=hilbert --out ${OUT}/csm_cross_moved.exr --timings ${OUT}/csm_cross_moved.json)
expect_json(${OUT}/csm_cross_moved.json "\"cache_hit\": 0")
file(GLOB after ${lcache}/csm-local-*.bin)
list(LENGTH after n_after)
math(EXPR added "${n_after} - ${n_before}")
if(NOT added EQUAL 4)
    message(SEND_ERROR "moving the point light should add 4 cube-map cache files, added ${added}")
    math(EXPR failures "${failures} + 1")
endif()
# a linear_aspect above the bar's 30 : 1 makes it an area light (4 x 4)
expect(0 "" ${largs} --param N_local=4 --param linear_aspect=50 --scene ${DATA}/csm_cross.glb
       --out ${OUT}/csm_cross_area.exr --timings ${OUT}/csm_cross_area.json)
expect_json(${OUT}/csm_cross_area.json "\"maps_local\": 312")

# an animated scene under fixed local lights: by default the cube maps are
# precomputed again in each frame whose objects moved (stage "rebuild", stat
# local_rebuilds); with local_motion=keep they stay, with one warning
expect(0 "" ${largs} --param N_local=2 --scene ${SCENES}/cornell_moving.gltf
       --animate 4 --out ${OUT}/csm_moving.exr --timings ${OUT}/csm_moving.json)
expect_json(${OUT}/csm_moving.json "\"local_rebuilds\": [1-9]" "\"rebuild\": {")
expect(0 "fixed local lights' cube maps are not rebuilt" ${largs} --param N_local=2 --param local_motion=keep
       --scene ${SCENES}/cornell_moving.gltf --animate 4 --out ${OUT}/csm_moving_keep.exr)

expect(2 "csm: " ${largs} --param N_local=2 --scene ${SCENES}/teapot_area.glb --param lights=distant --out ${OUT}/x.exr)
expect(2 "csm: N_local=0 is outside" ${largs} --scene ${SCENES}/teapot_area.glb --param N_local=0 --out ${OUT}/x.exr)
expect(2 "csm: M_local=4 is outside" render --method csm --size 32x32 --scene ${SCENES}/teapot_area.glb --param M_local=4 --out ${OUT}/x.exr)
expect(2 "csm: " ${largs} --param N_local=2 --scene ${SCENES}/teapot_area.glb --param light_enumeration=spiral --out ${OUT}/x.exr)
expect(2 "csm: linear_aspect=0.5 is outside" ${largs} --param N_local=2 --scene ${SCENES}/teapot_area.glb --param linear_aspect=0.5
       --out ${OUT}/x.exr)
expect(2 "csm: " ${largs} --param N_local=2 --scene ${SCENES}/teapot_area.glb --param receivers=all --out ${OUT}/x.exr)

if(failures GREATER 0)
    message(FATAL_ERROR "${failures} csm command-line expectation(s) failed")
endif()
message(STATUS "all csm command-line expectations met")
