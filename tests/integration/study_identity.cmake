# A run's identity is every input that changes its result: two studies that
# differ only in seed, camera or exposure make different runs, and two
# scenes of one file name in different folders get different references
# (and runs), by content (--dry-run); and a reference is rendered again when
# the scene's content changes under the same name (a tiny real study).
# cmake -DGIB=... -DROOT=... -DOUT=... -P study_identity.cmake
set(failures 0)
include(${CMAKE_CURRENT_LIST_DIR}/expect.cmake)
set(D ${OUT}/study_identity)
file(REMOVE_RECURSE ${D})
file(MAKE_DIRECTORY ${D}/a ${D}/b)
set(SCENE ${ROOT}/scenes/cornell_box_coarse.gltf)

# plan(<var> <extra top-level JSON> <scenes JSON>): the dry run's "run" and "reference" lines
function(plan var extra scenes)
    file(WRITE ${D}/s.json "{\"name\": \"id\", \"scenes\": ${scenes}, \"size\": [8, 8], ${extra}
      \"methods\": [{\"method\": \"direct\"}]}")
    execute_process(COMMAND ${GIB} study ${D}/s.json --dry-run WORKING_DIRECTORY ${ROOT} RESULT_VARIABLE rc
                    OUTPUT_VARIABLE out ERROR_VARIABLE err)
    if(NOT rc EQUAL 0)
        fail("dry run failed: ${err}")
    endif()
    set(${var} "${out}" PARENT_SCOPE)
endfunction()

plan(base "\"seed\": 1," "[\"${SCENE}\"]")
foreach(change "\"seed\": 2," "\"seed\": 1, \"exposure\": 1," "\"seed\": 1, \"camera\": \"camera\",")
    plan(other "${change}" "[\"${SCENE}\"]")
    string(REGEX MATCH "run [^:]+" r1 "${base}")
    string(REGEX MATCH "run [^:]+" r2 "${other}")
    if(r1 STREQUAL r2)
        fail("${change} leaves the run id unchanged (${r1})")
    endif()
endforeach()
# the same content under another path: the same run
file(COPY ${SCENE} ${ROOT}/scenes/cornell_box_coarse.bin DESTINATION ${D}/a)
plan(copy "\"seed\": 1," "[\"${D}/a/cornell_box_coarse.gltf\"]")
string(REGEX MATCH "run [^:]+" r1 "${base}")
string(REGEX MATCH "run [^:]+" r2 "${copy}")
if(NOT r1 STREQUAL r2)
    fail("the same scene content under another path changed the run id (${r1}, ${r2})")
endif()
# two scenes of one name, different content: different references and runs
file(READ ${SCENE} gltf)
string(JSON gltf SET "${gltf}" materials 0 name "\"changed\"")
file(WRITE ${D}/b/cornell_box_coarse.gltf "${gltf}")
file(COPY ${ROOT}/scenes/cornell_box_coarse.bin DESTINATION ${D}/b)
plan(two "\"seed\": 1," "[\"${D}/a/cornell_box_coarse.gltf\", \"${D}/b/cornell_box_coarse.gltf\"]")
string(REGEX MATCHALL "reference [^:]+" refs "${two}")
list(REMOVE_DUPLICATES refs)
list(LENGTH refs nrefs)
string(REGEX MATCHALL "run [^:]+" runs "${two}")
list(REMOVE_DUPLICATES runs)
list(LENGTH runs nruns)
if(NOT nrefs EQUAL 2 OR NOT nruns EQUAL 2)
    fail("two scenes of one name share references or runs:\n${two}")
endif()

# A reference is keyed on the scene's content too: the same study after an
# edit of the scene under the same name renders the reference again (its
# key changes), and without an edit reuses it (the key stays).
file(MAKE_DIRECTORY ${D}/c)
file(COPY ${SCENE} ${ROOT}/scenes/cornell_box_coarse.bin DESTINATION ${D}/c)
file(WRITE ${D}/real.json "{\"name\": \"idref\", \"scenes\": [\"${D}/c/cornell_box_coarse.gltf\"], \"size\": [8, 8],
  \"reference\": {\"spp\": 4, \"max_bounces\": 2}, \"methods\": [{\"method\": \"direct\"}]}")
function(real_study var)
    execute_process(COMMAND ${GIB} study ${D}/real.json --out ${D}/out WORKING_DIRECTORY ${ROOT} RESULT_VARIABLE rc
                    OUTPUT_VARIABLE out ERROR_VARIABLE err)
    if(NOT rc EQUAL 0)
        fail("study failed: ${err}")
    endif()
    file(GLOB cfgs ${D}/out/references/*.config)
    set(keys "")
    foreach(c ${cfgs})
        file(READ ${c} k)
        string(APPEND keys "${k}")
    endforeach()
    set(${var} "${keys}" PARENT_SCOPE)
endfunction()
real_study(k1)
real_study(k2)
if(NOT k1 MATCHES "scene-content [0-9a-f]+" OR NOT k1 STREQUAL k2)
    fail("a reference's key lacks the scene's content or changed without an edit:\n${k1}\n---\n${k2}")
endif()
file(READ ${D}/c/cornell_box_coarse.gltf gltf)
string(JSON gltf SET "${gltf}" materials 0 pbrMetallicRoughness baseColorFactor "[0.1, 0.2, 0.3, 1.0]")
file(WRITE ${D}/c/cornell_box_coarse.gltf "${gltf}")
real_study(k3)
if(k3 STREQUAL k1)
    fail("an edited scene under the same name kept its old reference key:\n${k3}")
endif()

if(failures GREATER 0)
    message(FATAL_ERROR "${failures} run identity expectation(s) failed")
endif()
message(STATUS "run ids follow every input")
