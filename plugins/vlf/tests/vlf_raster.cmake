# Propagation by the rasteriser (propagate = raster, vlf_raster.c) against
# the C sweeps (propagate = cpu, the oracle), 32x32, l = 128, N = 32, on
# the Cornell box (scenes/cornell_box_coarse.gltf) and the hand-made
# tests/data/truth/box_light.gltf (issue 28: no method was tuned on it),
# both against the 8-bounce Embree reference (256 spp) beside the trivial
# answers scored on the same reference (the black image and the
# unshadowed `direct` plugin). Both ways of ordering each ray's faces:
# GL_EXT_shader_framebuffer_fetch (raster_sync = auto on llvmpipe) on the Cornell box,
# the portable GL 4.5 core variant (raster_sync = barrier: the order in
# layers, texture barriers between; vlf_layers.c) on both scenes:
#   - the raster runs really rasterised (stat propagate_path = 2) the way
#     asked (stat raster_sync 1 fetch, 2 barrier) and the C run did not (0);
#   - the barrier variant's image equals the fetch variant's (relMSE
#     < 1e-6; measured 0: the same sums in the same order per pixel);
#     broken layering (every entry in layer 0) gives 0.27 (checked by hand);
#   - each raster image agrees with the C path's: relMSE < 1e-3, far below
#     each one's relMSE to the reference (measured: 3e-7 and 4.5e-7 between
#     the paths, 0.085 and 0.078 to the reference, over 100x the limit);
#   - each path's relMSE to the reference < 0.15 while the black image and
#     `direct` score > 0.3 (2x the limit; measured 0.38-0.87).
# Measured numbers: plugins/vlf/README.md "Tests".
# Run by ctest as: cmake -DGIB=... -DSCENES=... -DTRUTH=... -DOUT=... -DEXPECT=... -P vlf_raster.cmake

set(failures 0)
include(${EXPECT})

set(paths_cornell_box_coarse cpu fetch barrier)
set(paths_box_light cpu barrier)
foreach(scene ${SCENES}/cornell_box_coarse.gltf ${TRUTH}/box_light.gltf)
    get_filename_component(name ${scene} NAME_WE)
    set(paths ${paths_${name}})
    set(ref ${OUT}/vlf_raster_ref_${name}.exr)
    set(direct ${OUT}/vlf_raster_direct_${name}.exr)
    expect(0 "" reference --scene ${scene} --size 32x32 --spp 256 --max-bounces 8 --threads 1 --out ${ref})
    expect(0 "" render --scene ${scene} --method direct --size 32x32 --out ${direct})
    foreach(path ${paths})
        if(path STREQUAL "cpu")
            set(how propagate=cpu)
        else()
            # auto takes the fetch extension where the GL has it (llvmpipe)
            string(REPLACE fetch auto sync ${path})
            set(how propagate=raster --param raster_sync=${sync})
        endif()
        expect(0 "" render --scene ${scene} --method vlf --size 32x32 --no-cache --param l=128 --param N=32
               --param ${how} --out ${OUT}/vlf_raster_${path}_${name}.exr
               --timings ${OUT}/vlf_raster_${path}_${name}.json)
    endforeach()
    if(failures GREATER 0)
        message(FATAL_ERROR "set-up failed on ${name}")
    endif()
    foreach(path ${paths})
        file(READ ${OUT}/vlf_raster_${path}_${name}.json j)
        string(JSON ran_${path} GET "${j}" stats propagate_path)
        string(JSON sync_${path} GET "${j}" stats raster_sync)
        diff_metric(${OUT}/vlf_raster_${path}_${name}.exr ${ref} relmse e_${path})
    endforeach()
    diff_metric(${direct} ${ref} relmse e_direct)
    execute_process(COMMAND ${GIB} diff --black ${ref} --json RESULT_VARIABLE rc OUTPUT_VARIABLE j)
    if(NOT rc EQUAL 0)
        message(FATAL_ERROR "gibench diff --black ${ref} failed (${rc})")
    endif()
    string(JSON e_black GET "${j}" relmse)
    if(NOT ran_cpu EQUAL 0)
        fail("${name}: the C run's propagate_path is ${ran_cpu}, expected 0")
    endif()
    set(want_fetch 1)
    set(want_barrier 2)
    foreach(path ${paths})
        if(path STREQUAL "cpu")
            continue()
        endif()
        diff_metric(${OUT}/vlf_raster_${path}_${name}.exr ${OUT}/vlf_raster_cpu_${name}.exr relmse between)
        message(STATUS "${name}: raster (${path}) against cpu relMSE ${between}; against the reference: "
                       "${path} ${e_${path}}, cpu ${e_cpu}, direct ${e_direct}, black ${e_black}")
        if(NOT ran_${path} EQUAL 2 OR NOT sync_${path} EQUAL ${want_${path}})
            fail("${name}: ${path}: propagate_path ${ran_${path}}, raster_sync ${sync_${path}}, "
                 "expected 2 and ${want_${path}}")
        endif()
        if(NOT between LESS 1e-3)
            fail("${name}: the raster (${path}) and C paths' images differ by relMSE ${between} (limit 1e-3)")
        endif()
    endforeach()
    if(paths MATCHES "fetch")
        diff_metric(${OUT}/vlf_raster_barrier_${name}.exr ${OUT}/vlf_raster_fetch_${name}.exr relmse same)
        message(STATUS "${name}: barrier against fetch relMSE ${same}")
        if(NOT same LESS 1e-6)
            fail("${name}: the barrier and fetch variants' images differ by relMSE ${same} (limit 1e-6)")
        endif()
    endif()
    foreach(path ${paths})
        if(NOT e_${path} LESS 0.15)
            fail("${name}: ${path} path relMSE ${e_${path}} not below 0.15")
        endif()
    endforeach()
    if(NOT e_direct GREATER 0.3 OR NOT e_black GREATER 0.3)
        fail("${name}: a trivial answer scores under 0.3 (2x the limit): direct ${e_direct}, black ${e_black}")
    endif()
endforeach()
end_checks()
