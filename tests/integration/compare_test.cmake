# compare and study end to end: crash and hang isolation, n/a cells,
# reports, resume, study file validation.
# cmake -DGIB=... -DROOT=... -DOUT=... -DFAKE_RUN=... -P compare_test.cmake
set(failures 0)
include(${CMAKE_CURRENT_LIST_DIR}/expect.cmake)

set(ENV{GIBENCH_PLUGIN_PATH} "${FAKE_RUN}")
set(C ${OUT}/compare)
file(REMOVE_RECURSE ${C})
run(1 compare --scene scenes/cornell_box_coarse.gltf --methods direct,fake_crash,fake_hang,fake_narrow
       --out ${C} --size 16x16 --frames 2 --ref-spp 16 --ref-bounces 8 --timeout 8)
# failed runs fail the command (exit 1, as study), its last line naming them
match("${last_err}" "gibench: compare: 2 of 4 methods failed: fake_crash, fake_hang \\(see [^\n]*/report.md\\)\n$"
      "compare's verdict line:\n${last_err}")
file(READ ${C}/runs.csv csv)
match("${csv}" "\ndirect,[^\n]*,ok," "direct did not run ok:\n${csv}")
match("${csv}" "fake_crash,[^\n]*failed,\"?crashed \\(signal" "the crash was not isolated and reported:\n${csv}")
match("${csv}" "fake_hang,[^\n]*failed,timed out after" "the hang was not cut off:\n${csv}")
match("${csv}" "fake_narrow,[^\n]*n/a,fake_narrow does not handle area lights" "n/a cell missing:\n${csv}")
# issue 32 item 5: a method whose destroy() crashes is listed and costs its
# own runs only (the other method of the same compare is ok)
run(0 methods --json)
match("${last_out}" "\"fake_destroy_crash\"" "methods does not list fake_destroy_crash:\n${last_out}")
set(CD ${OUT}/compare_destroy)
file(REMOVE_RECURSE ${CD})
run(1 compare --scene scenes/cornell_box_coarse.gltf --methods direct,fake_destroy_crash
       --out ${CD} --size 16x16 --frames 1 --ref-spp 16 --ref-bounces 8 --timeout 20)
file(READ ${CD}/runs.csv csv_d)
match("${csv_d}" "\ndirect,[^\n]*,ok," "direct did not run ok beside a crashing destroy():\n${csv_d}")
match("${csv_d}" "fake_destroy_crash,[^\n]*failed,\"?crashed \\(signal"
      "the crash in destroy() was not isolated and reported:\n${csv_d}")
# render --animate tells update() what the animation moves: vertices on a
# deforming scene, transforms when objects move, lights when a light moves,
# the camera when the view's camera node is animated, and nothing else.
# want: scene, then changed_vertices transforms lights camera.
set(stat_keys changed_vertices changed_transforms changed_lights changed_camera)
foreach(case "cornell_deform 1 1 0 0" "cornell_moving 0 1 0 0" "stress/moving_light 0 0 1 0"
             "stress/moving_camera 0 0 0 1" "stress/hulls_overlap 0 1 0 0")
    separate_arguments(case)
    list(GET case 0 sc)
    list(SUBLIST case 1 4 want)
    string(REPLACE "/" "_" tag "${sc}")
    run(0 render --scene scenes/${sc}.gltf --method fake_changes --size 8x8 --time 0 --animate 2 --frames 3
           --out ${OUT}/fake_changes_${tag}.exr --timings ${OUT}/fake_changes_${tag}.json)
    file(READ ${OUT}/fake_changes_${tag}.json fj)
    string(JSON upd GET "${fj}" stats updates)
    set(got "")
    set(same 1)
    foreach(i RANGE 3)
        list(GET stat_keys ${i} key)
        list(GET want ${i} w)
        string(JSON v GET "${fj}" stats ${key})
        list(APPEND got ${v})
        if(NOT v EQUAL w)
            set(same 0)
        endif()
    endforeach()
    if(NOT upd EQUAL 2 OR NOT same)
        fail("${sc}: update() saw ${upd} updates (want 2), changed vertices/transforms/lights/camera ${got} (want ${want})")
    endif()
endforeach()

