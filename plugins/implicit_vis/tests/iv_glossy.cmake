# implicit_vis's glossy direct light (Sec. 4.3, Fig. 11) against the Embree
# path-traced reference, bounce-matched: the scenes of plugins/implicit_vis/data/
# (gen_glossy.py: a glossy Phong floor, albedo 0.25, ks 0.6, exponent 30,
# tessellated 32 x 32, a diffuse box casting a shadow; no mirror), lit by an
# area light (glossy_floor), a point and a spot light (glossy_punctual),
# an environment (glossy_env), at 64x64, direct light only (bounces=0)
# against the 1-bounce reference (256 spp); the area light with the remedy
# for small emitters the README describes (bilinear + coverage 1), all
# with splatting (README "Deviations"; off by default since issue 28).
# Beside it, on the same reference, the trivial answers: black, the
# unshadowed `direct` plugin, and the plugin's own diffuse-only image
# (glossy=false). The method must stay under LIMIT while every trivial
# answer exceeds TRIVIAL (the stated margin), and its image mean within
# MEAN %. The paper's own Eq. 5 as printed (the default) is scored and
# printed, not asserted (README "Weights"). Then: with no glossy material (the Cornell box)
# glossy=true and glossy=false give the same image to the bit, and
# illum=cpu refuses a glossy scene with one line.
# Run by ctest as: cmake -DGIB=... -DSCENES=... -DDATA=... -DOUT=... -DEXPECT=... -P iv_glossy.cmake
set(failures 0)
include(${EXPECT})
set(ENV{GIBENCH_CACHE} ${OUT}/iv_cache_glossy)
file(MAKE_DIRECTORY ${OUT}/iv_cache_glossy)
# The plugin's diffuse-only image (glossy=false, same settings) of a scene
# scored by expect_beats_reference: a trivial answer that must exceed
# `trivial` and score worse than the glossy image.
function(expect_beats_diffuse name trivial)
    set(ref ${OUT}/implicit_vis_ref_${name}.exr)
    set(img ${OUT}/implicit_vis_vs_ref_${name}.exr)
    set(diffuse ${OUT}/implicit_vis_diffuse_${name}.exr)
    expect(0 "" render --scene ${DATA}/${name}.gltf --method implicit_vis --size 64x64 ${ARGN}
           --param glossy=false --out ${diffuse})
    diff_metric(${diffuse} ${ref} relmse d_relmse)
    diff_metric(${diffuse} ${ref} mean_lum_diff_pct d_mean)
    diff_metric(${img} ${ref} relmse m_relmse)
    message(STATUS "${name}: the plugin's diffuse-only image (glossy=false) relMSE ${d_relmse}, mean ${d_mean} %")
    if(NOT d_relmse GREATER ${trivial})
        fail("${name}: the diffuse-only image scores ${d_relmse}, not above ${trivial}")
    endif()
    if(NOT m_relmse LESS d_relmse)
        fail("${name}: the glossy image (${m_relmse}) is no better than the diffuse-only one (${d_relmse})")
    endif()
    set(failures ${failures} PARENT_SCOPE)
endfunction()

# the area light (the light links); measured: method 0.033 (mean +4.4 %);
# diffuse-only 0.16, direct 0.22, black 0.39
set(scene ${DATA}/glossy_floor.gltf)
set(args --param bounces=0 --param bilinear=true --param coverage=1 --param splat=true)
expect_beats_reference(implicit_vis ${scene} LIMIT 0.08 TRIVIAL 0.12 MEAN 10 SPP 256 BOUNCES 1 SIZE 64x64 BLACK
                       METHOD_ARGS ${args} DIRECT_ARGS --frames 4)
expect_beats_diffuse(glossy_floor 0.12 ${args})
# the point and spot light (through their bins); splatting on (without it
# the floor's near discs leave bins open and the shadow leaks: 0.33);
# measured: method 0.016 (mean -1.4 %); diffuse-only 0.16, direct 0.58, black 0.44
expect_beats_reference(implicit_vis ${DATA}/glossy_punctual.gltf LIMIT 0.06 TRIVIAL 0.12 MEAN 10 SPP 256
                       BOUNCES 1 SIZE 64x64 BLACK METHOD_ARGS --param bounces=0 --param splat=true DIRECT_ARGS --frames 4)
expect_beats_diffuse(glossy_punctual 0.12 --param bounces=0 --param splat=true)
# the environment (through the open bins); splatting on (without it 0.18); measured:
# method 0.035 (mean -14 %); diffuse-only 0.44, direct 0.33, black 0.96
expect_beats_reference(implicit_vis ${DATA}/glossy_env.gltf LIMIT 0.1 TRIVIAL 0.2 MEAN 20 SPP 256
                       BOUNCES 1 SIZE 64x64 BLACK METHOD_ARGS --param bounces=0 --param splat=true DIRECT_ARGS --frames 4)
expect_beats_diffuse(glossy_env 0.2 --param bounces=0 --param splat=true)

# the paper's Eq. 5 as written (the default settings): printed only
set(ref ${OUT}/implicit_vis_ref_glossy_floor.exr)
set(eq5 ${OUT}/implicit_vis_eq5_glossy_floor.exr)
expect(0 "" render --scene ${scene} --method implicit_vis --size 64x64 --param bounces=0 --out ${eq5})
diff_metric(${eq5} ${ref} relmse e_relmse)
diff_metric(${eq5} ${ref} mean_lum_diff_pct e_mean)
message(STATUS "glossy_floor: default settings (Eq. 5 as printed, no splatting) relMSE ${e_relmse}, mean ${e_mean} % (not asserted)")

# no glossy material: the glossy code must not change a pixel
foreach(g true false)
    expect(0 "" render --scene ${SCENES}/cornell_box.gltf --method implicit_vis --size 32x32 --param N=8
           --param glossy=${g} --out ${OUT}/implicit_vis_cornell_glossy_${g}.exr)
endforeach()
execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files ${OUT}/implicit_vis_cornell_glossy_true.exr
                        ${OUT}/implicit_vis_cornell_glossy_false.exr RESULT_VARIABLE same)
if(NOT same EQUAL 0)
    fail("cornell_box (no glossy material): glossy=true and glossy=false images differ")
endif()

expect(2 "glossy materials need illum=gpu" render --scene ${scene} --method implicit_vis --size 16x16
       --param illum=cpu --out ${OUT}/implicit_vis_glossy_cpu.exr)

if(failures GREATER 0)
    message(FATAL_ERROR "${failures} implicit_vis glossy expectation(s) failed")
endif()
message(STATUS "implicit_vis glossy direct light: all expectations met")
