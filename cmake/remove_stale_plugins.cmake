# Removes from PLUGIN_DIR every gimethod_<id>.so whose <id> is not in IDS
# (a ;-list): the .so of a plugin whose folder was deleted from plugins/,
# which the loader would otherwise still find. Included by the top-level
# CMakeLists.txt at configure time (which a deleted plugin folder triggers,
# through the glob of plugins/*/CMakeLists.txt), and run by the test
# integration.stale_plugins as: cmake -DPLUGIN_DIR=... -DIDS=a;b -P remove_stale_plugins.cmake
cmake_policy(SET CMP0057 NEW) # if(IN_LIST) in script mode too
file(GLOB gi_built_plugins ${PLUGIN_DIR}/gimethod_*.so)
foreach(so ${gi_built_plugins})
    get_filename_component(name ${so} NAME_WE)
    string(REGEX REPLACE "^gimethod_" "" id "${name}")
    if(NOT id IN_LIST IDS)
        message(STATUS "Removing ${so}: no folder under plugins/ builds method '${id}' any more")
        file(REMOVE ${so})
    endif()
endforeach()