# A deforming scene (morph targets): methods without GI_CAP_DEFORMATION are
# n/a even for a still frame (their CPU copy of the mesh is the rest pose);
# avg and direct, which claim it, run.
set(D ${OUT}/compare_deform)
file(REMOVE_RECURSE ${D})
run(0 compare --scene scenes/cornell_deform.gltf --methods avg,csm,direct --out ${D} --size 16x16 --frames 1
       --ref-spp 8 --ref-bounces 4 --time 2 --timeout 120)
file(READ ${D}/runs.csv dcsv)
match("${dcsv}" "\ncsm,[^\n]*n/a,csm does not handle deforming meshes" "csm not n/a on a deforming scene:\n${dcsv}")
match("${dcsv}" "\ndirect,[^\n]*,ok," "direct did not run ok on the deforming scene:\n${dcsv}")
match("${dcsv}" "\navg,[^\n]*,ok," "avg did not run ok on the deforming scene:\n${dcsv}")
foreach(f report.md index.html reference_b8.exr reference_b1.exr direct/image.exr direct/image.png direct/heatmap.png direct/timings.json direct/result.json)
    if(NOT EXISTS ${C}/${f})
        fail("compare did not write ${f}")
    endif()
endforeach()
file(READ ${C}/report.md md)
match("${md}" "GL renderer: " "report names no GL renderer")
# The page's viewer holds the full reference, the bounce-matched one
# (direct: 1 bounce) and the run.
file(READ ${C}/index.html page)
match("${page}" "reference, full GI \\(8 bounces\\)" "the viewer has no full-GI reference")
match("${page}" "reference, 1 bounce[^s]" "the viewer has no bounce-matched reference")
# Resume: a second run reuses what is done (the result file is not rewritten:
# a run again records other timings, so its content would change; compared
# by content, no 1 s wait for the file's timestamp to tell).
file(SHA256 ${C}/direct/result.json before)
run(0 compare --scene scenes/cornell_box_coarse.gltf --methods direct,fake_narrow
       --out ${C} --size 16x16 --frames 2 --ref-spp 16 --ref-bounces 8 --timeout 8)
file(SHA256 ${C}/direct/result.json after)
if(NOT before STREQUAL after)
    fail("resume re-ran a finished method")
endif()
# A changed configuration is run again.
run(0 compare --scene scenes/cornell_box_coarse.gltf --methods direct --param direct.light_samples=2
       --out ${C} --size 16x16 --frames 2 --ref-spp 16 --ref-bounces 8)
file(SHA256 ${C}/direct/result.json changed)
if(before STREQUAL changed)
    fail("a changed configuration was not re-run")
endif()
run(2 compare --scene scenes/cornell_box_coarse.gltf --methods nope --out ${C})
match("${last_err}" "no method 'nope'" "unknown method message: ${last_err}")
run(2 compare --scene scenes/cornell_box_coarse.gltf --methods direct --param other.x=1 --out ${C})

# study
set(S ${OUT}/study)
file(REMOVE_RECURSE ${S})
# a study with a failed run (fake_crash) exits 1, after writing its report
run(1 study tests/data/studies/tiny.json --out ${S})
match("${last_err}" "gibench: study: 1 of 4 runs failed" "the failed run is not the verdict:\n${last_err}")
file(READ ${S}/runs.csv csv)
match_count("${csv}" "\n[^\n]+" 4 "tiny study: runs")
match("${csv}" "light_samples=8" "sweep value missing")
match("${csv}" "fake_crash[^\n]*failed" "crashing method not reported in the study")
match("${csv}" "fake_narrow[^\n]*n/a" "n/a method missing in the study")
if(NOT EXISTS ${S}/chart_cornell_box_coarse_error_vs_time.png)
    fail("no chart")
endif()
file(READ ${S}/report.md md)
match("${md}" "speed-up" "no equal-error speed-up table")
match("${md}" "Path tracer convergence" "no convergence curve")
run(2 study tests/data/studies/bad_param.json --out ${S}/bad)
match("${last_err}" "/methods/0: direct: light_samples=0 is outside" "bad sweep value: ${last_err}")
run(2 study tests/data/studies/bad_key.json --out ${S}/bad)
match("${last_err}" "/frame: unknown key" "unknown key: ${last_err}")
run(2 study tests/data/studies/missing.json --out ${S}/bad)

if(failures GREATER 0)
    message(FATAL_ERROR "${failures} compare/study expectation(s) failed")
endif()
message(STATUS "compare and study behave")
