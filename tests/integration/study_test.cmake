# Study files: every committed study (harness/studies/*.json and each
# paper's plugins/<id>/study*.json) loads and expands (--dry-run),
# malformed entries and charts are refused, and a tiny study with the
# features of plugins/csm/study.json runs end to end.
# cmake -DGIB=... -DROOT=... -DOUT=... -P study_test.cmake
set(failures 0)
include(${CMAKE_CURRENT_LIST_DIR}/expect.cmake)

# Every shipped study file is valid: scenes load, methods and parameter
# values exist, charts are well formed.
file(GLOB studies ${ROOT}/harness/studies/*.json ${ROOT}/plugins/*/study*.json)
foreach(s ${studies})
    run(0 study ${s} --dry-run)
    match("${last_out}" "^study [^\n]*: [1-9][0-9]* runs" "${s}: --dry-run printed no plan:\n${last_out}")
endforeach()
run(0 study plugins/csm/study.json --dry-run)
match("${last_out}" "label=table1 N=128 M=128 enumeration=hilbert" "csm.json: no Table 1 run at N = 128, Hilbert")
match("${last_out}" "no-cache not-compared label=table1" "csm.json: Table 1 runs must skip the cache and the references")
match("${last_out}" "animate not-compared label=moving" "csm.json: no animated run")

# The demo (make demo) runs the baseline and every method of the five
# papers, and times csm's and cssm_hrc's precomputation cold in both
# repeats (no cache: a repeat would otherwise read the first one's maps)
run(0 study harness/studies/demo.json --dry-run)
foreach(mn direct:8 csm:4 cssm_hrc:4 implicit_vis:2 vlf:2 avg:4)
    string(REPLACE ":" ";" mn "${mn}")
    list(GET mn 0 m)
    list(GET mn 1 n)
    match_count("${last_out}" "\nrun cornell_box-${m}-" ${n} "demo.json: runs of ${m}")
endforeach()
foreach(m csm cssm_hrc)
    match("${last_out}" "\nrun cornell_box-${m}-[^\n]* no-cache " "demo.json: ${m} runs with the cache:\n${last_out}")
endforeach()

run(2 study tests/data/studies/bad_entry_key.json --dry-run)
match("${last_err}" "/methods/0/frame: unknown key" "an unknown method-entry key was not named:\n${last_err}")
run(2 study tests/data/studies/bad_chart.json --dry-run)
match("${last_err}" "/charts/0: \"file\" must be a plain file name" "a chart escaping the output was accepted:\n${last_err}")

# The tiny csm study end to end.
set(S ${OUT}/study_csm_tiny)
file(REMOVE_RECURSE ${S})
run(0 study tests/data/studies/csm_tiny.json --out ${S})
# the reference stage reports each reference as it is done (issue 33: it was
# silent for a minute at the demo's size)
match("${last_err}" "study: reference bunny_env \\(4 bounces\\): 16 spp in [0-9.]+ s\n"
      "no progress line for the full-GI reference:\n${last_err}")
match("${last_err}" "study: bounce-matched reference bunny_env \\(1 bounces\\): 16 spp in [0-9.]+ s\n"
      "no progress line for the bounce-matched reference:\n${last_err}")
match("${last_err}" "study: convergence bunny_env \\(1 bounces, 4 spp\\): 4 spp in [0-9.]+ s\n"
      "no progress line for the convergence images:\n${last_err}")
file(READ ${S}/runs.csv csv)
match_count("${csv}" "\n[^\n]+" 6 "csm_tiny: runs")
match("${csv}" "^run,[^\n]*,label,width,height,prepare_depth_render_ms,prepare_compress_ms[^\n]*,stat_ratio,"
      "runs.csv lacks the label, prepare-stage or stats columns:\n${csv}")
# Table-style rows: 8x8, not compared (no metrics), fresh precomputation.
match("${csv}" "\nbunny_alone_env-csm-[^\n]*N=4,M=16,enumeration=hilbert[^\n]*,ok,[^\n]*,table,8,8,[0-9.e+-]+,[0-9.e+-]+"
      "the N = 4 Hilbert table row is missing or lacks its precompute timings:\n${csv}")
match("${csv}" "\nbunny_env-csm-[^\n]*,ok,[^\n]*,error,16,16" "the compared row is missing:\n${csv}")
match("${csv}" "\nbunny_env-csm-[^\n]*,ok,[^\n]*,process-cpu-time-around-glFinish,"
      "\"timer\": \"cputime\" did not reach the runs:\n${csv}")
file(READ ${S}/frames.csv frames)
match_count("${frames}" "\nbunny_teapot_moving-csm-[^,]*,moving,[0-9]+," 3 "frames.csv: timed frames of the moving run")
foreach(f chart_ratio.png chart_frames.png chart_bunny_env_error_vs_time.png report.md)
    if(NOT EXISTS ${S}/${f})
        fail("csm_tiny did not write ${f}")
    endif()
endforeach()
file(GLOB refs ${S}/references/*.exr)
foreach(r ${refs})
    if(r MATCHES "bunny_alone|moving")
        fail("a reference was rendered for a run with \"compare\": false: ${r}")
    endif()
endforeach()
file(READ ${S}/report.md md)
match("${md}" "chart_ratio.png" "report.md does not show the study's own chart")

if(failures GREATER 0)
    message(FATAL_ERROR "${failures} study expectation(s) failed")
endif()
message(STATUS "study files and features behave")
