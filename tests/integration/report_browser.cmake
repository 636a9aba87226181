# The study's report in a real browser: a tiny study (tests/data/studies/
# report_tiny.json), then tests/browser/report_test.js opens its index.html
# from file:// in Debian's headless Chromium through playwright-core (which
# downloads no browser) and checks the page (see that file); report.md has
# no link to a missing file. Screenshots stay in OUT/report_browser/shots.
# Skipped (SKIPPED:) only where Chromium is not installed.
# cmake -DGIB=... -DROOT=... -DOUT=... -P report_browser.cmake
set(failures 0)
include(${CMAKE_CURRENT_LIST_DIR}/expect.cmake)
set(D ${OUT}/report_browser)

find_program(CHROMIUM NAMES chromium chromium-browser)
if(NOT CHROMIUM)
    message("SKIPPED: chromium is not installed (scripts/install-deps.sh installs it)")
    return()
endif()
find_program(NODE NAMES node nodejs)
find_program(NPM NAMES npm)
if(NOT NODE OR NOT NPM)
    message(FATAL_ERROR "chromium is installed but node or npm is not (scripts/install-deps.sh installs them)")
endif()

# playwright-core from the committed lock file, installed once into the
# build tree; PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD: the browser is Debian's.
set(M ${OUT}/browser_modules)
if(NOT EXISTS ${M}/node_modules/playwright-core/package.json)
    file(MAKE_DIRECTORY ${M})
    file(COPY ${ROOT}/tests/browser/package.json ${ROOT}/tests/browser/package-lock.json DESTINATION ${M})
    execute_process(COMMAND ${CMAKE_COMMAND} -E env PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD=1
                            ${NPM} ci --no-audit --no-fund --loglevel=error
                    WORKING_DIRECTORY ${M} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
    if(NOT rc EQUAL 0)
        message(FATAL_ERROR "npm ci in ${M} failed (exit ${rc}):\n${out}\n${err}")
    endif()
endif()

file(REMOVE_RECURSE ${D})
file(MAKE_DIRECTORY ${D})
run(0 study tests/data/studies/report_tiny.json --out ${D}/study)
if(NOT EXISTS ${D}/study/index.html)
    message(FATAL_ERROR "the study wrote no index.html")
endif()

# report.md: every image link names a file that exists
file(READ ${D}/study/report.md md)
string(REGEX MATCHALL "!\\[[^]]*\\]\\([^)]*\\)" links "${md}")
list(LENGTH links nlinks)
if(nlinks LESS 3)
    fail("report.md has ${nlinks} image links, expected the reference, runs, maps and charts")
endif()
foreach(l ${links})
    string(REGEX REPLACE "^!\\[[^]]*\\]\\(([^)]*)\\)$" "\\1" target "${l}")
    if(target STREQUAL "" OR NOT EXISTS ${D}/study/${target})
        fail("report.md: broken link ${l}")
    endif()
endforeach()

execute_process(COMMAND ${CMAKE_COMMAND} -E env NODE_PATH=${M}/node_modules
                        ${NODE} ${ROOT}/tests/browser/report_test.js ${D}/study/index.html ${D}/shots ${CHROMIUM}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message("${out}${err}")
if(NOT rc EQUAL 0)
    fail("the browser test failed (exit ${rc}); screenshots in ${D}/shots")
endif()

end_checks()
