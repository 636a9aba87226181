# Bash completion (scripts/gen-completion.py, installed by `make`): generated
# from this build's methods, it completes commands, options, methods and
# parameter values. cmake -DGIB=... -DROOT=... -DOUT=... -DPYTHON=... -P completion.cmake
set(failures 0)
include(${CMAKE_CURRENT_LIST_DIR}/expect.cmake)
set(F ${OUT}/gibench-completion.bash)
file(REMOVE ${F})
execute_process(COMMAND ${PYTHON} ${ROOT}/scripts/gen-completion.py ${GIB} ${F} RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT EXISTS ${F})
    message(FATAL_ERROR "gen-completion.py failed (${rc}): ${err}")
endif()
set(script "source '${F}'
t() { COMP_LINE=\"$*\"; COMP_POINT=\${#COMP_LINE}; COMP_WORDS=(\"$@\"); COMP_CWORD=$((\${#COMP_WORDS[@]}-1)); COMPREPLY=(); _gibench; echo \"[$*] -> \${COMPREPLY[*]}\"; }
t gibench re
t gibench render --method ''
t gibench render --method csm --param fil
t gibench render --sc
t gibench compare --param csm.filter=p
t gibench help st
t gibench -q stu
")
execute_process(COMMAND bash -c "${script}" RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT err STREQUAL "")
    fail("sourcing the completion failed (${rc}): ${err}")
endif()
match("${out}" "\\[gibench re\\] -> render reference\n" "commands:\n${out}")
match("${out}" "\\[gibench render --method \\] -> [^\n]*csm[^\n]*direct" "methods:\n${out}")
match("${out}" "\\[gibench render --method csm --param fil\\] -> filter=nearest filter=pcf" "enum values:\n${out}")
match("${out}" "\\[gibench render --sc\\] -> --scene\n" "options:\n${out}")
# readline replaces the text after the '=' (a COMP_WORDBREAKS character) only
match("${out}" "\\[gibench compare --param csm.filter=p\\] -> pcf\n" "compare's method.k=v:\n${out}")
match("${out}" "\\[gibench help st\\] -> study\n" "help's commands:\n${out}")
match("${out}" "\\[gibench -q stu\\] -> study\n" "commands after a global option:\n${out}")
# The same in a real interactive bash (a pseudo-terminal, TAB typed): bash
# splits '--param k=v' at '=' before the completion sees it.
execute_process(COMMAND ${PYTHON} ${CMAKE_CURRENT_LIST_DIR}/completion_pty.py ${F} TIMEOUT 120
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
    fail("interactive bash completion (${rc}):\n${out}${err}")
endif()
if(failures GREATER 0)
    message(FATAL_ERROR "${failures} completion expectation(s) failed")
endif()
message(STATUS "bash completion behaves")
