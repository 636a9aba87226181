# The conformance suite must be able to fail: fake methods that each break
# one rule (tests/unit/fake_plugin.c, FAKE_CONF_* and the compare tests'
# crash and narrow kinds) must fail exactly the row of that rule, a method
# whose caps exclude a case gets n/a with the reason, a crashing method
# fails its rows without taking the table down, and bad usage exits 2.
include(${EXPECT})
set(failures 0)
set(ENV{GIBENCH_PLUGIN_PATH} ${FAKES})
file(MAKE_DIRECTORY ${OUT})

set(CONF_JSON_PREFIX ${OUT}/suite_)
include(${CMAKE_CURRENT_LIST_DIR}/conf_run.cmake)

# cell(<check> <status> <regex of the detail>)
function(cell check status re)
    string(JSON st ERROR_VARIABLE e1 GET "${table}" methods 0 checks ${check} status)
    string(JSON detail ERROR_VARIABLE e2 GET "${table}" methods 0 checks ${check} detail)
    if(NOT st STREQUAL status OR NOT detail MATCHES "${re}")
        fail("check ${check}: expected ${status} with '${re}', got ${st}: ${detail} ${e1}${e2}")
    endif()
    set(failures ${failures} PARENT_SCOPE)
endfunction()

# The emission alone where Le (1 + rho) is due.
conf(fake_conf_wrong 1)
cell(furnace_0.5 fail "mean 1.0000, expected 1.5000")
cell(furnace_0.8 fail "expected 1.8000")
cell(determinism pass "bit-identical")
# claims area light, but the image does not change when it is removed
cell(light_area fail "claims area light")
cell(light_point n/a "does not handle point or spot lights")

# NaN everywhere: every scene it covers fails, and so does the furnace.
conf(fake_conf_nan 1)
cell(scenes fail "NaN or Inf")
cell(furnace_0.5 fail "NaN or Inf")

# A new image on every call.
conf(fake_conf_nondet 1)
cell(determinism fail "pixels differ")
cell(unknown_params pass "refused")

# Claims every light type and renders black.
conf(fake_conf_liar 1)
cell(light_point fail "claims point light but .* mean 0")
cell(light_directional fail "claims directional light")
cell(light_environment fail "claims environment light")

# Caps that exclude the cases: n/a with the reason, never a silent pass.
conf(fake_narrow 0) # nothing it claims is wrong: all n/a, exit 0
cell(furnace_0.5 n/a "does not handle area lights")
cell(light_area n/a "does not handle area lights")
cell(update_transforms n/a "does not claim rigid motion")
cell(update_vertices n/a "does not claim deformation")
cell(determinism n/a "no test scene within the caps")

# A method that crashes in render(): every rendering row fails with the
# crash, the rows that need no rendering still pass, the table is complete.
conf(fake_crash 1)
cell(furnace_0.5 fail "crashed \\(signal 11")
cell(determinism fail "crashed")
cell(unknown_params pass "refused")

# The text table: one line per check, a column per method.
execute_process(COMMAND ${GIB} -q conformance --method fake_conf_nondet RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_QUIET)
if(NOT rc EQUAL 1 OR NOT out MATCHES "check +fake_conf_nondet" OR NOT out MATCHES "\ndeterminism +fail")
    fail("text table: exit ${rc}\n${out}")
endif()

# Bad usage: exit 2 with one line.
expect(2 "no method 'no_such_method'" conformance --method no_such_method)
expect(2 "--size '8' is not an integer in 32..64" conformance --size 8)
expect(2 "unknown argument '--bogus'" conformance --bogus)
expect(2 "--method needs a value" conformance --method)

if(failures GREATER 0)
    message(FATAL_ERROR "${failures} conformance-suite expectation(s) failed")
endif()
