# gibench diff end to end: an image against itself has no error; bad input
# exits 2 with one line; heat maps are written as readable PNGs; a render
# against its own PNG differs by 8-bit quantisation only.
# Run by ctest as: cmake -DGIB=... -DSCENES=... -DDATA=... -DOUT=... [-DRENDER=base] -P diff_test.cmake

set(failures 0)

# run(<expected exit> <out var> <args...>): runs gibench; on failure exits 2
# only with exactly one line on stderr.
function(run code outvar)
    execute_process(COMMAND ${GIB} ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
    string(STRIP "${err}" err_stripped)
    string(REGEX MATCHALL "\n" newlines "${err_stripped}")
    list(LENGTH newlines extra_lines)
    if(NOT rc EQUAL code OR (NOT code EQUAL 0 AND (extra_lines GREATER 0 OR err_stripped STREQUAL "")))
        message(SEND_ERROR "gibench ${ARGN}: expected exit ${code} (one stderr line on failure);\n"
                           "got exit ${rc}\nstdout: ${out}\nstderr: ${err}")
        math(EXPR f "${failures} + 1")
        set(failures ${f} PARENT_SCOPE)
    endif()
    set(${outvar} "${out}${err}" PARENT_SCOPE)
endfunction()

# check(<condition...> MESSAGE <text>)
macro(check)
    cmake_parse_arguments(C "" "MESSAGE" "" ${ARGN})
    if(NOT (${C_UNPARSED_ARGUMENTS}))
        message(SEND_ERROR "${C_MESSAGE}")
        math(EXPR failures "${failures} + 1")
    endif()
endmacro()

if(RENDER)
    # The direct render's EXR against its own PNG: only the PNG's 8-bit
    # quantisation (and its clamp, invisible after tonemapping) differs.
    run(0 j diff ${RENDER}.exr ${RENDER}.png --json)
    string(JSON psnr GET "${j}" psnr)
    string(JSON flip GET "${j}" flip)
    string(JSON ssim GET "${j}" ssim)
    check(psnr GREATER 45 MESSAGE "EXR vs its PNG: PSNR ${psnr} dB, expected > 45 (PNG decoded to linear?)")
    check(flip LESS 0.01 MESSAGE "EXR vs its PNG: FLIP ${flip}, expected < 0.01")
    check(ssim GREATER 0.99 MESSAGE "EXR vs its PNG: SSIM ${ssim}, expected > 0.99")
    if(failures GREATER 0)
        message(FATAL_ERROR "${failures} diff expectation(s) failed")
    endif()
    return()
endif()

# A small EXR (32 x 32): HDR-FLIP of a 512 x 256 image took some 5 s a call.
set(IMG ${DATA}/flip/render_ref.exr)

# Identity: every error 0, SSIM 1, FLIP 0, PSNR infinite (null in JSON).
run(0 j diff ${IMG} ${IMG} --json)
foreach(key rmse mse relmse mae flip mean_lum_diff_pct pixels_excluded)
    string(JSON v GET "${j}" ${key})
    check(v EQUAL 0 MESSAGE "diff of an image with itself: ${key} = ${v}, expected 0")
endforeach()
string(JSON v GET "${j}" ssim)
check(v EQUAL 1 MESSAGE "diff of an image with itself: ssim = ${v}, expected 1")
string(JSON v TYPE "${j}" psnr)
check(v STREQUAL "NULL" MESSAGE "diff of an image with itself: psnr is ${v}, expected null (infinite)")
string(JSON w GET "${j}" test width)
string(JSON n GET "${j}" reference nonfinite_pixels)
check(w EQUAL 32 AND n EQUAL 0 MESSAGE "diff --json: test width ${w}, reference non-finite ${n}")

run(0 text diff ${IMG} ${IMG})
foreach(line "rmse       0" "ssim       1.000000" "flip       0.000000" "psnr       inf dB")
    string(FIND "${text}" "${line}" pos)
    check(NOT pos EQUAL -1 MESSAGE "diff (human): no line '${line}' in:\n${text}")
endforeach()

# Heat maps: written, and readable again as images of the map plus a bar.
file(REMOVE ${OUT}/diff_heat.png ${OUT}/diff_flip.png)
run(0 text diff ${IMG} ${IMG} --heatmap ${OUT}/diff_heat.png --flip-map ${OUT}/diff_flip.png --exposure -1)
check(EXISTS ${OUT}/diff_heat.png AND EXISTS ${OUT}/diff_flip.png MESSAGE "diff --heatmap/--flip-map wrote no file")
run(0 j diff ${OUT}/diff_heat.png ${OUT}/diff_heat.png --json)
string(JSON w GET "${j}" test width)
string(JSON h GET "${j}" test height)
# (at least as high as the image: a small image gets the colour bar's own height)
check(w GREATER 32 AND h GREATER_EQUAL 32 MESSAGE "heat map is ${w}x${h}, expected wider than 32 and at least 32 high")

# The trivial answer --black: a black image of the reference's size; its
# mean luminance and leaked energy are 0, its relMSE lies in (0, 1) (each
# pixel's r^2 / (r^2 + eps) is below 1), its path is "black".
run(0 j diff --black ${IMG} --json)
string(JSON t GET "${j}" test path)
string(JSON w GET "${j}" test width)
string(JSON lum GET "${j}" mean_lum_test)
string(JSON leak GET "${j}" leaked_energy)
string(JSON rel GET "${j}" relmse)
check(t STREQUAL "black" AND w EQUAL 32 MESSAGE "diff --black: test '${t}', width ${w}")
check(lum EQUAL 0 AND leak EQUAL 0 MESSAGE "diff --black: mean luminance ${lum}, leaked energy ${leak}, expected 0")
check(rel GREATER 0 AND rel LESS 1 MESSAGE "diff --black: relMSE ${rel}, expected in (0, 1)")
run(2 text diff --black)
run(2 text diff --black ${IMG} ${IMG})

# Bad input and usage: exit 2 with one line.
run(2 text diff ${OUT}/no-such-image.exr ${IMG})
string(FIND "${text}" "no-such-image.exr" pos)
check(NOT pos EQUAL -1 MESSAGE "missing file not named: ${text}")
run(2 text diff ${IMG} ${DATA}/valid/env/sky.pfm)
string(FIND "${text}" "image sizes differ" pos)
check(NOT pos EQUAL -1 MESSAGE "size mismatch not reported: ${text}")
run(2 text diff ${IMG})
run(2 text diff ${IMG} ${IMG} ${IMG})
run(2 text diff ${IMG} ${IMG} --fast)
run(2 text diff ${IMG} ${IMG} --heatmap ${OUT}/heat.bmp)
run(2 text diff ${IMG} ${IMG} --exposure lots)
run(2 text diff ${IMG} ${IMG} --ppd 0)
# An unwritable heat map is a failure while running (1).
run(1 text diff ${IMG} ${IMG} --heatmap ${OUT}/missing-dir/heat.png)

if(failures GREATER 0)
    message(FATAL_ERROR "${failures} diff expectation(s) failed")
endif()
message(STATUS "all diff expectations met")
