# GoogleTest from Debian's libgtest-dev (no download). Returns early when a parent project
# already provides the target.
if(TARGET GTest::gtest_main)
  return()
endif()
find_package(GTest REQUIRED)
