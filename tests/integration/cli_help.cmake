# Every command has help (gibench help CMD, CMD --help, CMD -h: exit 0, its
# usage line on stdout); --version names the version and commit; an unknown
# command's help is refused with one line; a plain render ends with a
# one-line summary on stdout (none under -q); progress bars stay out of
# logs (stderr is not a terminal here).
# cmake -DGIB=... -DROOT=... -DOUT=... -P cli_help.cmake
set(failures 0)
include(${CMAKE_CURRENT_LIST_DIR}/expect.cmake)

foreach(cmd methods info render reference diff compare study conformance help)
    foreach(form "help;${cmd}" "${cmd};--help" "${cmd};-h")
        run(0 ${form})
        match("${last_out}" "^usage: gibench ${cmd}" "'gibench ${form}' printed no usage of ${cmd}:\n${last_out}")
        match("${last_out}" "exit status: 0 success" "'gibench ${form}' does not give the exit codes")
    endforeach()
endforeach()
# help after other arguments still wins over parsing them
run(0 compare --scene nowhere.gltf --help)
match("${last_out}" "^usage: gibench compare" "compare --help after an argument")

run(2 help nosuch)
expect_refusal("help of an unknown command" "help: unknown command 'nosuch'" "2" "${last_err}")
run(2 nosuch --help)
expect_refusal("--help of an unknown command" "unknown command 'nosuch'" "2" "${last_err}")

run(0 --version)
match("${last_out}" "^gibench [0-9]+\\.[0-9]+\\.[0-9]+ \\(commit [^)]+\\)\n$" "--version: ${last_out}")
run(0 -v --version)
match("${last_out}" "GL renderer: [^\n]+\n" "-v --version names no GL renderer: ${last_out}")
run(2 --version render)
expect_refusal("--version with a command" "--version takes no command" "2" "${last_err}")

file(MAKE_DIRECTORY ${OUT}/cli_help)
run(0 render --scene scenes/cornell_box.gltf --method direct --size 16x16 --frames 3 --out ${OUT}/cli_help/a.png)
match("${last_out}" "^render: direct, 16x16, 3 frames \\(0 warm-up\\), median [0-9.e+-]+ ms/frame, prepare [0-9.e+-]+ ms \\([^)]+\\)+; wrote [^\n]*a\\.png\n$"
      "render printed no one-line summary:\n${last_out}")
if(last_err MATCHES "\r|ETA")
    fail("render drew a progress bar into a log:\n${last_err}")
endif()
run(0 -q render --scene scenes/cornell_box.gltf --method direct --size 16x16 --out ${OUT}/cli_help/b.png)
if(NOT last_out STREQUAL "")
    fail("render -q printed: ${last_out}")
endif()

if(failures GREATER 0)
    message(FATAL_ERROR "${failures} help/version expectation(s) failed")
endif()
message(STATUS "help, version and the render summary behave")
