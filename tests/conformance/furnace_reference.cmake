# The furnace scenes are right: the reference path tracer, limited to B
# bounces, gives Le * sum_{k=0..B} rho^k (Le = 1) on both spheres, for the
# bounce limits the conformance suite uses (B = max_bounces + 1: 1 for
# direct and csm, 4 for avg) and for the unlimited sum Le / (1 - rho).
# Each pixel's paths all see the same radiance, so 16 x 16 pixels at 64 spp
# hold the mean to well under 1 % (limit 1 %).
file(MAKE_DIRECTORY ${OUT})
set(failures 0)
foreach(case "050;0.5" "080;0.8")
    list(GET case 0 name)
    list(GET case 1 rho)
    foreach(B 1 2 4 inf)
        execute_process(COMMAND ${GIB} reference --scene ${DATA}/furnace_${name}.gltf --size 16x16 --spp 64
                                --max-bounces ${B} --out ${OUT}/furnace_${name}_b${B}.exr
                                --stats ${OUT}/furnace_${name}_b${B}.json
                        RESULT_VARIABLE rc ERROR_VARIABLE err OUTPUT_QUIET)
        if(NOT rc EQUAL 0)
            message(SEND_ERROR "reference furnace_${name} B=${B}: exit ${rc}: ${err}")
            math(EXPR failures "${failures} + 1")
            continue()
        endif()
        file(READ ${OUT}/furnace_${name}_b${B}.json j)
        string(JSON mean GET "${j}" mean_rgb 0)
        # the closed form, computed here in fixed point (CMake has integers only)
        if(B STREQUAL "inf")
            if(rho STREQUAL "0.5")
                set(expect 2000000)
            else()
                set(expect 5000000)
            endif()
        else()
            string(REPLACE "0." "" r "${rho}") # 5 or 8: rho = r / 10
            set(term 1000000)
            set(expect 0)
            foreach(k RANGE 0 ${B})
                math(EXPR expect "${expect} + ${term}")
                math(EXPR term "${term} * ${r} / 10")
            endforeach()
        endif()
        # mean as micro-units
        string(REGEX MATCH "^([0-9]+)\\.?([0-9]*)" m "${mean}")
        set(int_part ${CMAKE_MATCH_1})
        string(SUBSTRING "${CMAKE_MATCH_2}000000" 0 6 frac)
        math(EXPR got "${int_part} * 1000000 + 1${frac} - 1000000")
        math(EXPR diff "${got} - ${expect}")
        if(diff LESS 0)
            math(EXPR diff "-${diff}")
        endif()
        math(EXPR limit "${expect} / 100")
        message(STATUS "furnace rho ${rho}, B = ${B}: reference mean ${mean}, closed form ${expect} e-6")
        if(diff GREATER limit)
            message(SEND_ERROR "furnace rho ${rho}, B = ${B}: reference mean ${mean}, closed form ${expect} e-6 (more than 1 % apart)")
            math(EXPR failures "${failures} + 1")
        endif()
    endforeach()
endforeach()
if(failures GREATER 0)
    message(FATAL_ERROR "${failures} furnace reference check(s) failed")
endif()
