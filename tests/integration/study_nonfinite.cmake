# Issue 32, item 4: non-finite output is a failed run, non-finite input is
# refused. A method whose image holds NaN pixels fails in a study, compared
# or not (before the fix the metrics left the pixels out and the run was
# "ok"); an environment map with NaN texels is refused by the scene loader
# with one line naming the file (before, it loaded and gave NaN images).
# cmake -DGIB=... -DROOT=... -DOUT=... -DFAKE_CONF=... -P study_nonfinite.cmake
set(failures 0)
include(${CMAKE_CURRENT_LIST_DIR}/expect.cmake)
set(ENV{GIBENCH_PLUGIN_PATH} "${FAKE_CONF}")
set(D ${OUT}/study_nonfinite)
file(REMOVE_RECURSE ${D})
file(MAKE_DIRECTORY ${D})

# an all-NaN EXR (fake_conf_nan renders NaN everywhere) as the environment map
run(0 render --scene scenes/cornell_box_coarse.gltf --method fake_conf_nan --size 8x4 --out ${D}/nan.exr)
file(COPY ${ROOT}/scenes/cornell_box_coarse.bin DESTINATION ${D})
file(READ ${ROOT}/scenes/cornell_box_coarse.gltf scene)
string(REPLACE "\"name\": \"cornell_box_coarse\","
               "\"name\": \"cornell_box_coarse\", \"extras\": {\"gibench\": {\"environment\": {\"uri\": \"nan.exr\"}}},"
               scene "${scene}")
file(WRITE ${D}/env_nan.gltf "${scene}")
expect(2 "environment map 'nan.exr' has 32 NaN or infinite texels"
       render --scene ${D}/env_nan.gltf --method direct --size 16x16 --out ${D}/env_nan.exr)
expect(2 "nan.exr" reference --scene ${D}/env_nan.gltf --size 16x16 --spp 4 --out ${D}/env_nan_ref.exr)
if(EXISTS ${D}/env_nan.exr OR EXISTS ${D}/env_nan_ref.exr)
    fail("an image was written from a scene with a NaN environment map")
endif()

# NaN output fails the run, compared with the reference or not; direct is ok
file(WRITE ${D}/s.json "{\"name\": \"nonfinite\", \"base\": \"${ROOT}\", \"scenes\": [\"scenes/cornell_box_coarse.gltf\"],
  \"size\": [16, 16], \"frames\": 1, \"warmup\": 0,
  \"methods\": [{\"method\": \"fake_conf_nan\"}, {\"method\": \"fake_conf_nan\", \"compare\": false},
               {\"method\": \"direct\", \"params\": {\"light_samples\": 1}}],
  \"reference\": {\"spp\": 4, \"max_bounces\": 1}}")
run(1 -q study ${D}/s.json --out ${D}/out)
file(READ ${D}/out/runs.csv csv)
match_count("${csv}" "fake_conf_nan,[^\n]*,failed,non-finite output: 256 of 256 pixels are NaN or infinite" 2
            "NaN runs failed")
match_count("${csv}" "\ncornell_box_coarse-direct[^\n]*,ok," 1 "direct ok")
match("${last_err}" "gibench: study: 2 of 3 runs failed" "no verdict on the failed runs:\n${last_err}")

if(failures GREATER 0)
    message(FATAL_ERROR "${failures} non-finite expectation(s) failed")
endif()
message(STATUS "non-finite output fails its run; a NaN environment map is refused")
