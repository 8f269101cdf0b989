# pcr_register_component(NAME TARGET): export TARGET as pcr::NAME and let pcrConfig.cmake know NAME
# was built. The package config then calls find_dependency() for the packages TARGET links to
# (cmake/PcrInstall.cmake reads them from its link libraries).
function(pcr_register_component name target)
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${name})
  set_property(GLOBAL APPEND PROPERTY PCR_EXPORTED_TARGETS ${target})
  set_property(GLOBAL APPEND PROPERTY PCR_BUILT_COMPONENTS ${name})
endfunction()

# pcr_add_test(NAME SOURCES... LIBS... LABELS...): a GoogleTest program registered with ctest, every
# test it discovers carrying LABELS (their meaning: tests/CMakeLists.txt).
function(pcr_add_test name)
  cmake_parse_arguments(ARG "" "" "SOURCES;LIBS;LABELS" ${ARGN})
  if(NOT ARG_LABELS)
    message(FATAL_ERROR "pcr_add_test(${name}): LABELS missing")
  endif()
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS} GTest::gtest GTest::gtest_main)
  target_compile_definitions(${name} PRIVATE PCR_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
                                             PCR_BINARY_DIR="${PROJECT_BINARY_DIR}")
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60)
  if("inputs" IN_LIST ARG_LABELS)
    set_property(GLOBAL APPEND PROPERTY PCR_INPUT_CHECKS ${name})
  endif()
  # Not gtest_discover_tests(PROPERTIES LABELS ...), which flattens a list value (LABELS unit cli
  # reaches set_tests_properties as three words). ctest runs this script after the discovered
  # tests' own, which leaves their names in <name>_TESTS.
  set(labels_script ${CMAKE_CURRENT_BINARY_DIR}/${name}_labels.cmake)
  file(WRITE ${labels_script}
    "if(${name}_TESTS)\n"
    "  set_tests_properties(\${${name}_TESTS} PROPERTIES LABELS \"${ARG_LABELS}\")\n"
    "endif()\n")
  set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES ${labels_script})
endfunction()

# pcr_fuzz_instrument(SOURCES...): with PCR_FUZZ, these sources (the parsers of users' files) are
# compiled with libFuzzer's coverage instrumentation, which guides the fuzz targets in
# tests/fuzz. Only they: the rest of the sanitizer build, which runs the whole suite, stays as fast.
function(pcr_fuzz_instrument)
  if(PCR_FUZZ)
    set_source_files_properties(${ARGN} DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}
                                PROPERTIES COMPILE_OPTIONS -fsanitize=fuzzer-no-link)
  endif()
endfunction()
