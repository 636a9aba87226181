# Declared departures (gi_departure, docs/conformance.md "Declared
# departures"): a method whose paper fails a check at its defaults declares
# it with a reason and a remedy. The suite must still render the defaults
# and report their result, labelled, and hold the remedy to the same check;
# a remedy that does not fix it fails, and a failure without a declaration
# (fake_conf_wrong, conformance.suite) still fails. The declaration shows in
# `gibench methods`. fake_conf_depart renders the emission alone at its
# defaults and the closed form with fix=true; fake_conf_depart_nofix ignores
# fix (tests/unit/fake_plugin.c).
include(${EXPECT})
set(failures 0)
set(ENV{GIBENCH_PLUGIN_PATH} ${FAKES})
file(REMOVE_RECURSE ${OUT}/departure)
file(MAKE_DIRECTORY ${OUT}/departure)

# check(<json> <method index> <check> <status> <departure> <regex of the detail>)
function(check json check status dep re)
    string(JSON st ERROR_VARIABLE e1 GET "${json}" methods 0 checks ${check} status)
    string(JSON d ERROR_VARIABLE e2 GET "${json}" methods 0 checks ${check} departure)
    string(JSON detail ERROR_VARIABLE e3 GET "${json}" methods 0 checks ${check} detail)
    if(NOT st STREQUAL status OR NOT d STREQUAL dep OR NOT detail MATCHES "${re}")
        fail("${check}: expected ${status} (departure ${dep}) with '${re}', got ${st} (${d}): ${detail} ${e1}${e2}${e3}")
    endif()
    set(failures ${failures} PARENT_SCOPE)
endfunction()

set(CONF_JSON_PREFIX ${OUT}/departure/)
include(${CMAKE_CURRENT_LIST_DIR}/conf_run.cmake)

set(paper "declared departure: the fake's paper renders the emission alone; paper default \\(reported, not gated\\) fails: rho 0.5, B = 1: mean 1.0000, expected 1.5000")
# the remedy passes: the check passes, the paper's failure reported beside it (exit 1 all the
# same: a constant image cannot show update_camera's move)
conf(fake_conf_depart 1)
check("${table}" furnace_0.5 pass ON "^${paper} \\(-33.33 %\\).*; remedy fix=true: rho 0.5, B = 1: mean 1.5000, expected 1.5000 \\(\\+0.00 %\\)")
check("${table}" furnace_0.8 pass ON "paper default \\(reported, not gated\\) fails: rho 0.8.*mean 1.0000.*remedy fix=true: rho 0.8, B = 1: mean 1.8000")
check("${table}" determinism pass OFF "bit-identical")
# a remedy that fixes nothing fails, with the same labels
conf(fake_conf_depart_nofix 1)
check("${table}" furnace_0.5 fail ON "^${paper}.*; remedy fix=true: rho 0.5, B = 1: mean 1.0000, expected 1.5000")
# no declaration: the same error fails, unlabelled
conf(fake_conf_wrong 1)
check("${table}" furnace_0.5 fail OFF "^rho 0.5, B = 1: mean 1.0000, expected 1.5000")

# the text table marks it
execute_process(COMMAND ${GIB} -q conformance --method fake_conf_depart RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_QUIET)
match("${out}" "\nfurnace_0.5 +pass\\* " "the text table marks the departure")
match("${out}" "\n\\* declared departure of the paper's method" "and explains the mark")

# gibench methods shows it, text and JSON
execute_process(COMMAND ${GIB} -q methods RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_QUIET)
match("${out}" "declared departure \\(furnace\\): the fake's paper renders the emission alone\n +remedy checked instead: fix=true" "methods text")
execute_process(COMMAND ${GIB} -q methods --json RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_QUIET)
match("${out}" "\"departures\": \\[[^]]*\"check\": \"furnace\",[^]]*\"reason\": \"the fake's paper renders the emission alone\",[^]]*\"remedy\": \"fix=true\"" "methods --json")

# the held-out family: the furnaces as above, a scene scored with the remedy and the paper's
# default reported beside it
execute_process(COMMAND ${PY} ${SCRIPT} --seed 7 --out ${OUT}/departure/ho RESULT_VARIABLE rc)
execute_process(COMMAND ${GIB} -q conformance --held-out ${OUT}/departure/ho --method fake_conf_depart
                        --variants furnace_in,ceiling --no-converge --json --size 32
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
file(WRITE ${OUT}/departure/held_out.json "${out}")
match("${out}" "\"check\": \"furnace_in\",[^}]*\"status\": \"pass\"[^}]*declared departure: the fake's paper renders the emission alone; paper default \\(reported, not gated\\) fails: rho 0.5[^}]*remedy fix=true: rho 0.5, B = 1: mean 1.5000[^}]*\"departure\": true" "held-out furnace_in under the departure")
match("${out}" "\"check\": \"trivial\",[^}]*declared departure: the fake's paper renders a constant; paper default \\(reported, not gated\\) relMSE [0-9.e+-]+; remedy fix=true: relMSE [0-9.e+-]+, limit" "held-out scene scored with the remedy")
if(failures GREATER 0)
    message(FATAL_ERROR "${failures} departure check(s) failed")
endif()
