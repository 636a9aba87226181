# The vlf plugin's rendered images against the Embree reference with its
# bounce count (B = max_bounces + 1 = 8), 32x32, on the scenes of
# plugins/vlf/data/gen_scenes.py, each beside trivial answers scored on the
# same reference (measured numbers: plugins/vlf/README.md "Tests").
#   PART=double_sided: a thin double-sided panel lit from its back side
#     (the side the camera sees; the panel fills the view). vlf must store
#     and render light for that side: relMSE < 0.1 and mean within 10 %,
#     while the black image and vlf's image of the same panel made
#     single-sided (no light kept for its back) score > 0.5 (5x the limit).
#   PART=mirror: an ideal mirror filling the view, reflecting a lit red and
#     white wall: relMSE < 0.15 and mean within 15 %, while the black image
#     and the `direct` plugin (direct light only: a black mirror) score
#     > 0.45 (3x the limit); the same with the mirror turned over and
#     double-sided (mirror_back.gltf: the camera sees its back), whose
#     image must equal the front's (relMSE < 1e-6).
# Run by ctest as: cmake -DGIB=... -DDATA=.../plugins/vlf/data -DOUT=... -DEXPECT=.../expect.cmake -DPART=... -P vlf_images.cmake

set(failures 0)
include(${EXPECT})

if(PART STREQUAL "double_sided")
    set(ref ${OUT}/vlf_ds_ref.exr)
    set(img ${OUT}/vlf_ds_double.exr)
    set(single ${OUT}/vlf_ds_single.exr)
    expect(0 "" reference --scene ${DATA}/panel_double.gltf --size 32x32 --spp 256 --max-bounces 8 --threads 1
           --out ${ref})
    expect(0 "" render --scene ${DATA}/panel_double.gltf --method vlf --size 32x32 --out ${img})
    expect(0 "" render --scene ${DATA}/panel_single.gltf --method vlf --size 32x32 --out ${single})
    if(failures GREATER 0)
        message(FATAL_ERROR "set-up failed")
    endif()
    diff_metric(${img} ${ref} relmse m_relmse)
    diff_metric(${img} ${ref} mean_lum_diff_pct m_mean)
    diff_metric(${single} ${ref} relmse single_relmse)
    execute_process(COMMAND ${GIB} diff --black ${ref} --json RESULT_VARIABLE rc OUTPUT_VARIABLE j)
    if(NOT rc EQUAL 0)
        message(FATAL_ERROR "gibench diff --black ${ref} failed (${rc})")
    endif()
    string(JSON black_relmse GET "${j}" relmse)
    message(STATUS "panel lit from its back: vlf double-sided relMSE ${m_relmse}, mean ${m_mean} %; "
                   "single-sided ${single_relmse}; black ${black_relmse}")
    if(NOT m_relmse LESS 0.1)
        fail("double-sided panel: vlf relMSE ${m_relmse} not below 0.1")
    endif()
    if(m_mean LESS -10 OR m_mean GREATER 10)
        fail("double-sided panel: vlf image mean ${m_mean} % off the reference's by more than 10 %")
    endif()
    if(NOT single_relmse GREATER 0.5 OR NOT black_relmse GREATER 0.5)
        fail("double-sided panel: a trivial answer scores under 0.5: single-sided ${single_relmse}, black ${black_relmse}")
    endif()
elseif(PART STREQUAL "mirror")
    foreach(name mirror_wall mirror_back)
        expect_beats_reference(vlf ${DATA}/${name}.gltf LIMIT 0.15 TRIVIAL 0.45 BLACK MEAN 15 SPP 256 BOUNCES 8
                               DIRECT_ARGS --frames 4)
    endforeach()
    # the double-sided mirror seen from its back reflects as the front does
    diff_metric(${OUT}/vlf_vs_ref_mirror_back.exr ${OUT}/vlf_vs_ref_mirror_wall.exr relmse back_front)
    message(STATUS "mirror seen from its double-sided back against the same mirror's front: relMSE ${back_front}")
    if(NOT back_front LESS 1e-6)
        fail("the double-sided mirror's back reflects differently from its front: relMSE ${back_front}")
    endif()
else()
    message(FATAL_ERROR "vlf_images.cmake: PART must be double_sided or mirror, not '${PART}'")
endif()

if(failures GREATER 0)
    message(FATAL_ERROR "${failures} vlf image expectation(s) failed")
endif()
message(STATUS "vlf images (${PART}): all expectations met")
