# `cmake --install BUILD [--prefix DIR]`: the library as a system library,
# in the GNUInstallDirs places under any prefix (README, "Installing"):
#   LIBDIR/libplumage.so.X.Y.Z, libplumage.so.X -> it, libplumage.so -> .so.X, libplumage.a
#   INCLUDEDIR/plumage.h (and the optional C++ wrapper plumage.hpp)
#   LIBDIR/cmake/Plumage/PlumageConfig.cmake, PlumageConfigVersion.cmake
#     (find_package(Plumage): Plumage::plumage, Plumage::plumage_static)
#   LIBDIR/pkgconfig/plumage.pc
# Every path written into the package files is relative to where they are
# installed, so the prefix may also be chosen at install time.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

install(FILES "${PLUMAGE_LIBRARY}" DESTINATION "${CMAKE_INSTALL_LIBDIR}"
  PERMISSIONS OWNER_READ OWNER_WRITE OWNER_EXECUTE GROUP_READ GROUP_EXECUTE WORLD_READ WORLD_EXECUTE)
# The two symbolic links, installed as links.
install(FILES "${PLUMAGE_STAGE_DIR}/${PLUMAGE_SONAME}" "${PLUMAGE_STAGE_DIR}/libplumage.so"
  DESTINATION "${CMAKE_INSTALL_LIBDIR}")
install(FILES "${PLUMAGE_STATIC_LIBRARY}" DESTINATION "${CMAKE_INSTALL_LIBDIR}")
install(FILES "${PLUMAGE_ROOT}/include/plumage.h" "${PLUMAGE_ROOT}/include/plumage.hpp" DESTINATION "${CMAKE_INSTALL_INCLUDEDIR}")

# What a static link of Rust's standard library needs (rustc --print native-static-libs on Linux).
set(PLUMAGE_STATIC_DEPS gcc_s util rt pthread m dl)
list(TRANSFORM PLUMAGE_STATIC_DEPS PREPEND "-l" OUTPUT_VARIABLE _plumage_static_flags)
list(JOIN _plumage_static_flags " " PLUMAGE_STATIC_LIBS_PRIVATE)

set(PLUMAGE_CMAKE_DIR "${CMAKE_INSTALL_LIBDIR}/cmake/Plumage")
set(_plumage_pkg "${CMAKE_BINARY_DIR}/plumage_package")
configure_package_config_file("${CMAKE_CURRENT_LIST_DIR}/PlumageConfig.cmake.in"
  "${_plumage_pkg}/PlumageConfig.cmake"
  INSTALL_DESTINATION "${PLUMAGE_CMAKE_DIR}"
  PATH_VARS CMAKE_INSTALL_LIBDIR CMAKE_INSTALL_INCLUDEDIR)
# Same MAJOR = same SONAME = compatible (README, "ABI versions"), 0.x included.
write_basic_package_version_file("${_plumage_pkg}/PlumageConfigVersion.cmake"
  VERSION "${PLUMAGE_VERSION}" COMPATIBILITY SameMajorVersion)
install(FILES "${_plumage_pkg}/PlumageConfig.cmake" "${_plumage_pkg}/PlumageConfigVersion.cmake"
  DESTINATION "${PLUMAGE_CMAKE_DIR}")

# plumage.pc finds the prefix from its own place (${pcfiledir}) when the
# directories are relative, as GNUInstallDirs makes them.
set(_plumage_pc_dir "${CMAKE_INSTALL_LIBDIR}/pkgconfig")
if(IS_ABSOLUTE "${CMAKE_INSTALL_LIBDIR}")
  set(PLUMAGE_PC_PREFIX "${CMAKE_INSTALL_PREFIX}")
else()
  file(RELATIVE_PATH _plumage_up "/root/${_plumage_pc_dir}" "/root")
  string(REGEX REPLACE "/$" "" _plumage_up "${_plumage_up}")
  set(PLUMAGE_PC_PREFIX "\${pcfiledir}/${_plumage_up}")
endif()
foreach(_dir LIBDIR INCLUDEDIR)
  if(IS_ABSOLUTE "${CMAKE_INSTALL_${_dir}}")
    set(PLUMAGE_PC_${_dir} "${CMAKE_INSTALL_${_dir}}")
  else()
    set(PLUMAGE_PC_${_dir} "\${prefix}/${CMAKE_INSTALL_${_dir}}")
  endif()
endforeach()
configure_file("${CMAKE_CURRENT_LIST_DIR}/plumage.pc.in" "${_plumage_pkg}/plumage.pc" @ONLY)
install(FILES "${_plumage_pkg}/plumage.pc" DESTINATION "${_plumage_pc_dir}")
