# cpack -G DEB (in the build folder): a Debian package of what cmake --install installs,
# under /usr: bin/mgrl, the Python module in Debian's dist-packages, share/mgrl, and the
# libraries, headers and CMake package. dpkg-shlibdeps finds the shared libraries the
# program and the module need (libyaml-cpp, libfmt, Open MPI, ...); Python and NumPy are
# declared. tests/package_test.sh builds it and checks it.
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME mgrl)
set(CPACK_PACKAGE_VENDOR mgrl)
set(CPACK_PACKAGE_CONTACT "mgrl developers <mgrl-dev@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
    "Avatar behaviours learned from motion capture by reinforcement learning on a motion graph")
set(CPACK_PACKAGE_DESCRIPTION
    "mgrl trains avatar behaviours (a boxer approaching and punching a target, two boxers sparring) from\
 unlabelled motion capture with reinforcement learning on a motion graph, and plays them back interactively:\
 the mgrl command, its browser viewer, the Python module and the C++ libraries.")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_DEPENDS "python3 (>= 3.11), python3-numpy")
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "python3-matplotlib, jupyter-nbconvert, python3-ipykernel")
set(CPACK_DEBIAN_PACKAGE_SUGGESTS "openmpi-bin")
include(CPack)
