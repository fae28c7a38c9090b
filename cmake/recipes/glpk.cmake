# GLPK (GNU Linear Programming Kit) from Debian's libglpk-dev. GLPK ships no CMake config, so the
# header and library are found by name. Defines the imported target GLPK::GLPK, or nothing when
# GLPK is not installed: the callers test `if(TARGET GLPK::GLPK)`. Returns early when a parent
# project already provides the target.
if(TARGET GLPK::GLPK)
  return()
endif()

find_path(GLPK_INCLUDE_DIR glpk.h)
find_library(GLPK_LIBRARY glpk)
if(NOT GLPK_INCLUDE_DIR OR NOT GLPK_LIBRARY)
  message(STATUS "GLPK not found: the selection's optimality bound is not built (Debian: libglpk-dev)")
  return()
endif()

# GLOBAL: the core library links it privately, and a static library's private links reach every
# target that links the core (tests, the Python module) in other directories.
add_library(GLPK::GLPK UNKNOWN IMPORTED GLOBAL)
set_target_properties(GLPK::GLPK PROPERTIES
  IMPORTED_LOCATION "${GLPK_LIBRARY}"
  INTERFACE_INCLUDE_DIRECTORIES "${GLPK_INCLUDE_DIR}")
message(STATUS "GLPK: ${GLPK_LIBRARY}: building the selection's optimality bound")
