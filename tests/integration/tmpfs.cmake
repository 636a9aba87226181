# Shared set-up of the full-disk tests (full_disk, study_full_disk_run):
# include()d after expect.cmake.

# small_tmpfs(<dir>): mounts a fresh 256 KiB tmpfs on dir (unmounting one a
# failed run left there), to fill. Needs root: otherwise, or when the mount
# fails, prints "SKIPPED: ..." (the tests' SKIP_REGULAR_EXPRESSION) and
# returns from the calling script (a macro's return() does).
macro(small_tmpfs dir)
    execute_process(COMMAND id -u OUTPUT_VARIABLE uid OUTPUT_STRIP_TRAILING_WHITESPACE)
    if(NOT uid STREQUAL "0")
        message(STATUS "SKIPPED: not running as root (uid ${uid}), so no tmpfs can be mounted to fill")
        return()
    endif()
    execute_process(COMMAND umount ${dir} RESULT_VARIABLE ignored ERROR_QUIET)
    file(REMOVE_RECURSE ${dir})
    file(MAKE_DIRECTORY ${dir})
    execute_process(COMMAND mount -t tmpfs -o size=256k tmpfs ${dir} RESULT_VARIABLE rc ERROR_VARIABLE err)
    if(NOT rc EQUAL 0)
        message(STATUS "SKIPPED: cannot mount a tmpfs (${err})")
        return()
    endif()
endmacro()
