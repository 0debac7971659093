# Builds libplumage.so and libplumage.a with cargo, stages them in the build
# tree under their installed names (libplumage.so -> libplumage.so.MAJOR ->
# libplumage.so.MAJOR.MINOR.PATCH) and exposes the shared one as the imported
# target `plumage`. PLUMAGE_VERSION{,_MAJOR,_MINOR,_PATCH} come from Cargo.toml.
find_program(PLUMAGE_CARGO cargo HINTS "$ENV{HOME}/.cargo/bin" "$ENV{CARGO_HOME}/bin")
if(NOT PLUMAGE_CARGO)
  message(FATAL_ERROR "cargo not found: install Rust (https://rustup.rs) or put cargo on PATH")
endif()

# The package version: the first `version = "X.Y.Z"` of Cargo.toml ([package]).
set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS "${PLUMAGE_ROOT}/Cargo.toml")
file(STRINGS "${PLUMAGE_ROOT}/Cargo.toml" _plumage_version_line REGEX "^version = \"[0-9]+\\.[0-9]+\\.[0-9]+\"" LIMIT_COUNT 1)
if(NOT _plumage_version_line MATCHES "\"(([0-9]+)\\.([0-9]+)\\.([0-9]+))\"")
  message(FATAL_ERROR "no version = \"X.Y.Z\" line in ${PLUMAGE_ROOT}/Cargo.toml")
endif()
set(PLUMAGE_VERSION "${CMAKE_MATCH_1}")
set(PLUMAGE_VERSION_MAJOR "${CMAKE_MATCH_2}")
set(PLUMAGE_VERSION_MINOR "${CMAKE_MATCH_3}")
set(PLUMAGE_VERSION_PATCH "${CMAKE_MATCH_4}")
# Must match what build.rs gives the library (checked by the consumer test with readelf).
set(PLUMAGE_SONAME "libplumage.so.${PLUMAGE_VERSION_MAJOR}")

if(DEFINED ENV{CARGO_TARGET_DIR})
  set(PLUMAGE_CARGO_TARGET_DIR "$ENV{CARGO_TARGET_DIR}")
else()
  set(PLUMAGE_CARGO_TARGET_DIR "${PLUMAGE_ROOT}/target")
endif()

set(PLUMAGE_CARGO_ARGS build --release --lib --manifest-path "${PLUMAGE_ROOT}/Cargo.toml")
if(PLUMAGE_TEST_HOOKS)
  # A separate target dir so the hooked library never replaces the normal one.
  set(PLUMAGE_CARGO_TARGET_DIR "${PLUMAGE_CARGO_TARGET_DIR}/test-hooks")
  list(APPEND PLUMAGE_CARGO_ARGS --features test-hooks)
endif()
set(_plumage_cargo_out "${PLUMAGE_CARGO_TARGET_DIR}/release")

# What programs link and load, and what `cmake --install` copies.
set(PLUMAGE_STAGE_DIR "${CMAKE_BINARY_DIR}/plumage_lib")
set(PLUMAGE_LIBRARY "${PLUMAGE_STAGE_DIR}/libplumage.so.${PLUMAGE_VERSION}")
set(PLUMAGE_STATIC_LIBRARY "${PLUMAGE_STAGE_DIR}/libplumage.a")

add_custom_target(plumage_cargo ALL
  COMMAND ${CMAKE_COMMAND} -E env "CARGO_TARGET_DIR=${PLUMAGE_CARGO_TARGET_DIR}" ${PLUMAGE_CARGO} ${PLUMAGE_CARGO_ARGS}
  COMMAND ${CMAKE_COMMAND} -E make_directory "${PLUMAGE_STAGE_DIR}"
  COMMAND ${CMAKE_COMMAND} -E copy_if_different "${_plumage_cargo_out}/libplumage.so" "${PLUMAGE_LIBRARY}"
  COMMAND ${CMAKE_COMMAND} -E copy_if_different "${_plumage_cargo_out}/libplumage.a" "${PLUMAGE_STATIC_LIBRARY}"
  COMMAND ${CMAKE_COMMAND} -E create_symlink "libplumage.so.${PLUMAGE_VERSION}" "${PLUMAGE_STAGE_DIR}/${PLUMAGE_SONAME}"
  COMMAND ${CMAKE_COMMAND} -E create_symlink "${PLUMAGE_SONAME}" "${PLUMAGE_STAGE_DIR}/libplumage.so"
  WORKING_DIRECTORY "${PLUMAGE_ROOT}"
  BYPRODUCTS "${PLUMAGE_LIBRARY}" "${PLUMAGE_STATIC_LIBRARY}"
  COMMENT "cargo build --release (libplumage.so, libplumage.a)"
  USES_TERMINAL)

add_library(plumage SHARED IMPORTED GLOBAL)
set_target_properties(plumage PROPERTIES
  IMPORTED_LOCATION "${PLUMAGE_LIBRARY}"
  IMPORTED_SONAME "${PLUMAGE_SONAME}"
  INTERFACE_INCLUDE_DIRECTORIES "${PLUMAGE_ROOT}/include")
add_dependencies(plumage plumage_cargo)
