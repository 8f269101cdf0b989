# ctest driver (cmake -P): install a pcr build tree into a fresh prefix, then configure, build and
# run tests/consumer against that installation; then check the installed `pcr` tool.
#   -DPCR_BUILD_DIR=  the pcr build tree      -DWORK_DIR=   scratch directory (wiped)
#   -DGENERATOR= -DCXX_COMPILER=             -DEXPECTED_COMPONENTS=core,io,...
cmake_minimum_required(VERSION 3.18)

function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE result COMMAND_ECHO STDOUT)
  if(NOT result EQUAL 0)
    message(FATAL_ERROR "failed (${result}): ${ARGN}")
  endif()
endfunction()

# The README's C++ example is this project's main.cpp (without its first comment line).
file(READ ${CMAKE_CURRENT_LIST_DIR}/../../README.md readme)
file(READ ${CMAKE_CURRENT_LIST_DIR}/main.cpp example)
string(REGEX REPLACE "^//[^\n]*\n" "" example "${example}")
string(FIND "${readme}" "```cpp\n${example}```" at)
if(at EQUAL -1)
  message(FATAL_ERROR "README.md's C++ example differs from tests/consumer/main.cpp")
endif()

set(prefix ${WORK_DIR}/prefix)
set(build ${WORK_DIR}/build)
file(REMOVE_RECURSE ${WORK_DIR})

run(${CMAKE_COMMAND} --install ${PCR_BUILD_DIR} --prefix ${prefix})
run(${CMAKE_COMMAND} -S ${CMAKE_CURRENT_LIST_DIR} -B ${build} -G ${GENERATOR}
    -DCMAKE_CXX_COMPILER=${CXX_COMPILER} -DCMAKE_BUILD_TYPE=Release
    -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_FIND_PACKAGE_NO_PACKAGE_REGISTRY=ON
    -DPCR_CONSUMER_CHECKS=ON -DPCR_EXPECTED_PREFIX=${prefix}
    -DPCR_EXPECTED_COMPONENTS=${EXPECTED_COMPONENTS})
run(${CMAKE_COMMAND} --build ${build})

execute_process(COMMAND ${build}/pcr_consumer RESULT_VARIABLE result OUTPUT_VARIABLE output)
message("${output}")
if(NOT result EQUAL 0 OR NOT output MATCHES "pose: x = ")
  message(FATAL_ERROR "pcr_consumer failed (${result})")
endif()
# Linking pcr::solvers instead of the header-only core changes where the solvers are compiled,
# not what they compute.
execute_process(COMMAND ${build}/pcr_consumer_solvers RESULT_VARIABLE result
                OUTPUT_VARIABLE solvers_output)
if(NOT result EQUAL 0 OR NOT solvers_output STREQUAL output)
  message(FATAL_ERROR "pcr_consumer_solvers (${result}) printed\n${solvers_output}\n"
                      "instead of pcr_consumer's")
endif()

# The installed `pcr` hands the calibration subcommands to the `pcr-full` installed next to it.
if(",${EXPECTED_COMPONENTS}," MATCHES ",calib,")
  execute_process(COMMAND ${prefix}/bin/pcr sensitivity --help RESULT_VARIABLE result
                  OUTPUT_VARIABLE output ERROR_VARIABLE error)
  if(NOT result EQUAL 0 OR NOT output MATCHES "Usage: [^\n]*pcr sensitivity")
    message(FATAL_ERROR "installed pcr sensitivity --help failed (${result}): ${output}${error}")
  endif()
endif()
