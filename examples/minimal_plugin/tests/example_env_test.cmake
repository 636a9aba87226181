# The example plugin is found on GIBENCH_PLUGIN_PATH, not in the build's
# plugin directory, and its image is right: against `direct` (environment
# importance sampling with MIS, an independent estimator of the same
# unshadowed integral) on the diffuse bunny under the forest map it must
# come within a tenth of the error of the trivial answer (surfaces never
# lit, the background kept; the background pixels agree, so it scores
# about 0.18 here, not 1).
include(${EXPECT})
set(failures 0)
file(MAKE_DIRECTORY ${OUT})

# Not an installed method: absent without the path.
execute_process(COMMAND ${GIB} methods OUTPUT_VARIABLE out RESULT_VARIABLE rc)
if(out MATCHES "example_env")
    fail("example_env is listed without GIBENCH_PLUGIN_PATH:\n${out}")
endif()
set(ENV{GIBENCH_PLUGIN_PATH} ${PLUGINS})
expect(0 "example_env" methods)

set(scene ${SCENES}/bunny_alone_env.glb)
expect(0 "" render --scene ${scene} --method example_env --size 32x32 --frames 16 --param samples=64
       --out ${OUT}/example.exr)
expect(0 "" render --scene ${scene} --method direct --size 32x32 --frames 16 --param env_samples=64
       --out ${OUT}/direct.exr)
# The trivial answer on the same pixels: surfaces never lit, background
# kept (direct with no environment samples).
expect(0 "" render --scene ${scene} --method direct --size 32x32 --frames 1 --param env_samples=0 --param mis=0
       --out ${OUT}/unlit.exr)
function(score test out_relmse out_lum)
    execute_process(COMMAND ${GIB} diff ${test} ${OUT}/direct.exr --json OUTPUT_VARIABLE dj RESULT_VARIABLE rc)
    if(NOT rc EQUAL 0)
        message(FATAL_ERROR "diff ${test} failed: ${dj}")
    endif()
    string(JSON r GET "${dj}" relmse)
    string(JSON l GET "${dj}" mean_lum_diff_pct)
    set(${out_relmse} ${r} PARENT_SCOPE)
    set(${out_lum} ${l} PARENT_SCOPE)
endfunction()
score(${OUT}/example.exr relmse lum)
score(${OUT}/unlit.exr relmse_unlit lum_unlit)
message(STATUS "against direct: example_env relMSE ${relmse} (mean luminance ${lum} %), "
               "never lit relMSE ${relmse_unlit} (${lum_unlit} %)")
if(NOT relmse_unlit GREATER 0.1)
    fail("the trivial answer scores ${relmse_unlit}: the scene does not test anything")
endif()
# Below a tenth of the trivial answer's error (0.01 = 0.1 x 0.1, the least it
# may score above; measured 0.006 against 0.18), and the mean within 3 %.
if(relmse GREATER 0.01)
    fail("example_env relMSE ${relmse} is not below 0.01, a tenth of the never-lit answer's floor")
endif()
if(lum GREATER 3 OR lum LESS -3)
    fail("mean luminance differs by ${lum} % (limit 3 %)")
endif()
if(failures GREATER 0)
    message(FATAL_ERROR "${failures} failure(s)")
endif()
