# Builds libplumage.so with cargo and exposes it as the imported target `plumage`.
find_program(PLUMAGE_CARGO cargo HINTS "$ENV{HOME}/.cargo/bin" "$ENV{CARGO_HOME}/bin")
if(NOT PLUMAGE_CARGO)
  message(FATAL_ERROR "cargo not found: install Rust (https://rustup.rs) or put cargo on PATH")
endif()

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
set(PLUMAGE_LIBRARY "${PLUMAGE_CARGO_TARGET_DIR}/release/libplumage.so")

add_custom_target(plumage_cargo ALL
  COMMAND ${CMAKE_COMMAND} -E env "CARGO_TARGET_DIR=${PLUMAGE_CARGO_TARGET_DIR}" ${PLUMAGE_CARGO} ${PLUMAGE_CARGO_ARGS}
  WORKING_DIRECTORY "${PLUMAGE_ROOT}"
  BYPRODUCTS "${PLUMAGE_LIBRARY}"
  COMMENT "cargo build --release (libplumage.so)"
  USES_TERMINAL)

add_library(plumage SHARED IMPORTED GLOBAL)
set_target_properties(plumage PROPERTIES
  IMPORTED_LOCATION "${PLUMAGE_LIBRARY}"
  IMPORTED_NO_SONAME ON
  INTERFACE_INCLUDE_DIRECTORIES "${PLUMAGE_ROOT}/include")
add_dependencies(plumage plumage_cargo)
