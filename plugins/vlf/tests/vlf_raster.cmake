# Propagation by the rasteriser (propagate = raster, vlf_raster.c) against
# the C sweeps (propagate = cpu, the oracle), 32x32, l = 128, N = 32, on
# the Cornell box (scenes/cornell_box_coarse.gltf) and the hand-made
# tests/data/truth/box_light.gltf (issue 28: no method was tuned on it),
# both against the 8-bounce Embree reference (256 spp) beside the trivial
# answers scored on the same reference (the black image and the
# unshadowed `direct` plugin):
#   - the raster run really rasterised (stat propagate_path = 2) and the C
#     run did not (0);
#   - the two images agree: their relMSE < 1e-3, far below each one's
#     relMSE to the reference (measured: 3e-7 and 1.5e-7 between the
#     paths, 0.085 and 0.078 to the reference, over 100x the limit);
#   - each path's relMSE to the reference < 0.15 while the black image and
#     `direct` score > 0.3 (2x the limit; measured 0.38-0.87).
# Measured numbers: plugins/vlf/README.md "Tests".
# Run by ctest as: cmake -DGIB=... -DSCENES=... -DTRUTH=... -DOUT=... -DEXPECT=... -P vlf_raster.cmake

set(failures 0)
include(${EXPECT})

foreach(scene ${SCENES}/cornell_box_coarse.gltf ${TRUTH}/box_light.gltf)
    get_filename_component(name ${scene} NAME_WE)
    set(ref ${OUT}/vlf_raster_ref_${name}.exr)
    set(direct ${OUT}/vlf_raster_direct_${name}.exr)
    expect(0 "" reference --scene ${scene} --size 32x32 --spp 256 --max-bounces 8 --threads 1 --out ${ref})
    expect(0 "" render --scene ${scene} --method direct --size 32x32 --out ${direct})
    foreach(path cpu raster)
        expect(0 "" render --scene ${scene} --method vlf --size 32x32 --no-cache --param l=128 --param N=32
               --param propagate=${path} --out ${OUT}/vlf_raster_${path}_${name}.exr
               --timings ${OUT}/vlf_raster_${path}_${name}.json)
    endforeach()
    if(failures GREATER 0)
        message(FATAL_ERROR "set-up failed on ${name}")
    endif()
    foreach(path cpu raster)
        file(READ ${OUT}/vlf_raster_${path}_${name}.json j)
        string(JSON ran_${path} GET "${j}" stats propagate_path)
        diff_metric(${OUT}/vlf_raster_${path}_${name}.exr ${ref} relmse e_${path})
    endforeach()
    diff_metric(${OUT}/vlf_raster_raster_${name}.exr ${OUT}/vlf_raster_cpu_${name}.exr relmse between)
    diff_metric(${direct} ${ref} relmse e_direct)
    execute_process(COMMAND ${GIB} diff --black ${ref} --json RESULT_VARIABLE rc OUTPUT_VARIABLE j)
    if(NOT rc EQUAL 0)
        message(FATAL_ERROR "gibench diff --black ${ref} failed (${rc})")
    endif()
    string(JSON e_black GET "${j}" relmse)
    message(STATUS "${name}: raster against cpu relMSE ${between}; against the reference: raster ${e_raster}, "
                   "cpu ${e_cpu}, direct ${e_direct}, black ${e_black}; propagate_path ${ran_raster} / ${ran_cpu}")
    if(NOT ran_raster EQUAL 2 OR NOT ran_cpu EQUAL 0)
        fail("${name}: propagate_path ${ran_raster} (raster) and ${ran_cpu} (cpu), expected 2 and 0")
    endif()
    if(NOT between LESS 1e-3)
        fail("${name}: the raster and C paths' images differ by relMSE ${between} (limit 1e-3)")
    endif()
    foreach(path cpu raster)
        if(NOT e_${path} LESS 0.15)
            fail("${name}: ${path} path relMSE ${e_${path}} not below 0.15")
        endif()
    endforeach()
    if(NOT e_direct GREATER 0.3 OR NOT e_black GREATER 0.3)
        fail("${name}: a trivial answer scores under 0.3 (2x the limit): direct ${e_direct}, black ${e_black}")
    endif()
endforeach()
end_checks()
