# pcr_register_component(NAME TARGET): export TARGET as pcr::NAME and let pcrConfig.cmake know NAME
# was built. The package config then calls find_dependency() for the packages TARGET links to
# (cmake/PcrInstall.cmake reads them from its link libraries).
function(pcr_register_component name target)
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${name})
  set_property(GLOBAL APPEND PROPERTY PCR_EXPORTED_TARGETS ${target})
  set_property(GLOBAL APPEND PROPERTY PCR_BUILT_COMPONENTS ${name})
endfunction()

# pcr_add_test(NAME SOURCES... LIBS ...): a GoogleTest program registered with ctest.
function(pcr_add_test name)
  cmake_parse_arguments(ARG "" "" "SOURCES;LIBS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS} GTest::gtest GTest::gtest_main)
  target_compile_definitions(${name} PRIVATE PCR_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
                                             PCR_BINARY_DIR="${PROJECT_BINARY_DIR}")
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60)
endfunction()
