# A batch node's environment (issue 32, items 8 and 9):
#   - HOME unset, or HOME where nothing can be written (no cache directory):
#     a render still works, with exactly one warning line, and its timings
#     say it ran without the cache (it used to fail, even `direct`);
#   - SLURM_CPUS_PER_TASK: the reference uses that many threads when
#     --threads is not given (it used to take every core of the node).
# cmake -DGIB=... -DROOT=... -DOUT=... -P batch_env.cmake
set(failures 0)
include(${CMAKE_CURRENT_LIST_DIR}/expect.cmake)
set(D ${OUT}/batch_env)
file(REMOVE_RECURSE ${D})
file(MAKE_DIRECTORY ${D})
set(SCENE ${ROOT}/scenes/cornell_box_coarse.gltf)
file(WRITE ${D}/home_is_a_file "not a directory\n")
# "unset": no HOME, no XDG_CACHE_HOME, no GIBENCH_CACHE; "unwritable": /proc
# (read-only even for root) and a regular file
foreach(kind unset proc file)
    set(home_arg -u HOME)
    if(kind STREQUAL proc)
        set(home_arg HOME=/proc)
    elseif(kind STREQUAL file)
        set(home_arg HOME=${D}/home_is_a_file)
    endif()
    execute_process(COMMAND env -u GIBENCH_CACHE -u XDG_CACHE_HOME ${home_arg}
                            ${GIB} -q render --scene ${SCENE} --method direct --size 32x32
                            --out ${D}/${kind}.exr --timings ${D}/${kind}.json
                    TIMEOUT 120 RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
    if(NOT rc EQUAL 0 OR NOT EXISTS ${D}/${kind}.exr)
        fail("HOME ${kind}: render exited ${rc} (expected 0 and an image):\n${err}")
        continue()
    endif()
    match("${err}" "^gibench: warning: [^\n]*; rendering without the cache\n$"
          "HOME ${kind}: not exactly one warning line about the cache:\n${err}")
    expect_json(${D}/${kind}.json "\"cache\": *false")
endforeach()

# the reference's threads: SLURM_CPUS_PER_TASK (1 and 3: at least one of
# them differs from this machine's core count), --threads wins over it
foreach(n 1 3)
    execute_process(COMMAND env SLURM_CPUS_PER_TASK=${n}
                            ${GIB} -q reference --scene ${SCENE} --size 16x16 --spp 1
                            --out ${D}/ref${n}.exr --stats ${D}/ref${n}.json
                    TIMEOUT 120 RESULT_VARIABLE rc ERROR_VARIABLE err)
    if(NOT rc EQUAL 0)
        fail("reference with SLURM_CPUS_PER_TASK=${n} exited ${rc}:\n${err}")
        continue()
    endif()
    expect_json(${D}/ref${n}.json "\"threads\": *${n}[,\n }]")
endforeach()
execute_process(COMMAND env SLURM_CPUS_PER_TASK=3
                        ${GIB} -q reference --scene ${SCENE} --size 16x16 --spp 1 --threads 2
                        --out ${D}/ref_t.exr --stats ${D}/ref_t.json
                TIMEOUT 120 RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
    fail("reference --threads 2 exited ${rc}:\n${err}")
else()
    expect_json(${D}/ref_t.json "\"threads\": *2[,\n }]")
endif()

if(failures GREATER 0)
    message(FATAL_ERROR "${failures} batch environment expectation(s) failed")
endif()
message(STATUS "renders work without a cache directory; the reference follows SLURM_CPUS_PER_TASK")
