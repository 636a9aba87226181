# The build removes the .so of a plugin whose folder no longer exists
# (cmake/remove_stale_plugins.cmake, run at every configuration): in a
# scratch plugin directory, the files of methods still built stay, the
# stale one goes, and files that are not method plugins are left alone.
# Run by ctest as: cmake -DROOT=... -DOUT=... -P stale_plugins.cmake
set(dir ${OUT}/stale_plugins)
file(REMOVE_RECURSE ${dir})
file(MAKE_DIRECTORY ${dir})
foreach(f gimethod_csm.so gimethod_vlf.so gimethod_gone.so notes.txt libother.so)
    file(WRITE ${dir}/${f} "x")
endforeach()
execute_process(COMMAND ${CMAKE_COMMAND} "-DPLUGIN_DIR=${dir}" "-DIDS=csm;vlf"
                        -P ${ROOT}/cmake/remove_stale_plugins.cmake
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
set(failures 0)
if(NOT rc EQUAL 0)
    message(SEND_ERROR "remove_stale_plugins.cmake: exit ${rc}: ${err}")
    math(EXPR failures "${failures} + 1")
endif()
foreach(f gimethod_csm.so gimethod_vlf.so notes.txt libother.so)
    if(NOT EXISTS ${dir}/${f})
        message(SEND_ERROR "${f} was removed, though it is not a stale method plugin")
        math(EXPR failures "${failures} + 1")
    endif()
endforeach()
if(EXISTS ${dir}/gimethod_gone.so)
    message(SEND_ERROR "gimethod_gone.so (no folder builds 'gone') was left in the plugin directory")
    math(EXPR failures "${failures} + 1")
endif()
if(NOT "${out}${err}" MATCHES "method 'gone'")
    message(SEND_ERROR "the removal is not reported: '${out}${err}'")
    math(EXPR failures "${failures} + 1")
endif()
if(failures GREATER 0)
    message(FATAL_ERROR "${failures} failure(s)")
endif()
message(STATUS "stale gimethod_gone.so removed; the built plugins and other files kept")
