# What `cmake --install BUILD --prefix P` puts under P:
#   bin/mgrl                               the command line
#   lib/libmgrl_*.a                        the framework's stages, the plug-ins, the built-in registries
#   include/mgrl/<stage>/*.hpp             the framework's headers, as the sources include them
#   include/mgrl/builtin_plugins.hpp       the composition root (mgrl::builtinPlugins())
#   lib/cmake/mgrl/                        find_package(mgrl CONFIG): mgrl::<stage>, mgrl::builtins
#   share/mgrl/scenarios/                  the scenarios (mgrl train P/share/mgrl/scenarios/boxing.yaml)
#   share/mgrl/web/                        the viewer's page with the parts of three.js it loads
# The installed mgrl finds its page beside itself (P/bin/../share/mgrl/web); docs/install.md.
include(CMakePackageConfigHelpers)

set(MGRL_INSTALL_CMAKEDIR "${CMAKE_INSTALL_LIBDIR}/cmake/mgrl")
set(MGRL_INSTALL_SHAREDIR "${CMAKE_INSTALL_DATADIR}/mgrl")

set(mgrl_exported mgrl_core mgrl_motion mgrl_graph mgrl_learning mgrl_runtime mgrl_scenario mgrl_session
                  mgrl_reports mgrl_starter mgrl_discretizers mgrl_rewards mgrl_environments mgrl_learners
                  mgrl_builtins)
install(TARGETS ${mgrl_exported} EXPORT mgrlTargets ARCHIVE DESTINATION "${CMAKE_INSTALL_LIBDIR}")
install(TARGETS mgrl RUNTIME DESTINATION "${CMAKE_INSTALL_BINDIR}")
install(DIRECTORY "${MGRL_INCLUDE_DIR}/mgrl" DESTINATION "${CMAKE_INSTALL_INCLUDEDIR}")
install(FILES "${PROJECT_SOURCE_DIR}/app/builtins/builtin_plugins.hpp" DESTINATION "${CMAKE_INSTALL_INCLUDEDIR}/mgrl")
install(EXPORT mgrlTargets NAMESPACE mgrl:: DESTINATION "${MGRL_INSTALL_CMAKEDIR}")

# The package's dependencies are found again where it is used: the libraries the stages
# link publicly, and MPI when the learners were built with it (linked by the static library).
if(NOT MGRL_WITH_MPI)  # set by learners/CMakeLists.txt when it found MPI
  set(MGRL_WITH_MPI OFF)
endif()
configure_package_config_file("${PROJECT_SOURCE_DIR}/cmake/mgrlConfig.cmake.in"
                              "${PROJECT_BINARY_DIR}/mgrlConfig.cmake" INSTALL_DESTINATION "${MGRL_INSTALL_CMAKEDIR}")
write_basic_package_version_file("${PROJECT_BINARY_DIR}/mgrlConfigVersion.cmake" COMPATIBILITY SameMinorVersion)
install(FILES "${PROJECT_BINARY_DIR}/mgrlConfig.cmake" "${PROJECT_BINARY_DIR}/mgrlConfigVersion.cmake"
        DESTINATION "${MGRL_INSTALL_CMAKEDIR}")

install(DIRECTORY "${PROJECT_SOURCE_DIR}/scenarios/" DESTINATION "${MGRL_INSTALL_SHAREDIR}/scenarios"
        FILES_MATCHING PATTERN "*.yaml" PATTERN "*.md")

# The page, and of three.js (npm's copy in web/node_modules, scripts/setup.sh) what it loads.
set(three "${PROJECT_SOURCE_DIR}/web/node_modules/three")
install(CODE "
  if(NOT EXISTS \"${three}/build/three.module.js\")
    message(FATAL_ERROR \"mgrl install: expected three.js in ${three} (scripts/setup.sh runs npm ci in web/), found none\")
  endif()")
install(DIRECTORY "${PROJECT_SOURCE_DIR}/web/" DESTINATION "${MGRL_INSTALL_SHAREDIR}/web"
        FILES_MATCHING PATTERN "*.html" PATTERN "*.js" PATTERN "*.css"
        PATTERN "node_modules" EXCLUDE PATTERN "tests" EXCLUDE)
install(FILES "${three}/build/three.module.js" "${three}/build/three.core.js"
        DESTINATION "${MGRL_INSTALL_SHAREDIR}/web/node_modules/three/build")
install(FILES "${three}/examples/jsm/controls/OrbitControls.js"
        DESTINATION "${MGRL_INSTALL_SHAREDIR}/web/node_modules/three/examples/jsm/controls")
install(FILES "${three}/LICENSE" "${three}/package.json" DESTINATION "${MGRL_INSTALL_SHAREDIR}/web/node_modules/three")
