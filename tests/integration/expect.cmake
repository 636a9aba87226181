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

# end_checks(): the end of a script: FATAL_ERROR with the count when an
# expectation failed (a macro, so that it reads the script's `failures`).
macro(end_checks)
    if(failures GREATER 0)
        message(FATAL_ERROR "${failures} check(s) failed")
    endif()
endmacro()

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

# diff_metric(<test image> <reference image> <key> <out var>): one number of
# `gibench diff --json` (relmse, mean_lum_diff_pct, ...); a failing diff is
# a failed set-up (FATAL_ERROR).
function(diff_metric test ref key out_var)
    execute_process(COMMAND ${GIB} diff ${test} ${ref} --json RESULT_VARIABLE rc OUTPUT_VARIABLE j)
    if(NOT rc EQUAL 0)
        message(FATAL_ERROR "gibench diff ${test} ${ref} failed (${rc})")
    endif()
    string(JSON v GET "${j}" ${key})
    set(${out_var} ${v} PARENT_SCOPE)
endfunction()

# expect_beats_reference(<method> <scene file> LIMIT <relMSE> MEAN <pct> SPP <n> BOUNCES <n>
#                        [TRIVIAL <relMSE>] [BLACK] [SIZE <WxH>] [METHOD_ARGS <args>...]
#                        [DIRECT_ARGS <args>...]):
# a method against the Embree reference (`gibench reference`, SPP samples,
# BOUNCES bounces, one thread) at SIZE (default 32x32), beside the trivial
# answers scored on the same reference: the unshadowed `direct` plugin
# and, with BLACK, a black image (the reference times 0, by oiiotool).
# The method's relMSE must be under LIMIT, each trivial answer's over
# TRIVIAL (default LIMIT), and the method's image mean within MEAN % of
# the reference's. METHOD_ARGS and DIRECT_ARGS go to the two renders.
# Images: ${OUT}/<method>_{ref,vs_ref,direct,black}_<scene name>.exr.
function(expect_beats_reference method scene)
    cmake_parse_arguments(PARSE_ARGV 2 A "BLACK" "LIMIT;TRIVIAL;MEAN;SPP;BOUNCES;SIZE" "METHOD_ARGS;DIRECT_ARGS")
    if(A_UNPARSED_ARGUMENTS OR NOT DEFINED A_LIMIT OR NOT DEFINED A_MEAN OR NOT DEFINED A_SPP
       OR NOT DEFINED A_BOUNCES)
        message(FATAL_ERROR "expect_beats_reference(${method} ${scene} ${ARGN}): LIMIT, MEAN, SPP and BOUNCES "
                            "are required (left over: ${A_UNPARSED_ARGUMENTS})")
    endif()
    if(NOT DEFINED A_TRIVIAL)
        set(A_TRIVIAL ${A_LIMIT})
    endif()
    if(NOT DEFINED A_SIZE)
        set(A_SIZE 32x32)
    endif()
    get_filename_component(name ${scene} NAME_WE)
    set(ref ${OUT}/${method}_ref_${name}.exr)
    set(img ${OUT}/${method}_vs_ref_${name}.exr)
    set(direct ${OUT}/${method}_direct_${name}.exr)
    expect(0 "" reference --scene ${scene} --size ${A_SIZE} --spp ${A_SPP} --max-bounces ${A_BOUNCES} --threads 1
           --out ${ref})
    expect(0 "" render --scene ${scene} --method ${method} --size ${A_SIZE} ${A_METHOD_ARGS} --out ${img})
    expect(0 "" render --scene ${scene} --method direct --size ${A_SIZE} ${A_DIRECT_ARGS} --out ${direct})
    diff_metric(${img} ${ref} relmse m_relmse)
    diff_metric(${img} ${ref} mean_lum_diff_pct m_mean)
    diff_metric(${direct} ${ref} relmse direct_relmse)
    diff_metric(${direct} ${ref} mean_lum_diff_pct direct_mean)
    set(trivial "direct ${direct_relmse}")
    set(status "${name}: ${method} relMSE ${m_relmse}, mean ${m_mean} %; unshadowed direct relMSE ${direct_relmse}, mean ${direct_mean} %")
    set(trivial_fail FALSE)
    if(NOT direct_relmse GREATER ${A_TRIVIAL})
        set(trivial_fail TRUE)
    endif()
    if(A_BLACK)
        set(black ${OUT}/${method}_black_${name}.exr)
        execute_process(COMMAND oiiotool ${ref} --mulc 0,0,0,1 -o ${black} RESULT_VARIABLE rc)
        if(NOT rc EQUAL 0)
            message(FATAL_ERROR "oiiotool could not write the black image (${rc})")
        endif()
        diff_metric(${black} ${ref} relmse black_relmse)
        string(APPEND trivial ", black ${black_relmse}")
        string(APPEND status "; black ${black_relmse}")
        if(NOT black_relmse GREATER ${A_TRIVIAL})
            set(trivial_fail TRUE)
        endif()
    endif()
    message(STATUS "${status}")
    if(NOT m_relmse LESS ${A_LIMIT})
        fail("${name}: ${method} relMSE ${m_relmse} not below ${A_LIMIT}")
    endif()
    if(trivial_fail)
        fail("${name}: a trivial answer scores under ${A_TRIVIAL}: ${trivial}")
    endif()
    if(m_mean LESS -${A_MEAN} OR m_mean GREATER ${A_MEAN})
        fail("${name}: ${method} image mean ${m_mean} % off the reference's by more than ${A_MEAN} %")
    endif()
    set(failures ${failures} PARENT_SCOPE)
endfunction()
