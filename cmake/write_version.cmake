# Writes OUT (a C header) with the git commit of SRC, at every build, and
# touches it only when the text changes (so nothing rebuilds needlessly).
# cmake -DSRC=... -DOUT=... -DVERSION=... -P write_version.cmake
execute_process(COMMAND git -C ${SRC} rev-parse --short=12 HEAD OUTPUT_VARIABLE commit
                OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET RESULT_VARIABLE rc)
if(NOT rc EQUAL 0 OR commit STREQUAL "")
    set(commit "unknown (not a git checkout)")
else()
    execute_process(COMMAND git -C ${SRC} status --porcelain --untracked-files=no OUTPUT_VARIABLE dirty
                    ERROR_QUIET)
    if(NOT dirty STREQUAL "")
        set(commit "${commit} with local changes")
    endif()
endif()
set(text "/* Written by cmake/write_version.cmake at build time. */\n#define GIBENCH_VERSION \"${VERSION}\"\n#define GIBENCH_COMMIT \"${commit}\"\n")
if(EXISTS ${OUT})
    file(READ ${OUT} old)
endif()
if(NOT old STREQUAL text)
    file(WRITE ${OUT} "${text}")
endif()
