# Animated runs compared frame by frame (render --frames-out, a reference
# per frame, flicker and the reference's noise floor), leaked energy and
# memory in a study's records. Every per-frame number is recomputed by
# anim_check.py through gibench diff. cmake -DGIB=... -DROOT=... -DOUT=...
# -DPYTHON=... -P anim_study.cmake
set(failures 0)
include(${CMAKE_CURRENT_LIST_DIR}/expect.cmake)
set(D ${OUT}/anim_study)
file(REMOVE_RECURSE ${D})
file(MAKE_DIRECTORY ${D}/frames)

# --frames-out: a pattern with exactly one %d and an image extension, else exit 2 before rendering
foreach(bad "${D}/frames/f.exr" "${D}/frames/f%d_%d.exr" "${D}/frames/f%s.exr" "${D}/frames/f%04d.txt")
    run(2 render --scene scenes/cornell_moving.gltf --method direct --size 16x16 --frames 3 --animate 5
        --out ${D}/x.exr --frames-out ${bad})
    expect_refusal("--frames-out ${bad}" "--frames-out" "2" "${last_err}")
endforeach()
# every frame written; the last is the image --out writes
run(0 render --scene scenes/cornell_moving.gltf --method direct --size 16x16 --frames 3 --animate 5
    --out ${D}/last.exr --frames-out ${D}/frames/f%03d_100%%.exr)
foreach(f 000 001 002)
    if(NOT EXISTS ${D}/frames/f${f}_100%.exr)
        fail("render --frames-out wrote no frame ${f}")
    endif()
endforeach()
if(EXISTS ${D}/frames/f003_100%.exr)
    fail("render --frames-out wrote a frame too many")
endif()
diff_metric(${D}/frames/f002_100%.exr ${D}/last.exr rmse last_rmse)
if(NOT last_rmse EQUAL 0)
    fail("the last frame written differs from the image (rmse ${last_rmse})")
endif()
diff_metric(${D}/frames/f000_100%.exr ${D}/last.exr rmse first_rmse)
if(NOT first_rmse GREATER 0)
    fail("frames 0 and 2 of a moving scene are the same image")
endif()

# the study: 2 animated runs (4 frames each) and a still one
set(S ${D}/study)
run(0 study tests/data/studies/anim_tiny.json --out ${S})
execute_process(COMMAND ${PYTHON} ${CMAKE_CURRENT_LIST_DIR}/anim_check.py ${GIB} ${S} RESULT_VARIABLE rc
                OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
    fail("anim_check.py: ${out}${err}")
endif()
file(READ ${S}/report.md md)
match("${md}" "## Animated runs, frame by frame" "report.md has no animation section")
match_count("${md}" "\n\\| cornell_moving-direct-[0-9a-f]+ \\| direct \\| `light_samples=[0-9]+` \\| moving \\| 4 \\| 5 \\|" 2
            "report.md: a row per animated run")
match("${md}" "peak RSS \\(MiB\\) \\| data \\(MiB\\)" "the equal-error table has no memory columns")
file(READ ${S}/runs.csv csv)
match("${csv}" ",leaked_energy_full,dark_fraction_full,[^\n]*,peak_rss_mib,[^\n]*,anim_flicker_full,anim_flicker_matched,"
      "runs.csv lacks the leak, memory or flicker columns")
foreach(c relmse frame_ms change)
    if(NOT EXISTS ${S}/chart_cornell_moving_anim_${c}.png)
        fail("the study drew no chart_cornell_moving_anim_${c}.png")
    endif()
endforeach()
# the still run keeps its reference set's name; the frames get their own
foreach(f cornell_moving_b8_32spp_center.exr cornell_moving_24x24_t0.6_b8_32spp_center.exr
          cornell_moving_24x24_t0.6_b8_32spp_center_alt.exr cornell_moving_24x24_t0.6_b1_32spp_center.exr)
    if(NOT EXISTS ${S}/references/${f})
        fail("no reference ${f}")
    endif()
endforeach()
file(GLOB conv ${S}/references/cornell_moving_24x24_t*_conv_*)
if(conv)
    fail("a frame's reference set got a convergence curve: ${conv}")
endif()
# resuming runs nothing again, and a result made before the leaked energy
# existed gets it on resume, without a render (one resume for both: CI time)
file(GLOB results ${S}/runs/*/result.json)
list(GET results 0 res)
file(READ ${res} j)
string(JSON leak GET "${j}" metrics full leaked_energy)
string(JSON j REMOVE "${j}" metrics full leaked_energy)
string(JSON j REMOVE "${j}" metrics matched leaked_energy)
file(WRITE ${res} "${j}")
file(TIMESTAMP ${res} before)
run(0 study tests/data/studies/anim_tiny.json --out ${S})
string(REGEX MATCHALL "cached cornell_moving-" hits "${last_err}") # not through a function: the text holds semicolons
list(LENGTH hits n)
if(NOT n EQUAL 3)
    fail("a resumed study reran runs (${n} of 3 cached):\n${last_err}")
endif()
file(READ ${res} j)
string(JSON leak2 ERROR_VARIABLE e GET "${j}" metrics full leaked_energy)
if(NOT leak2 STREQUAL leak)
    fail("an old result did not get its leaked energy back on resume (${leak2} vs ${leak})")
endif()

if(failures GREATER 0)
    message(FATAL_ERROR "${failures} animation expectation(s) failed")
endif()
message(STATUS "animated runs are compared frame by frame; leak and memory are recorded")
