# Install the headers, the exported targets (pcr::<component>) and a relocatable pcrConfig.cmake
# that calls find_dependency() for exactly the packages the built components link to.
get_property(PCR_EXPORTED_TARGETS GLOBAL PROPERTY PCR_EXPORTED_TARGETS)
get_property(PCR_BUILT_COMPONENTS GLOBAL PROPERTY PCR_BUILT_COMPONENTS)

# Imported-target prefix -> find_dependency() arguments. A static library's private dependencies
# are part of its exported link interface ($<LINK_ONLY:...>), so they must be found too.
set(_pcr_dep_Eigen3 "Eigen3 3.3 NO_MODULE")
set(_pcr_dep_Ceres "Ceres")
set(_pcr_dep_SUNDIALS "SUNDIALS")
set(_pcr_dep_nlohmann_json "nlohmann_json 3")
set(_pcr_dep_apriltag "apriltag")
set(_pcr_dep_opencv "OpenCV")
set(_pcr_dep_CLI11 "CLI11")
set(_pcr_dep_Threads "Threads")
set(_pcr_dep_OpenMP "OpenMP")
set(_pcr_dep_benchmark "benchmark")
set(_pcr_dep_GTest "GTest")

set(_pcr_dependencies "")
foreach(_target IN LISTS PCR_EXPORTED_TARGETS)
  get_target_property(_libs ${_target} INTERFACE_LINK_LIBRARIES)
  if(NOT _libs)
    continue()
  endif()
  foreach(_lib IN LISTS _libs)
    # Names of imported targets, also inside generator expressions ($<LINK_ONLY:Ceres::ceres>).
    string(REGEX MATCHALL "[A-Za-z0-9_]+::[A-Za-z0-9_.+-]+|opencv_[a-z0-9_]+" _names "${_lib}")
    foreach(_name IN LISTS _names)
      string(REGEX REPLACE "^([A-Za-z0-9_]+)(::|_).*$" "\\1" _prefix "${_name}")
      if(_prefix STREQUAL "pcr")
        continue()
      elseif(DEFINED _pcr_dep_${_prefix})
        list(APPEND _pcr_dependencies "${_pcr_dep_${_prefix}}")
      else()
        message(WARNING "pcr: exported target ${_target} links ${_name}: add its package to "
                        "cmake/PcrInstall.cmake so pcrConfig.cmake finds it")
      endif()
    endforeach()
  endforeach()
endforeach()
list(REMOVE_DUPLICATES _pcr_dependencies)
set(PCR_FIND_DEPENDENCIES "")
foreach(_dep IN LISTS _pcr_dependencies)
  string(APPEND PCR_FIND_DEPENDENCIES "find_dependency(${_dep})\n")
endforeach()

install(DIRECTORY include/pcr DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(TARGETS ${PCR_EXPORTED_TARGETS} EXPORT pcrTargets
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
set(PCR_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/pcr)
install(EXPORT pcrTargets NAMESPACE pcr:: DESTINATION ${PCR_INSTALL_CMAKEDIR})
# The build tree is a package too (-Dpcr_DIR=<build>), so that `pip install ./python` can link the
# libraries it already built.
export(EXPORT pcrTargets NAMESPACE pcr:: FILE ${PROJECT_BINARY_DIR}/pcrTargets.cmake)
configure_package_config_file(cmake/pcrConfig.cmake.in ${PROJECT_BINARY_DIR}/pcrConfig.cmake
  INSTALL_DESTINATION ${PCR_INSTALL_CMAKEDIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/pcrConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/pcrConfig.cmake ${PROJECT_BINARY_DIR}/pcrConfigVersion.cmake
  DESTINATION ${PCR_INSTALL_CMAKEDIR})
