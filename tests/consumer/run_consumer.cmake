# SPDX-License-Identifier: AGPL-3.0-or-later
# The install_consumer test (cmake -P): installs the build into a fresh prefix, then configures,
# builds and runs tests/consumer against that prefix alone, so a header, library or dependency
# missing from the installed package fails here rather than in a user's project.
# In: KDMESH_BUILD_DIR, CONSUMER_SOURCE_DIR, CXX_COMPILER, BUILD_TYPE.
cmake_minimum_required(VERSION 3.25)

set(prefix "${KDMESH_BUILD_DIR}/test-install")
set(consumer_build "${KDMESH_BUILD_DIR}/test-consumer")
# Fresh every time: files left by an earlier install must not hide one this install forgot.
file(REMOVE_RECURSE "${prefix}" "${consumer_build}")

function(step)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    string(JOIN " " cmd ${ARGN})
    message(FATAL_ERROR "install_consumer: failed (${rc}): ${cmd}")
  endif()
endfunction()

step("${CMAKE_COMMAND}" --install "${KDMESH_BUILD_DIR}" --prefix "${prefix}")
# Only the prefix is searched: no package registry, no kdmesh source or build tree.
step("${CMAKE_COMMAND}" -S "${CONSUMER_SOURCE_DIR}" -B "${consumer_build}"
     "-DCMAKE_PREFIX_PATH=${prefix}" "-DCMAKE_BUILD_TYPE=${BUILD_TYPE}"
     "-DCMAKE_CXX_COMPILER=${CXX_COMPILER}"
     -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF -DCMAKE_FIND_USE_SYSTEM_PACKAGE_REGISTRY=OFF)
# Prove where kdmesh came from.
file(STRINGS "${consumer_build}/CMakeCache.txt" kdmesh_dir REGEX "^kdmesh_DIR:")
string(REGEX REPLACE "^[^=]*=" "" kdmesh_dir "${kdmesh_dir}")
if(NOT kdmesh_dir MATCHES "^${prefix}/")
  message(FATAL_ERROR "install_consumer: kdmesh was found in '${kdmesh_dir}', not under ${prefix}")
endif()
message(STATUS "install_consumer: kdmesh_DIR = ${kdmesh_dir}")
step("${CMAKE_COMMAND}" --build "${consumer_build}")
step("${consumer_build}/consumer" "${consumer_build}/cube.vtu")
if(NOT EXISTS "${consumer_build}/cube.vtu")
  message(FATAL_ERROR "install_consumer: the consumer wrote no cube.vtu")
endif()
message(STATUS "install_consumer: passed")
