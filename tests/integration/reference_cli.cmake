# The `gibench reference` command: exit status 0 / 1 / 2 with a one-line
# reason, the outputs it promises (EXR with a variance layer, PNG, stats
# JSON), stopping rules, thread-count independence of the image, and a
# finite image for every committed scene.
# Run by ctest as: cmake -DGIB=... -DSCENES=... -DDATA=... -DOUT=... -P reference_cli.cmake

set(failures 0)
set(CB ${SCENES}/cornell_box_coarse.gltf)

include(${CMAKE_CURRENT_LIST_DIR}/expect.cmake)


function(expect_same a b)
    execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files ${a} ${b} RESULT_VARIABLE rc)
    if(NOT rc EQUAL 0)
        message(SEND_ERROR "${a} and ${b} differ")
        math(EXPR f "${failures} + 1")
        set(failures ${f} PARENT_SCOPE)
    endif()
endfunction()

# Bad usage and bad input: 2.
expect(2 "reference: --scene is required" reference --out ${OUT}/r.exr)
expect(2 "reference: --out is required" reference --scene ${CB})
expect(2 "reference: --spp '0'" reference --scene ${CB} --spp 0 --out ${OUT}/r.exr)
expect(2 "reference: --time 'soon'" reference --scene ${CB} --time soon --out ${OUT}/r.exr)
expect(2 "reference: --target-se '-1'" reference --scene ${CB} --target-se -1 --out ${OUT}/r.exr)
expect(2 "reference: --max-bounces 'many'" reference --scene ${CB} --max-bounces many --out ${OUT}/r.exr)
expect(2 "reference: --strategy 'path'" reference --scene ${CB} --strategy path --out ${OUT}/r.exr)
expect(2 "reference: --size '0x4'" reference --scene ${CB} --size 0x4 --out ${OUT}/r.exr)
expect(2 "reference: --out '${OUT}/r.bmp'" reference --scene ${CB} --out ${OUT}/r.bmp)
expect(2 "reference: unknown argument '--fast'" reference --scene ${CB} --fast --out ${OUT}/r.exr)
expect(2 "reference: --seed needs a value" reference --scene ${CB} --out ${OUT}/r.exr --seed)
expect(2 "has no camera 'nope'" reference --scene ${CB} --camera nope --out ${OUT}/r.exr)
expect(2 "no-such-file.gltf" reference --scene ${OUT}/no-such-file.gltf --out ${OUT}/r.exr)
file(GLOB malformed ${DATA}/malformed/*.gltf)
list(GET malformed 0 one_bad)
expect(2 ": /" reference --scene ${one_bad} --out ${OUT}/r.exr)
# Failure while running: 1.
expect(1 "${OUT}/missing-dir/r.exr" reference --scene ${CB} --size 8x8 --spp 2 --out ${OUT}/missing-dir/r.exr)

# A run with every output.
expect(0 "" reference --scene ${CB} --size 24x16 --spp 8 --max-bounces 3 --seed 9 --threads 2
       --out ${OUT}/ref_cb.exr --out ${OUT}/ref_cb.png --stats ${OUT}/ref_cb.json)
expect_json(${OUT}/ref_cb.json "\"renderer\": \"embree 3\\.[0-9]+\\.[0-9]+ cpu\"" "\"spp\": 8," "\"seed\": 9,"
            "\"max_bounces\": 3," "\"threads\": 2," "\"width\": 24," "\"height\": 16," "\"nonfinite_samples\": 0,"
            "\"mean_rel_se\": [0-9]" "\"mean_se\": [0-9]" "\"camera\": \"#0\"" "\"scene\": \"[^\"]*cornell_box_coarse.gltf\""
            "\"wall_seconds\": [0-9]" "\"stop\": \"spp\"" "\"mrays_per_second\": [0-9]" "\"strategy\": \"mis\"")
file(STRINGS ${OUT}/ref_cb.exr layer REGEX "variance\\.A")
if(NOT layer)
    message(SEND_ERROR "${OUT}/ref_cb.exr has no variance layer")
    math(EXPR failures "${failures} + 1")
endif()
if(NOT EXISTS ${OUT}/ref_cb.png)
    message(SEND_ERROR "no PNG written")
    math(EXPR failures "${failures} + 1")
endif()

# The image does not depend on the thread count (PFM: no time stamp inside).
expect(0 "" reference --scene ${CB} --size 20x12 --spp 6 --threads 1 --out ${OUT}/ref_t1.pfm)
expect(0 "" reference --scene ${CB} --size 20x12 --spp 6 --threads 3 --out ${OUT}/ref_t3.pfm)
expect_same(${OUT}/ref_t1.pfm ${OUT}/ref_t3.pfm)

# --target-se stops at a sample count that depends on the image alone.
expect(0 "" reference --scene ${CB} --size 16x16 --target-se 0.2 --threads 1 --out ${OUT}/ref_se1.pfm
       --stats ${OUT}/ref_se1.json)
expect(0 "" reference --scene ${CB} --size 16x16 --target-se 0.2 --threads 2 --out ${OUT}/ref_se2.pfm
       --stats ${OUT}/ref_se2.json)
expect_json(${OUT}/ref_se1.json "\"stop\": \"target-se\"")
expect_same(${OUT}/ref_se1.pfm ${OUT}/ref_se2.pfm)
# ... and --spp caps it.
expect(0 "" reference --scene ${CB} --size 16x16 --target-se 0.0001 --spp 5 --out ${OUT}/ref_cap.pfm
       --stats ${OUT}/ref_cap.json)
expect_json(${OUT}/ref_cap.json "\"stop\": \"spp\"" "\"spp\": 5,")
# --pixel center: every camera sample through the pixel centre, so with
# emitters only (0 bounces) all samples of a pixel agree: no variance.
expect(2 "reference: --pixel 'gauss'" reference --scene ${CB} --pixel gauss --out ${OUT}/r.exr)
expect(0 "" reference --scene ${CB} --size 16x16 --spp 4 --max-bounces 0 --pixel center --out ${OUT}/ref_pc.pfm
       --stats ${OUT}/ref_pc.json)
expect_json(${OUT}/ref_pc.json "\"pixel\": \"center\"" "\"mean_se\": 0(\\.0*)?,")
expect(0 "" reference --scene ${CB} --size 16x16 --spp 4 --max-bounces 0 --out ${OUT}/ref_box.pfm
       --stats ${OUT}/ref_box.json)
expect_json(${OUT}/ref_box.json "\"pixel\": \"box\"" "\"mean_se\": [0-9.]*[1-9]")
# --time stops on time.
expect(0 "" reference --scene ${CB} --size 16x16 --time 0.3 --out ${OUT}/ref_time.pfm --stats ${OUT}/ref_time.json)
expect_json(${OUT}/ref_time.json "\"stop\": \"time\"")

# Every committed scene gives a finite image, at time 0 and mid-animation.
foreach(scene cornell_box.gltf cornell_glossy.gltf bunny_env.glb teapot_plane.glb teapot_area.glb u_room.gltf
              cornell_moving.gltf stress/two_rooms_thin.gltf stress/two_rooms_thick.gltf stress/light_in_hull.gltf
              stress/hulls_overlap.gltf stress/glossy.gltf stress/moving_light.gltf stress/moving_camera.gltf
              stress/scale_t00116.gltf stress/scale_t57090.gltf)
    string(REPLACE "/" "_" tag "${scene}")
    expect(0 "" reference --scene ${SCENES}/${scene} --size 24x24 --spp 4 --out ${OUT}/ref_all_${tag}.exr
           --stats ${OUT}/ref_all_${tag}.json)
    expect_json(${OUT}/ref_all_${tag}.json "\"nonfinite_samples\": 0,")
endforeach()
expect(0 "" reference --scene ${SCENES}/cornell_moving.gltf --time-of-scene 1.5 --size 24x24 --spp 4
       --max-bounces 0 --out ${OUT}/ref_moving.png --stats ${OUT}/ref_moving.json)
expect_json(${OUT}/ref_moving.json "\"time_of_scene\": 1.5" "\"max_bounces\": 0,")

if(failures GREATER 0)
    message(FATAL_ERROR "${failures} reference command-line expectation(s) failed")
endif()
message(STATUS "all reference command-line expectations met")
