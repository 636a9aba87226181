# implicit_vis's relink=moved (issue 29): the links (Algorithm 1, lines 3-6)
# are kept from the last frame when nothing moved, and the image is the same
# to the bit as when they are made every frame (relink=always, Algorithm 1 as
# printed). On the still Cornell box the last of 3 frames reuses them (stat
# links_reused 1); on the moving Cornell box (--animate) every frame makes
# them anew (links_reused 0) and the images again match to the bit.
# Run by ctest as: cmake -DGIB=... -DSCENES=... -DOUT=... -DEXPECT=... -P iv_relink.cmake
set(failures 0)
include(${EXPECT})
set(dir ${OUT}/iv_relink)
file(REMOVE_RECURSE ${dir})
file(MAKE_DIRECTORY ${dir})
set(ENV{GIBENCH_CACHE} ${dir}/cache)

# render(<scene> <relink> <tag> <args...>): the image and the timings record
function(render scene relink tag)
    expect(0 "" -q render --scene ${SCENES}/${scene}.gltf --method implicit_vis --size 32x32 --frames 3
           --param relink=${relink} --param N=6 --out ${dir}/${tag}.exr --timings ${dir}/${tag}.json ${ARGN})
    set(failures ${failures} PARENT_SCOPE)
endfunction()

# same_image(<a> <b> <what>): the two EXR files are equal byte for byte
function(same_image a b what)
    file(SHA256 ${dir}/${a}.exr ha)
    file(SHA256 ${dir}/${b}.exr hb)
    if(NOT ha STREQUAL hb)
        fail("${what}: relink=moved and relink=always give different images")
    endif()
    set(failures ${failures} PARENT_SCOPE)
endfunction()

render(cornell_box always still_always)
render(cornell_box moved still_moved)
same_image(still_always still_moved "the still Cornell box")
expect_json(${dir}/still_moved.json "\"links_reused\": 1\\.0")
expect_json(${dir}/still_always.json "\"links_reused\": 0\\.0")

render(cornell_moving always moving_always --animate 10)
render(cornell_moving moved moving_moved --animate 10)
same_image(moving_always moving_moved "the moving Cornell box")
expect_json(${dir}/moving_moved.json "\"links_reused\": 0\\.0")
end_checks()
