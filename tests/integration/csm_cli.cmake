# The csm plugin through the gibench command: a finite render of the bunny,
# the on-disk cache (a second run hits it; a damaged file is recomputed with
# a warning), and bad parameters exit 2.
# Run by ctest as: cmake -DGIB=... -DSCENES=... -DOUT=... -P csm_cli.cmake

set(failures 0)
include(${CMAKE_CURRENT_LIST_DIR}/expect.cmake)

set(cache ${OUT}/csm_cache)
file(REMOVE_RECURSE ${cache})
file(MAKE_DIRECTORY ${cache})
set(ENV{GIBENCH_CACHE} ${cache})
set(args render --scene ${SCENES}/bunny_env.glb --method csm --size 48x48 --frames 2 --param N=8 --param M=64)

expect(0 "" ${args} --out ${OUT}/csm_bunny_1.exr --timings ${OUT}/csm_bunny_1.json)
expect_json(${OUT}/csm_bunny_1.json "\"nonfinite_pixels\": 0" "\"cache_hit\": 0" "\"segments_per_texel\""
           "\"maps\": 128" "\"depth_render\"" "\"compress\"" "\"upload\"")
file(GLOB cached ${cache}/csm-*.bin)
list(LENGTH cached n_cached)
if(NOT n_cached EQUAL 2)
    message(SEND_ERROR "expected 2 cache files (bunny, ground), found ${n_cached}")
    math(EXPR failures "${failures} + 1")
endif()
expect(0 "" ${args} --out ${OUT}/csm_bunny_2.exr --timings ${OUT}/csm_bunny_2.json)
expect_json(${OUT}/csm_bunny_2.json "\"nonfinite_pixels\": 0" "\"cache_hit\": 1")

# A damaged cache file: a warning naming it, recomputed, and rewritten.
list(GET cached 0 victim)
file(WRITE ${victim} "GICSMZ this is not a CSM")
expect(0 "unusable cache file" ${args} --out ${OUT}/csm_bunny_3.exr --timings ${OUT}/csm_bunny_3.json)
expect_json(${OUT}/csm_bunny_3.json "\"nonfinite_pixels\": 0" "\"cache_hit\": 0")
expect(0 "" ${args} --out ${OUT}/csm_bunny_4.exr --timings ${OUT}/csm_bunny_4.json)
expect_json(${OUT}/csm_bunny_4.json "\"cache_hit\": 1")

# Other options run and stay finite.
expect(0 "" ${args} --param filter=pcf --param depth=z3 --param enumeration=zigzag --param S=5
       --out ${OUT}/csm_bunny_pcf.exr --timings ${OUT}/csm_bunny_pcf.json)
expect_json(${OUT}/csm_bunny_pcf.json "\"nonfinite_pixels\": 0")
expect(0 "" ${args} --param filter=rr --param enumeration=scanline --out ${OUT}/csm_bunny_rr.exr
       --timings ${OUT}/csm_bunny_rr.json)
expect_json(${OUT}/csm_bunny_rr.json "\"nonfinite_pixels\": 0")

# Bad parameters.
expect(2 "csm: N=1 is outside" ${args} --param N=1 --out ${OUT}/x.exr)
expect(2 "csm: M=2000 is outside" ${args} --param M=2000 --out ${OUT}/x.exr)
expect(2 "csm: " ${args} --param filter=box --out ${OUT}/x.exr)
expect(2 "csm: " ${args} --param enumeration=spiral --out ${OUT}/x.exr)
expect(2 "csm: S=0 is outside" ${args} --param S=0 --out ${OUT}/x.exr)
expect(2 "csm: unknown parameter 'K'" ${args} --param K=3 --out ${OUT}/x.exr)

if(failures GREATER 0)
    message(FATAL_ERROR "${failures} csm command-line expectation(s) failed")
endif()
message(STATUS "all csm command-line expectations met")
