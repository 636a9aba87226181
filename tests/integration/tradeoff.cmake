# Per-frame convergence (render --curve-ref) and the study's speed against
# accuracy: curves in curves.csv, each run charged only the frames its error
# needs, both charts, the equal-error and equal-time tables with repeats as
# spread. cmake -DGIB=... -DROOT=... -DOUT=... -P tradeoff.cmake
set(failures 0)
include(${CMAKE_CURRENT_LIST_DIR}/expect.cmake)
set(D ${OUT}/tradeoff)
file(REMOVE_RECURSE ${D})
file(MAKE_DIRECTORY ${D})

# A reference for render's own curve.
run(0 reference --scene scenes/cornell_box.gltf --size 16x16 --spp 16 --max-bounces 1 --out ${D}/ref.exr)
run(0 reference --scene scenes/cornell_box.gltf --size 8x8 --spp 4 --out ${D}/small.exr)

# Bad --curve-ref: one line, exit 2, nothing rendered.
foreach(bad "noequals" "=x.exr" "full=")
    run(2 render --scene scenes/cornell_box.gltf --method direct --size 16x16 --out ${D}/x.exr --curve-ref ${bad})
    expect_refusal("--curve-ref ${bad}" "is not NAME=IMAGE" "2" "${last_err}")
endforeach()
run(2 render --scene scenes/cornell_box.gltf --method direct --size 16x16 --out ${D}/x.exr --curve-ref full=${D}/none.exr)
expect_refusal("missing curve reference" "--curve-ref" "2" "${last_err}")
run(2 render --scene scenes/cornell_box.gltf --method direct --size 16x16 --out ${D}/x.exr --curve-ref full=${D}/small.exr)
expect_refusal("curve reference of another size" "is 8x8, the render 16x16" "2" "${last_err}")
if(EXISTS ${D}/x.exr)
    fail("a refused render wrote its image")
endif()

# 20 frames: the error after frames 1, 2, 4, 8, 16 and 20; the time to each
# image grows; a progressive method's error falls.
run(0 render --scene scenes/cornell_box.gltf --method direct --param light_samples=1 --size 16x16 --frames 20
    --warmup 1 --out ${D}/img.exr --timings ${D}/t.json --curve-ref matched=${D}/ref.exr)
file(READ ${D}/t.json tj)
string(JSON n LENGTH "${tj}" curve)
if(NOT n EQUAL 6)
    fail("20 frames: ${n} curve points, expected 6 (1 2 4 8 16 20)")
else()
    set(prev_t 0)
    set(frames "")
    foreach(k RANGE 5)
        string(JSON f GET "${tj}" curve ${k} frame)
        string(JSON t GET "${tj}" curve ${k} time_ms)
        list(APPEND frames ${f})
        if(NOT t GREATER prev_t)
            fail("curve time does not grow at frame ${f}: ${t} after ${prev_t}")
        endif()
        set(prev_t ${t})
    endforeach()
    if(NOT frames STREQUAL "1;2;4;8;16;20")
        fail("curve frames ${frames}")
    endif()
    string(JSON e1 GET "${tj}" curve 0 matched relmse)
    string(JSON e20 GET "${tj}" curve 5 matched relmse)
    if(NOT e20 LESS e1)
        fail("the progressive method's error did not fall: frame 1 ${e1}, frame 20 ${e20}")
    endif()
endif()

# The study: 2 settings x 2 repeats, curves, tables, both charts.
set(S ${D}/study)
run(0 study tests/data/studies/tradeoff_tiny.json --out ${S})
file(READ ${S}/curves.csv curves)
match_count("${curves}" "\ncornell_box-direct-[^\n]+" 24 "curves.csv: 4 runs x 6 points")
file(READ ${S}/report.md md)
match("${md}" "equal error" "report.md has no equal-error table")
match("${md}" "equal time" "report.md has no equal-time table")
match("${md}" "\\| direct \\| `light_samples=[14]` \\| [0-9]+ \\| [0-9.e-]+ \\| [0-9.e-]+ \\[[0-9.e-]+–[0-9.e-]+\\] \\|"
      "no Pareto row with its spread over the repeats:\n${md}")
match("${md}" "\\| direct \\(matched\\) \\|" "no bounce-matched equal-time row for a direct-only method")
match("${md}" "max_bounces 8:[^;]*; max_bounces 1:" "the path tracer's curves for full GI and 1 bounce are not both given")
foreach(f chart_cornell_box_error_vs_time.png chart_cornell_box_error_vs_time_matched.png)
    if(NOT EXISTS ${S}/${f})
        fail("the study did not draw ${f}")
    endif()
endforeach()
# runs.csv: per run, the time its error needed (a method with an error
# floor is charged fewer frames than it ran), both speed-ups and whether the
# path tracer's time was extrapolated beyond its curve.
file(READ ${S}/runs.csv csv)
match("${csv}" ",seed,time_to_final_error_s,frames_to_final_error,speedup_vs_pt,speedup_vs_pt_matched,speedup_extrapolated,"
      "runs.csv lacks the speed-against-accuracy columns:\n${csv}")
match_count("${csv}" "\ncornell_box-direct-[^\n]*,[34],[0-9.e-]+,[0-9]+,[0-9.e+-]+,[0-9.e+-]+,[01]," 4
            "runs.csv: every run with its seed, time, frames and speed-ups")

if(failures GREATER 0)
    message(FATAL_ERROR "${failures} tradeoff expectation(s) failed")
endif()
message(STATUS "convergence curves and the speed-against-accuracy tables behave")
