# conf(<method> <expected exit>): runs the conformance suite on one method
# with --json, keeps its output as ${CONF_JSON_PREFIX}<method>.json and
# leaves the table in the variable `table`. Shared by suite_test.cmake and
# departure_test.cmake; needs GIB, fail() (expect.cmake) and `failures`.
function(conf method code)
    execute_process(COMMAND ${GIB} -q conformance --method ${method} --json --item-timeout 30
                    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
    file(WRITE ${CONF_JSON_PREFIX}${method}.json "${out}")
    if(NOT rc EQUAL code)
        fail("conformance --method ${method}: exit ${rc}, expected ${code}\n${out}\n${err}")
    endif()
    set(table "${out}" PARENT_SCOPE)
    set(failures ${failures} PARENT_SCOPE)
endfunction()
