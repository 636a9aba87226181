# Bounded and unambiguous input (issue 32 items 10-12), each case refused
# (or warned about) in well under a second where the old code spent tens of
# seconds and gigabytes, or took the input silently:
#  - declared sizes checked against gi/limits.h before decoding: a 533-byte
#    EXR declaring 8,000,000 x 32 pixels, an 8192^2 PNG listed as two
#    textures, image sizes over 8192 a side or 4096^2 pixels in all;
#  - keys compared after unescaping ("fr\u0061mes" is "frames") in studies
#    and saved views; a scene listed twice in a study;
#  - plugin folders: a FIFO skipped unopened, a world-writable folder
#    refused, a constructor's printing kept out of `methods --json`, the
#    compiled-in folder overridden by GIBENCH_PLUGIN_DIR;
#  - report.md escapes HTML in study names; GIBENCH_TIMER=bogus refused.
# The crafted files are written at test time (gen_hostile.py).
# cmake -DGIB=... -DROOT=... -DOUT=... -DFAKE_PRINT=... -P input_limits.cmake
set(failures 0)
include(${CMAKE_CURRENT_LIST_DIR}/expect.cmake)
set(D ${OUT}/input_limits)
file(REMOVE_RECURSE ${D})
file(MAKE_DIRECTORY ${D})
execute_process(COMMAND /usr/bin/python3 ${CMAKE_CURRENT_LIST_DIR}/gen_hostile.py ${D} RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
    message(FATAL_ERROR "gen_hostile.py failed (${rc})")
endif()
set(SCENE scenes/cornell_box_coarse.gltf)

# refused(<name> <regex> <args...>): exit 2, one stderr line matching regex,
# within 120 s (the old code took longer or more memory than a test has;
# the new one a second at most, the decoding of one 8192^2 texture).
function(refused name regex)
    execute_process(COMMAND ${GIB} ${ARGN} WORKING_DIRECTORY ${ROOT} TIMEOUT 120
                    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
    expect_refusal(${name} "${regex}" "${rc}" "${err}")
    set(failures ${failures} PARENT_SCOPE)
endfunction()
function(study name text regex)
    # the study's scenes are named from the tree's root (its "base")
    if(NOT text MATCHES "\"base\"")
        string(REGEX REPLACE "^[{]" "{\"base\": \"${ROOT}\", " text "${text}")
    endif()
    file(WRITE ${D}/${name}.json "${text}")
    refused(${name} "${regex}" study ${D}/${name}.json --dry-run)
    set(failures ${failures} PARENT_SCOPE)
endfunction()

# ---- item 10: declared sizes against the stated limits ----
execute_process(COMMAND ${GIB} diff ${D}/huge.exr ${D}/huge.exr WORKING_DIRECTORY ${ROOT} TIMEOUT 60
                RESULT_VARIABLE rc ERROR_VARIABLE err)
match("${rc}|${err}" "^2\\|.*huge\\.exr: image size 8000000x32 with 1 channels exceeds the limit of 33554432 pixels"
      "huge.exr: expected exit 2 and the limit in the message; got exit ${rc}: ${err}")
refused(big_textures "/images/1: images exceed the limit of 67108864 texels in all" info ${D}/big_tex.gltf)
refused(render_size "render: --size '8192x4096' is not WxH with 1\\.\\.8192 each and at most 16777216 pixels"
        render --scene ${SCENE} --method direct --size 8192x4096 --out ${D}/x.exr)
refused(reference_size "reference: --size '16384x16384' is not WxH with 1\\.\\.8192"
        reference --scene ${SCENE} --size 16384x16384 --out ${D}/x.exr)
study(study_size "{\"scenes\": [\"${SCENE}\"], \"size\": [8192, 8192], \"methods\": \"all\"}"
      "/size: width and height must be integers, 1\\.\\.8192 each and at most 16777216 pixels")
# a saved view named as a study's camera: its size is checked as it is read
function(write_view path size extra)
    file(WRITE ${path} "{\"gibench_view\": 1, \"scene\": \"${ROOT}/${SCENE}\", \"method\": \"direct\", \"params\": [],
  \"width\": ${size}, \"height\": ${size}, \"frames\": 3, \"seed\": 7, \"time\": 0, \"exposure\": 1,${extra}
  \"camera\": {\"eye\": [4.5, 3.5, -6.0], \"forward\": [-0.25, -0.1, 1.0], \"up\": [0, 1, 0], \"yfov\": 0.7,
              \"znear\": 0.01, \"zfar\": 100}, \"nodes\": []}")
endfunction()
write_view(${D}/view_ok.json 64 "")
write_view(${D}/view_big.json 16384 "")
write_view(${D}/view_dup.json 64 " \"se\\u0065d\": 8,")
set(VSTUDY "\"base\": \"${ROOT}\", \"scenes\": [\"${SCENE}\"], \"size\": [16, 16], \"methods\": [{\"method\": \"direct\"}]")
file(WRITE ${D}/view_ok_study.json "{${VSTUDY}, \"camera\": \"view:${D}/view_ok.json\"}")
execute_process(COMMAND ${GIB} study ${D}/view_ok_study.json --dry-run WORKING_DIRECTORY ${ROOT} TIMEOUT 60
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
    fail("a study with a valid saved view: exit ${rc} (a failed set-up)\n${out}${err}")
endif()
study(view_size_study "{${VSTUDY}, \"camera\": \"view:${D}/view_big.json\"}"
      "view_big\\.json: missing or bad width \\(1\\.\\.8192 each and at most 16777216 pixels")

# ---- item 11: duplicate keys, compared unescaped ----
study(dup_escaped "{\"scenes\": [\"${SCENE}\"], \"frames\": 2,\n\"fr\\u0061mes\": 100000, \"methods\": \"all\"}"
      "/frames: key given twice \\(line 2\\)")
study(dup_surrogate "{\"scenes\": [\"${SCENE}\"], \"methods\": [{\"method\": \"direct\", \"label\": \"\\ud83d\\ude00\",
\"l\\u0061bel\": \"b\"}]}" "/methods/0/label: key given twice \\(line 2\\)")
study(view_dup_study "{${VSTUDY}, \"camera\": \"view:${D}/view_dup.json\"}" "view_dup\\.json: /seed: key given twice")

# ---- item 12: a scene listed twice (one run id for both) ----
study(scene_twice "{\"scenes\": [\"${SCENE}\", \"${SCENE}\"], \"methods\": \"all\"}"
      "/scenes/1: scene listed twice")
study(scene_twice_named "{\"scenes\": [\"${ROOT}/${SCENE}\", \"${ROOT}/./${SCENE}\"], \"methods\": \"all\"}"
      "/scenes/1: ${ROOT}/\\./${SCENE} has the same content as ${ROOT}/${SCENE}")

# ---- item 12: plugin folders ----
# a FIFO named like a plugin: skipped without being opened (was 30 s)
set(P ${D}/plugins_fifo)
file(MAKE_DIRECTORY ${P})
execute_process(COMMAND mkfifo ${P}/gimethod_fifo.so RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
    fail("mkfifo failed (a failed set-up)")
endif()
set(ENV{GIBENCH_PLUGIN_PATH} ${P})
string(TIMESTAMP t0 "%s")
execute_process(COMMAND ${GIB} methods TIMEOUT 60 RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
string(TIMESTAMP t1 "%s")
math(EXPR secs "${t1} - ${t0}")
if(NOT rc EQUAL 0 OR secs GREATER 10 OR NOT err MATCHES "gimethod_fifo\\.so: not a regular file \\(skipped unopened\\)"
   OR NOT out MATCHES "direct")
    fail("FIFO in the plugin folder: exit ${rc} after ${secs} s (want 0, < 10 s, one warning, direct listed)\n${out}${err}")
endif()
# a world-writable folder: refused whole, with one warning
set(P ${D}/plugins_open)
file(MAKE_DIRECTORY ${P})
file(COPY ${FAKE_PRINT}/gimethod_fake_ctor_print.so DESTINATION ${P})
execute_process(COMMAND chmod 0777 ${P})
set(ENV{GIBENCH_PLUGIN_PATH} ${P})
execute_process(COMMAND ${GIB} methods TIMEOUT 60 RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR out MATCHES "fake_ctor_print" OR NOT err MATCHES "plugins_open: folder is world-writable: its plugins are not loaded")
    fail("world-writable plugin folder: expected its plugin refused with a warning\n${out}${err}")
endif()
# a constructor that prints: methods --json stays JSON (and lists it)
set(ENV{GIBENCH_PLUGIN_PATH} ${FAKE_PRINT})
execute_process(COMMAND ${GIB} methods --json TIMEOUT 60 RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
string(JSON n ERROR_VARIABLE jerr LENGTH "${out}")
if(NOT rc EQUAL 0 OR jerr OR NOT out MATCHES "\"fake_ctor_print\"")
    fail("a printing constructor: methods --json is not clean JSON listing it (${jerr})\n${out}")
endif()
unset(ENV{GIBENCH_PLUGIN_PATH})
# GIBENCH_PLUGIN_DIR replaces the compiled-in folder; empty: none
execute_process(COMMAND env GIBENCH_PLUGIN_DIR= ${GIB} methods TIMEOUT 60 RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
match("${rc}|${out}" "^0\\|no method plugins found \\(build directory none"
      "GIBENCH_PLUGIN_DIR='': the compiled-in folder was still scanned\n${out}${err}")
set(ENV{GIBENCH_PLUGIN_DIR} ${FAKE_PRINT})
execute_process(COMMAND ${GIB} methods TIMEOUT 60 RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT out MATCHES "fake_ctor_print" OR out MATCHES "\ndirect ")
    fail("GIBENCH_PLUGIN_DIR=${FAKE_PRINT}: expected only its plugin\n${out}${err}")
endif()
unset(ENV{GIBENCH_PLUGIN_DIR})

# ---- item 12: GIBENCH_TIMER=bogus ----
set(ENV{GIBENCH_TIMER} bogus)
refused(timer_bogus "GIBENCH_TIMER='bogus' is not a timer mode: query, finish or cputime" methods)
unset(ENV{GIBENCH_TIMER})

# ---- item 12: report.md shows HTML in names as text ----
file(WRITE ${D}/esc.json "{\"name\": \"<img src=x onerror=alert(1)>\", \"base\": \"${ROOT}\", \"scenes\": [\"${SCENE}\"], \"size\": [8, 8],
 \"frames\": 1, \"warmup\": 0, \"compare\": false, \"methods\": [{\"method\": \"direct\"}]}")
execute_process(COMMAND ${GIB} -q study ${D}/esc.json --out ${D}/esc WORKING_DIRECTORY ${ROOT} TIMEOUT 120
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT EXISTS ${D}/esc/report.md)
    fail("the escaping study did not run (a failed set-up): exit ${rc}\n${out}${err}")
else()
    file(READ ${D}/esc/report.md md)
    if(md MATCHES "<img" OR NOT md MATCHES "&lt;img src=x onerror=alert\\(1\\)&gt;")
        fail("report.md embeds the study name's HTML raw")
    endif()
endif()

if(failures GREATER 0)
    message(FATAL_ERROR "${failures} input limit expectation(s) failed")
endif()
message(STATUS "hostile sizes, duplicate keys and scenes, plugin folders, report names and timer modes handled")
