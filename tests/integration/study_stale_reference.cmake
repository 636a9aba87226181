# Issue 32, item 1: an interrupted reference is not done. Edit a scene,
# interrupt the study while it renders the new reference, resume: the
# reference must be rendered again for the edited scene (before the fix the
# interrupted child counted as a success, its key was written beside the
# old image, and the resumed study compared with the stale reference).
# cmake -DGIB=... -DROOT=... -DOUT=... -P study_stale_reference.cmake
set(failures 0)
include(${CMAKE_CURRENT_LIST_DIR}/expect.cmake)
set(D ${OUT}/study_stale_reference)
file(REMOVE_RECURSE ${D})
file(MAKE_DIRECTORY ${D})
file(COPY ${ROOT}/scenes/cornell_box_coarse.bin DESTINATION ${D})
file(READ ${ROOT}/scenes/cornell_box_coarse.gltf scene)
file(WRITE ${D}/box.gltf "${scene}")
# one bounce: a single reference, no bounce-matched one; enough samples that
# the render is still going when the signal comes
file(WRITE ${D}/s.json "{\"name\": \"stale\", \"scenes\": [\"${D}/box.gltf\"], \"size\": [16, 16],
  \"frames\": 1, \"warmup\": 0, \"methods\": [{\"method\": \"direct\"}],
  \"reference\": {\"spp\": 2048, \"max_bounces\": 1}}")
set(S ${D}/out)
set(REF ${S}/references/box_b1_2048spp.exr)
execute_process(COMMAND ${GIB} -q study ${D}/s.json --out ${S} RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT EXISTS ${REF})
    message(FATAL_ERROR "the first study failed (exit ${rc}) or made no ${REF}:\n${err}")
endif()
file(SHA256 ${REF} old_ref)
file(COPY_FILE ${REF} ${D}/old.exr)

# the light a third as strong: the reference must change
string(REPLACE "\"emissiveStrength\": 17.0" "\"emissiveStrength\": 5.0" edited "${scene}")
if(edited STREQUAL scene)
    message(FATAL_ERROR "the scene's light strength was not found to edit")
endif()
file(WRITE ${D}/box.gltf "${edited}")
file(REMOVE ${REF}.log)
# start the study, wait for the reference's child (its log), SIGTERM the study
execute_process(COMMAND sh -c "\"$0\" study \"$2\" --out \"$1\" >\"$1.log\" 2>&1 & p=$!
                               i=0; while [ ! -e \"$3.log\" ] && [ $i -lt 600 ]; do sleep 0.05; i=$((i+1)); done
                               kill -TERM $p; wait $p; echo $?"
                        ${GIB} ${S} ${D}/s.json ${REF}
                TIMEOUT 120 RESULT_VARIABLE rc OUTPUT_VARIABLE code)
string(STRIP "${code}" code)
file(READ ${S}.log log)
if(NOT rc EQUAL 0 OR NOT code STREQUAL "1")
    fail("the interrupted study exited ${code} (expected 1):\n${log}")
endif()
match("${log}" "reference for [^\n]*: interrupted" "the reference was not reported interrupted:\n${log}")

# resuming renders the reference of the edited scene
execute_process(COMMAND ${GIB} study ${D}/s.json --out ${S} RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
    fail("the resumed study exited ${rc}:\n${err}")
endif()
file(SHA256 ${REF} new_ref)
if(new_ref STREQUAL old_ref)
    fail("the resumed study kept the reference of the scene before the edit:\n${err}")
endif()
# ... and it is the edited scene's: the light a third as strong makes it
# about 70 % darker (the old reference would differ by 0 %)
execute_process(COMMAND ${GIB} diff ${REF} ${D}/old.exr --json RESULT_VARIABLE rc OUTPUT_VARIABLE dj)
string(JSON dlum ERROR_VARIABLE jerr GET "${dj}" mean_lum_diff_pct)
if(NOT rc EQUAL 0 OR jerr OR NOT dlum LESS -60 OR NOT dlum GREATER -80)
    fail("the resumed study's reference is not the edited scene's (mean luminance ${dlum} % from the old one):\n${dj}")
endif()

if(failures GREATER 0)
    message(FATAL_ERROR "${failures} stale-reference expectation(s) failed")
endif()
message(STATUS "an interrupted reference is rendered again on resume")
