# Issue 32, item 3: a cache entry records what it was made for and is
# checked on read. An entry copied from another scene under this scene's
# name is refused with a warning and recomputed (before the fix it was used
# silently: the image was the other scene's shadows); truncated, padded and
# flipped entries are refused too. csm (per-object CSMs) and cssm_hrc (the
# scene's CSSM).
# cmake -DGIB=... -DROOT=... -DOUT=... -P cache_foreign.cmake
set(failures 0)
include(${CMAKE_CURRENT_LIST_DIR}/expect.cmake)
set(D ${OUT}/cache_foreign)
file(REMOVE_RECURSE ${D})
file(MAKE_DIRECTORY ${D}/a ${D}/b)
# scene B: the short block moved (its entries get other names)
file(COPY ${ROOT}/scenes/cornell_box_coarse.bin DESTINATION ${D})
file(READ ${ROOT}/scenes/cornell_box_coarse.gltf scene)
string(REPLACE "[1.855, 0.0, 1.69]" "[1.4, 0.0, 1.3]" moved "${scene}")
file(WRITE ${D}/b.gltf "${moved}")
set(A_SCENE ${ROOT}/scenes/cornell_box_coarse.gltf)

# render(<method> <cache> <scene> <name>): renders into D/<name>.exr and .json
function(render method cache scene name)
    set(ENV{GIBENCH_CACHE} ${cache})
    execute_process(COMMAND ${GIB} render --scene ${scene} --method ${method} --size 16x16
                            --out ${D}/${name}.exr --timings ${D}/${name}.json
                    RESULT_VARIABLE rc ERROR_VARIABLE err)
    set(last_err "${err}" PARENT_SCOPE)
    if(NOT rc EQUAL 0)
        message(FATAL_ERROR "${method} ${name}: exit ${rc}\n${err}")
    endif()
endfunction()

# refused(<method> <name> <why regex>): B rendered again warns about its entry,
# misses the cache and gives the image of a fresh render
function(refused method name why)
    render(${method} ${D}/b ${D}/b.gltf ${method}_${name})
    match("${last_err}" "unusable cache file \\(${why}" "${method}, ${name}: no warning:\n${last_err}")
    file(READ ${D}/${method}_${name}.json t)
    match("${t}" "\"cache_hit\": 0" "${method}, ${name}: the entry was used")
    execute_process(COMMAND ${GIB} diff ${D}/${method}_${name}.exr ${D}/${method}_b.exr --json OUTPUT_VARIABLE dj)
    string(JSON e ERROR_VARIABLE jerr GET "${dj}" relmse)
    if(jerr OR e GREATER 1e-6)
        fail("${method}, ${name}: the image differs from a fresh one (relMSE ${e})")
    endif()
    set(failures ${failures} PARENT_SCOPE)
endfunction()

foreach(method csm cssm_hrc)
    file(REMOVE_RECURSE ${D}/a ${D}/b)
    render(${method} ${D}/a ${A_SCENE} ${method}_a)
    render(${method} ${D}/b ${D}/b.gltf ${method}_b)
    # an entry of B that A lacks, and one of A that B lacks: the moved block's
    file(GLOB a_files RELATIVE ${D}/a ${D}/a/*.bin)
    file(GLOB b_files RELATIVE ${D}/b ${D}/b/*.bin)
    set(b_only "")
    set(a_only "")
    foreach(f ${b_files})
        list(FIND a_files ${f} at)
        if(at EQUAL -1)
            list(APPEND b_only ${f})
        endif()
    endforeach()
    foreach(f ${a_files})
        list(FIND b_files ${f} at)
        if(at EQUAL -1)
            list(APPEND a_only ${f})
        endif()
    endforeach()
    if(NOT b_only OR NOT a_only)
        message(FATAL_ERROR "${method}: moving the block made no new cache entry (A: ${a_files}, B: ${b_files})")
    endif()
    list(GET b_only 0 victim)
    list(GET a_only 0 stranger)
    file(COPY_FILE ${D}/a/${stranger} ${D}/b/${victim})
    refused(${method} foreign "made as ${stranger}, not ${victim}")
    if(method STREQUAL "csm")
        # the damages caught before the header existed are still caught
        execute_process(COMMAND truncate -s -1 ${D}/b/${victim})
        refused(${method} truncated "[0-9]+ bytes of data, the header says")
        execute_process(COMMAND truncate -s +1 ${D}/b/${victim})
        refused(${method} padded "[0-9]+ bytes of data, the header says")
        file(SIZE ${D}/b/${victim} n)
        math(EXPR at "${n} - 100")
        execute_process(COMMAND sh -c "printf '\\377' | dd of=\"$0\" bs=1 seek=$1 conv=notrunc 2>/dev/null"
                                ${D}/b/${victim} ${at})
        refused(${method} flipped "checksum mismatch")
    endif()
endforeach()

if(failures GREATER 0)
    message(FATAL_ERROR "${failures} cache expectation(s) failed")
endif()
message(STATUS "a cache entry from another scene, truncated, padded or flipped is recomputed")
