# Shared helpers of the command-line tests (include()d by the *_test.cmake
# and *_cli.cmake scripts). Each failure is reported with SEND_ERROR and
# counted in the caller's `failures`.

# expect(<exit code> <substring of stdout or stderr> <args...>): runs
# gibench; on failure (code != 0) stderr must be exactly one line.
function(expect code text)
    execute_process(COMMAND ${GIB} ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
    string(STRIP "${err}" err_stripped)
    string(FIND "${out}${err}" "${text}" pos)
    string(REGEX MATCHALL "\n" newlines "${err_stripped}")
    list(LENGTH newlines extra_lines)
    if(NOT rc EQUAL code OR pos EQUAL -1 OR (NOT code EQUAL 0 AND extra_lines GREATER 0))
        message(SEND_ERROR "gibench ${ARGN}: expected exit ${code} and '${text}' (one stderr line on failure);\n"
                           "got exit ${rc}\nstdout: ${out}\nstderr: ${err}")
        math(EXPR f "${failures} + 1")
        set(failures ${f} PARENT_SCOPE)
    endif()
endfunction()

# expect_json(<file> <regex>...): a JSON file written by gibench matches every regex.
function(expect_json file)
    file(READ ${file} j)
    foreach(re ${ARGN})
        if(NOT j MATCHES "${re}")
            message(SEND_ERROR "${file}: no match for '${re}' in\n${j}")
            math(EXPR f "${failures} + 1")
            set(failures ${f} PARENT_SCOPE)
        endif()
    endforeach()
endfunction()

# fail(<message>): one failed expectation.
function(fail msg)
    message(SEND_ERROR "${msg}")
    math(EXPR f "${failures} + 1")
    set(failures ${f} PARENT_SCOPE)
endfunction()

# match(<text> <regex> <message>): text must match regex.
function(match text regex msg)
    if(NOT text MATCHES "${regex}")
        message(SEND_ERROR "${msg}")
        math(EXPR f "${failures} + 1")
        set(failures ${f} PARENT_SCOPE)
    endif()
endfunction()

# match_count(<text> <regex> <count> <what>): regex matches text exactly
# count times (e.g. "\n[^\n]+": the data rows of a CSV file).
function(match_count text regex count what)
    string(REGEX MATCHALL "${regex}" found "${text}")
    list(LENGTH found n)
    if(NOT n EQUAL count)
        message(SEND_ERROR "${what}: expected ${count}, got ${n}:\n${text}")
        math(EXPR f "${failures} + 1")
        set(failures ${f} PARENT_SCOPE)
    endif()
endfunction()

# run(<exit code> <args...>): runs gibench in ${ROOT}, which must exit with
# code; its stdout and stderr are left in last_out and last_err.
function(run code)
    execute_process(COMMAND ${GIB} ${ARGN} WORKING_DIRECTORY ${ROOT} RESULT_VARIABLE rc OUTPUT_VARIABLE out
                    ERROR_VARIABLE err)
    set(last_out "${out}" PARENT_SCOPE)
    set(last_err "${err}" PARENT_SCOPE)
    if(NOT rc EQUAL code)
        message(SEND_ERROR "gibench ${ARGN}: exit ${rc}, expected ${code}\n${out}\n${err}")
        math(EXPR f "${failures} + 1")
        set(failures ${f} PARENT_SCOPE)
    endif()
endfunction()

# expect_refusal(<name> <regex> <rc> <stderr>): a command's result must be
# exit 2 with one stderr line matching regex (study_strict, resource_files).
function(expect_refusal name regex rc err)
    string(STRIP "${err}" err)
    string(REGEX MATCHALL "\n" lines "${err}")
    list(LENGTH lines extra)
    if(NOT rc STREQUAL "2" OR extra GREATER 0 OR NOT err MATCHES "${regex}")
        message(SEND_ERROR "${name}: expected exit 2 and one line matching '${regex}'; got exit ${rc}\n${err}")
        math(EXPR f "${failures} + 1")
        set(failures ${f} PARENT_SCOPE)
    endif()
endfunction()
