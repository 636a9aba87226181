# Start-up (issue 14): the heavy libraries load only in the commands that
# need them. `gibench methods` and a plain 16x16 render writing EXR and PNG
# (what a study cell writes) must load neither VTK nor OpenImageIO nor their
# modules; reading a PNG loads the OpenImageIO module on demand; and with
# the module missing that read fails (non-zero exit) with one line naming it.
# The list of loaded objects is the dynamic linker's own (LD_DEBUG=libs).
# cmake -DGIB=... -DROOT=... -DOUT=... -P startup_libs.cmake
set(failures 0)
include(${CMAKE_CURRENT_LIST_DIR}/expect.cmake)
set(S ${ROOT}/scenes/cornell_box_coarse.gltf)
set(D ${OUT}/startup_libs)
file(REMOVE_RECURSE ${D})
file(MAKE_DIRECTORY ${D})
set(heavy "libvtk|libOpenImageIO|gi_image_oiio\\.so|libgi_charts\\.so")

# loaded(<var> <args...>): runs gibench under LD_DEBUG=libs; <var> gets the
# objects it initialised, one per line; a failed run fails the test.
function(loaded var)
    execute_process(COMMAND ${CMAKE_COMMAND} -E env LD_DEBUG=libs ${GIB} ${ARGN}
                    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
    if(NOT rc EQUAL 0)
        fail("gibench ${ARGN}: exit ${rc}\n${err}")
    endif()
    string(REGEX MATCHALL "calling init: [^\n]*" inits "${err}")
    set(${var} "${inits}" PARENT_SCOPE)
    set(failures ${failures} PARENT_SCOPE)
endfunction()

loaded(m methods)
# The set-up must see the loader's list at all, or the checks below prove nothing.
if(NOT m MATCHES "libgicore\\.so")
    fail("LD_DEBUG=libs did not list libgicore.so for gibench methods: ${m}")
endif()
if(m MATCHES "${heavy}")
    fail("gibench methods loads a heavy library again: ${CMAKE_MATCH_0}")
endif()
list(LENGTH m n_methods)
# 43 in the release build (since the first count of 35: GMP for the core's
# CGAL re-meshing, qhull for vlf, GLFW and X11 for the viewer), 51 under
# ASan + UBSan (their runtimes); 322 before the heavy libraries became
# modules. The bound catches a heavy library linked in again.
if(n_methods GREATER 60)
    fail("gibench methods initialises ${n_methods} shared objects (at most 60 expected)")
endif()

loaded(r render --scene ${S} --method direct --size 16x16 --frames 1 --warmup 0
       --out ${D}/r.exr --out ${D}/r.png)
if(r MATCHES "${heavy}")
    fail("a plain render writing EXR and PNG loads a heavy library: ${CMAKE_MATCH_0}")
endif()
foreach(f r.exr r.png)
    if(NOT EXISTS ${D}/${f})
        fail("the render wrote no ${f}")
    endif()
endforeach()

# Reading the EXR back is the core's (no module); reading a PNG is the module's.
loaded(e diff ${D}/r.exr ${D}/r.exr)
if(e MATCHES "${heavy}")
    fail("gibench diff of two EXRs loads a heavy library: ${CMAKE_MATCH_0}")
endif()
loaded(p diff ${D}/r.png ${D}/r.png)
if(NOT p MATCHES "gi_image_oiio\\.so")
    fail("gibench diff of two PNGs did not load the OpenImageIO module")
endif()

# The module missing: a copy of libgicore.so in a folder without modules,
# found first through LD_LIBRARY_PATH (the build's RUNPATH comes after it).
execute_process(COMMAND ${CMAKE_COMMAND} -E env LD_DEBUG=libs ${GIB} methods
                OUTPUT_QUIET ERROR_VARIABLE err)
string(REGEX MATCH "calling init: ([^\n]*libgicore\\.so)" _ "${err}")
set(core ${CMAKE_MATCH_1})
if(NOT core OR NOT EXISTS "${core}")
    fail("cannot find the libgicore.so gibench loads")
else()
    file(MAKE_DIRECTORY ${D}/lonely)
    file(COPY ${core} DESTINATION ${D}/lonely)
    execute_process(COMMAND ${CMAKE_COMMAND} -E env LD_LIBRARY_PATH=${D}/lonely
                            ${GIB} diff ${D}/r.png ${D}/r.png
                    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
    string(STRIP "${err}" err)
    string(REGEX MATCHALL "\n" nl "${err}")
    list(LENGTH nl extra)
    if(rc EQUAL 0 OR NOT rc MATCHES "^[0-9]+$" OR extra GREATER 0 OR
       NOT err MATCHES "needs the module ${D}/lonely/gi_image_oiio\\.so")
        fail("a missing module: expected a non-zero exit and one line naming ${D}/lonely/gi_image_oiio.so; "
             "got exit ${rc}: ${err}")
    endif()
endif()

if(failures GREATER 0)
    message(FATAL_ERROR "${failures} start-up check(s) failed")
endif()
message(STATUS "methods: ${n_methods} shared objects, no VTK or OpenImageIO; modules load on demand")
