# Malformed study files are refused before anything runs: exit 2, one line
# on stderr naming the JSON path, never a crash or a hang. Each case is
# written to ${OUT}/study_strict/ and loaded with --dry-run (the asan preset
# runs this script too, so an out-of-bounds write shows as a failure).
# cmake -DGIB=... -DROOT=... -DOUT=... -P study_strict.cmake
set(failures 0)
include(${CMAKE_CURRENT_LIST_DIR}/expect.cmake)
set(D ${OUT}/study_strict)
file(REMOVE_RECURSE ${D})
file(MAKE_DIRECTORY ${D})
set(SCENE "\"base\": \"${ROOT}\", \"scenes\": [\"scenes/cornell_box_coarse.gltf\"]")

# refuse(<name> <study text> <regex of the message>)
function(refuse name text regex)
    file(WRITE ${D}/${name}.json "${text}")
    execute_process(COMMAND ${GIB} study ${D}/${name}.json --dry-run WORKING_DIRECTORY ${ROOT} TIMEOUT 60
                    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
    expect_refusal(${name} "${regex}" "${rc}" "${err}")
    set(failures ${failures} PARENT_SCOPE)
endfunction()

# Memory safety: values of the wrong type where the reader used to assume one.
refuse(method_null "{${SCENE}, \"methods\": [{\"method\": null}]}" "/methods/0: \"method\" must be")
refuse(method_number "{${SCENE}, \"methods\": [{\"method\": 5}]}" "/methods/0: \"method\" must be")
refuse(reference_number "{${SCENE}, \"methods\": \"all\", \"reference\": 5}" "/reference: must be an object")
refuse(param_null "{${SCENE}, \"methods\": [{\"method\": \"direct\", \"params\": {\"mis\": null}}]}"
       "/methods/0/params/mis: a value is")
# A range whose step is lost to rounding (1e17 + 1 == 1e17 in double) used
# to loop for ever, writing past the table of values.
refuse(range_rounding_float
       "{${SCENE}, \"methods\": [{\"method\": \"direct\", \"params\": {\"light_samples\": {\"from\": 1e17, \"to\": 1.00000000000000016e17, \"step\": 1}}}]}"
       "/methods/0/params/light_samples: the range gives the same value twice")
refuse(range_rounding_int
       "{${SCENE}, \"methods\": [{\"method\": \"direct\", \"params\": {\"light_samples\": {\"from\": 100000000000000000, \"to\": 100000000000000016, \"step\": 1}}}]}"
       "light_samples=100000000000000000 is outside")
refuse(range_too_long
       "{${SCENE}, \"methods\": [{\"method\": \"direct\", \"params\": {\"light_samples\": {\"from\": 1, \"to\": 1000, \"step\": 1}}}]}"
       "the range gives more than 64 values")
refuse(range_huge_span
       "{${SCENE}, \"methods\": [{\"method\": \"direct\", \"params\": {\"light_samples\": {\"from\": -9000000000000000000, \"to\": 9000000000000000000, \"step\": 1}}}]}"
       "the range gives more than 64 values")
refuse(range_count_rounding
       "{${SCENE}, \"methods\": [{\"method\": \"direct\", \"params\": {\"light_samples\": {\"from\": 1, \"to\": 2, \"count\": 5}}}]}"
       "the range gives the same value twice")
# Too many runs is refused before the first is made.
refuse(too_many_runs
       "{${SCENE}, \"methods\": [{\"method\": \"direct\", \"params\": {\"light_samples\": {\"from\": 1, \"to\": 64, \"step\": 1}, \"env_samples\": {\"from\": 0, \"to\": 63, \"step\": 1}, \"mis\": [true, false]}}]}"
       "/methods/0: the study makes more than 4096 runs")

# Sloppy input that used to be taken: one strict reader, types, ranges and
# unknown keys checked before anything runs.
refuse(trailing_comma "{${SCENE}, \"methods\": \"all\",}" "line 1: not valid JSON")
refuse(trailing_text "{${SCENE}, \"methods\": \"all\"} x" "not valid JSON")
refuse(size_strings "{${SCENE}, \"size\": [\"32\", \"32\"], \"methods\": \"all\"}"
       "/size: width and height must be integers")
refuse(size_fraction "{${SCENE}, \"size\": [32.9, 32], \"methods\": \"all\"}" "/size: width and height must be integers")
refuse(exposure_text "{${SCENE}, \"exposure\": \"abc\", \"methods\": \"all\"}" "/exposure: must be a number in")
refuse(exposure_huge "{${SCENE}, \"exposure\": 1e39, \"methods\": \"all\"}" "/exposure: must be a number in")
refuse(timeout_text "{${SCENE}, \"timeout\": \"10\", \"methods\": \"all\"}" "/timeout: must be a number in")
refuse(time_text "{${SCENE}, \"time\": \"1\", \"methods\": \"all\"}" "/time: must be a number in")
refuse(animate_text "{${SCENE}, \"animate\": \"30\", \"methods\": \"all\"}" "/animate: must be a positive frame rate")
refuse(name_null "{${SCENE}, \"name\": null, \"methods\": \"all\"}" "/name: must be a string")
refuse(methods_empty "{${SCENE}, \"methods\": []}" "/methods: must be \"all\" or a non-empty list")
refuse(all_with_params "{${SCENE}, \"methods\": [{\"method\": \"all\", \"params\": {\"mis\": false}}]}"
       "/methods/0: \"all\" runs every method with its defaults: no \"params\"")
refuse(camera_unknown "{${SCENE}, \"camera\": \"nope\", \"methods\": \"all\"}" "/camera: [^ ]+ has no camera 'nope'")
refuse(camera_number "{${SCENE}, \"camera\": 3, \"methods\": \"all\"}" "/camera: must be a string or null")
refuse(convergence_fraction "{${SCENE}, \"methods\": \"all\", \"reference\": {\"spp\": 64, \"convergence_spp\": [4.5]}}"
       "/reference/convergence_spp: each count")
refuse(range_unknown_key
       "{${SCENE}, \"methods\": [{\"method\": \"direct\", \"params\": {\"light_samples\": {\"from\": 1, \"to\": 4, \"stepp\": 1}}}]}"
       "a range has only")
refuse(range_count_fraction
       "{${SCENE}, \"methods\": [{\"method\": \"direct\", \"params\": {\"light_samples\": {\"from\": 1, \"to\": 4, \"count\": 2.5}}}]}"
       "\"count\" must be an integer")
refuse(range_scale_unknown
       "{${SCENE}, \"methods\": [{\"method\": \"direct\", \"params\": {\"light_samples\": {\"from\": 1, \"to\": 4, \"count\": 2, \"scale\": \"lg\"}}}]}"
       "\"scale\" is \"lin\" or \"log\"")
refuse(chart_log_text
       "{${SCENE}, \"methods\": \"all\", \"charts\": [{\"file\": \"a.png\", \"x\": \"run\", \"y\": \"prepare_ms\", \"log_x\": \"yes\"}]}"
       "\"log_x\" and \"log_y\" must be true or false")
# Two equal keys in one object: json-c keeps the last silently; refused,
# with the key's JSON path and line, at any depth.
refuse(duplicate_top "{${SCENE}, \"size\": [8, 8],\n\"methods\": \"all\", \"size\": [16, 16]}"
       "/size: key given twice \\(line 2\\)")
refuse(duplicate_params
       "{${SCENE}, \"methods\": [{\"method\": \"direct\"}, {\"method\": \"direct\", \"params\": {\"light_samples\": 4, \"light_samples\": 8}}]}"
       "/methods/1/params/light_samples: key given twice \\(line 1\\)")
refuse(duplicate_reference
       "{${SCENE}, \"methods\": \"all\", \"reference\": {\"spp\": 4, \"pixel\": \"box\", \"spp\": 64}}"
       "/reference/spp: key given twice")

# A method may be given every parameter it declares (csm declares 18; the
# reader used to stop at 16).
set(ALL "\"N\": 4, \"M\": 16, \"enumeration\": \"hilbert\", \"depth\": \"z2\", \"open_surfaces\": \"shell\",
\"shell_thickness\": 0.001, \"filter\": \"nearest\", \"bias\": 0.01, \"normal_offset\": 1,
\"normal_offset_local\": 0.25, \"lights\": \"local\", \"N_local\": 2, \"M_local\": 16,
\"light_enumeration\": \"diagonal\", \"linear_aspect\": 4, \"receivers\": \"none\", \"mode\": \"shade\"")
file(WRITE ${D}/csm_all_params.json
     "{${SCENE}, \"methods\": [{\"method\": \"csm\", \"params\": {${ALL}, \"S\": [4, 8]}}]}")
execute_process(COMMAND ${GIB} study ${D}/csm_all_params.json --dry-run WORKING_DIRECTORY ${ROOT} TIMEOUT 60
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
string(REGEX MATCHALL "\nrun [^\n]*" runs "\n${out}")
list(LENGTH runs nruns)
set(first "")
if(nruns GREATER 0)
    list(GET runs 0 first)
endif()
string(REGEX MATCHALL " [A-Za-z_]+=" given "${first}")
list(LENGTH given ngiven)
if(NOT rc EQUAL 0 OR NOT nruns EQUAL 2 OR NOT ngiven EQUAL 18)
    fail("csm with all its parameters: expected exit 0, 2 runs of 18 parameters; got exit ${rc}, ${nruns} runs, ${ngiven} parameters\n${out}${err}")
endif()

# --slurm's options: refused with exit 2 and one line before anything is
# planned or submitted (no Slurm needed).
set(TINY tests/data/studies/slurm_tiny.json)
# refuse_opts(<name> <regex> <args...>)
function(refuse_opts name regex)
    execute_process(COMMAND ${ARGN} WORKING_DIRECTORY ${ROOT} TIMEOUT 60
                    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
    expect_refusal(${name} "${regex}" "${rc}" "${err}")
    set(failures ${failures} PARENT_SCOPE)
endfunction()
refuse_opts(slurm_partition "--partition 'a b' is not a partition name"
            ${GIB} study ${TINY} --out ${D}/s --slurm --dry-run --partition "a b")
refuse_opts(slurm_time "--time '1:2:3:4' is not a Slurm time"
            ${GIB} study ${TINY} --out ${D}/s --slurm --dry-run --time 1:2:3:4)
refuse_opts(slurm_gres "--gres 'gpu[*]1' is not a generic resource"
            ${GIB} study ${TINY} --out ${D}/s --slurm --dry-run --gres "gpu*1")
refuse_opts(slurm_array_limit "--array-limit '0' is not an integer"
            ${GIB} study ${TINY} --out ${D}/s --slurm --dry-run --array-limit 0)
refuse_opts(slurm_missing_value "--time needs a value" ${GIB} study ${TINY} --out ${D}/s --slurm --time)
refuse_opts(slurm_without "go with --slurm" ${GIB} study ${TINY} --out ${D}/s --partition p)
refuse_opts(slurm_fresh "--fresh does not go with --slurm" ${GIB} study ${TINY} --out ${D}/s --slurm --fresh)
refuse_opts(slurm_blank_out "without blanks" ${GIB} study ${TINY} --out "${D}/a b" --slurm --dry-run)
refuse_opts(slurm_no_sbatch "sbatch is not on PATH"
            ${CMAKE_COMMAND} -E env PATH=${D} ${GIB} study ${TINY} --out ${D}/s --slurm)
refuse_opts(slurm_bad_cell "--cell 'run:x' is not" ${GIB} study ${TINY} --out ${D}/s --cell run:x)
refuse_opts(slurm_stale_cell "the study's plan changed" ${GIB} study ${TINY} --out ${D}/s --cell run:0:1234)
# a dry run prints the three scripts, the run array with its limit
execute_process(COMMAND ${GIB} study ${TINY} --out ${D}/s --slurm --dry-run --array-limit 2 --partition gpu
                        --gres gpu:1 --time 10:00 WORKING_DIRECTORY ${ROOT} TIMEOUT 60
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
    fail("--slurm --dry-run: exit ${rc}: ${err}")
endif()
foreach(want "#SBATCH --array=0%2" "#SBATCH --array=0-2%2" "#SBATCH --partition=gpu" "#SBATCH --gres=gpu:1"
        "#SBATCH --time=10:00" "--cell run:\"[$]SLURM_ARRAY_TASK_ID\":" "--slurm-collect \"[$]1,[$]2\"")
    match("${out}" "${want}" "--slurm --dry-run lacks ${want}:\n${out}")
endforeach()
if(EXISTS ${D}/s/slurm/runs.sh)
    fail("--slurm --dry-run wrote a script")
endif()

if(failures GREATER 0)
    message(FATAL_ERROR "${failures} malformed study file(s) not refused properly")
endif()
message(STATUS "malformed study files are refused")
