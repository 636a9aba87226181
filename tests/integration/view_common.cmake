# Helpers of the gibench view tests (view_script.cmake, view_every_method.cmake).

# Skips (SKIPPED:) where no X server can be started for the window.
macro(view_require_xvfb)
    find_program(XVFB_RUN xvfb-run)
    find_program(XVFB Xvfb)
    if(NOT XVFB_RUN OR NOT XVFB)
        message(STATUS "SKIPPED: xvfb-run or Xvfb is not installed (scripts/install-deps.sh installs xvfb)")
        return()
    endif()
endmacro()

# view_run(<script file> <args...>): gibench view under a fresh Xvfb; fails the
# test unless it exits 0.
function(view_run script)
    execute_process(COMMAND ${XVFB_RUN} -a ${GIB} view --script ${script} ${ARGN}
        WORKING_DIRECTORY ${W} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 300)
    if(NOT rc EQUAL 0)
        message(FATAL_ERROR "gibench view --script ${script} ${ARGN}: exit ${rc}\n${out}\n${err}")
    endif()
    set(VIEW_OUT "${out}" PARENT_SCOPE)
    set(VIEW_ERR "${err}" PARENT_SCOPE)
endfunction()

# milli(<out var> <number>): a number of a view file in thousandths, rounded
# towards zero (CMake has integer arithmetic only).
function(milli outvar x)
    if(x MATCHES "[eE]-")
        set(${outvar} 0 PARENT_SCOPE) # json-c writes only values below 1e-4 with a negative exponent: 0
        return()
    endif()
    if(NOT x MATCHES "^(-?)([0-9]+)(\\.([0-9]*))?$")
        message(FATAL_ERROR "not a plain number in the view file: ${x}")
    endif()
    set(sign "${CMAKE_MATCH_1}")
    set(int "${CMAKE_MATCH_2}")
    string(SUBSTRING "${CMAKE_MATCH_4}000" 0 3 frac)
    math(EXPR v "${sign}(${int} * 1000 + 1${frac} - 1000)")
    set(${outvar} ${v} PARENT_SCOPE)
endfunction()

# view_diff(<out var> <test.exr> <reference.exr>): gibench diff's JSON.
function(view_diff outvar test ref)
    execute_process(COMMAND ${GIB} diff ${test} ${ref} --json RESULT_VARIABLE rc OUTPUT_VARIABLE out
        ERROR_VARIABLE err)
    if(NOT rc EQUAL 0)
        message(FATAL_ERROR "gibench diff ${test} ${ref}: exit ${rc}\n${err}")
    endif()
    set(${outvar} "${out}" PARENT_SCOPE)
endfunction()

# view_render_matches(<prefix> <max rmse>): `gibench render --view PREFIX.json`
# gives PREFIX.exr within max rmse; sets RENDER_RMSE in the caller.
function(view_render_matches prefix max)
    execute_process(COMMAND ${GIB} -q render --view ${prefix}.json --out ${prefix}_batch.exr
        RESULT_VARIABLE rc ERROR_VARIABLE err)
    if(NOT rc EQUAL 0)
        message(FATAL_ERROR "gibench render --view ${prefix}.json: exit ${rc}\n${err}")
    endif()
    view_diff(j ${prefix}.exr ${prefix}_batch.exr)
    string(JSON rmse GET "${j}" rmse)
    string(JSON bad GET "${j}" test nonfinite_pixels)
    if(rmse GREATER ${max} OR NOT bad EQUAL 0)
        message(FATAL_ERROR "${prefix}: the viewer's screenshot and render --view differ: rmse ${rmse} "
                            "(at most ${max}), ${bad} non-finite pixels")
    endif()
    set(RENDER_RMSE ${rmse} PARENT_SCOPE)
endfunction()
