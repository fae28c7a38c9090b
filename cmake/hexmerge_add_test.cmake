include(${CMAKE_CURRENT_LIST_DIR}/recipes/gtest.cmake)
include(GoogleTest)

# hexmerge_add_test(<name> <source>...)
# Creates the test runner <name> from the sources, links GoogleTest's main, the core library and
# the TetGen interface (the fixtures' TetGen meshes), and registers every TEST with CTest through
# gtest_discover_tests.
function(hexmerge_add_test name)
  add_executable(${name} ${ARGN})
  target_link_libraries(${name} PRIVATE GTest::gtest_main hexmerge::core hexmerge::tetgen
                                        hexmerge_warnings)
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR}/tests/cpp)
  # Discovery runs the runner at test time, not at build time: the build never depends on the
  # runner starting (and a slow first run does not hit the build's discovery timeout).
  gtest_discover_tests(${name} DISCOVERY_MODE PRE_TEST)
endfunction()
