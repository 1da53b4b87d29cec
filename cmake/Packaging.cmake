# The Debian package (issue #16): `cpack` in the build folder (or
# `cmake --build build --target package`) writes
# ground-aware-mapping_<version>_amd64.deb with everything `cmake --install`
# installs, under /usr. Depends are computed from the binaries' shared
# libraries (dpkg-shlibdeps: libmrpt-*, libwx*, liboctomap...); the SDK part
# (headers, CMake package) also needs the -dev packages, which the package
# recommends.
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME ground-aware-mapping)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_VENDOR "ground-aware mapping for MRPT")
set(CPACK_PACKAGE_CONTACT "ground-aware mapping developers <ground-aware-mapping@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
  "Ground-aware 2D occupancy grids from depth cameras for MRPT (RRT-GPD ground detection, negative obstacles)")
set(CPACK_PACKAGE_DESCRIPTION
  "MRPT map classes CGroundAwareOccupancyGrid and CElevation25DMap (a plugin for stock MRPT apps), the comparison maps, ground-aware-mapper, ground-aware-viewer, the simulator and evaluation tools, and the SDK (headers, CMake package GroundAwareMapping).")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
# dpkg-shlibdeps must find this package's own libraries (they are not installed yet).
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS_PRIVATE_DIRS ${CMAKE_BINARY_DIR}/lib)
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "libmrpt-dev, libeigen3-dev, mrpt-apps")
set(CPACK_STRIP_FILES ON)
include(CPack)
