# Numerical-stability tests (issue 6), included from Testing/Core/CMakeLists.txt.
find_package(GTest REQUIRED)
add_executable(TestStability
  "${CMAKE_CURRENT_LIST_DIR}/TestStability.cpp"
  "${CMAKE_CURRENT_LIST_DIR}/FEMTestScenes.cpp")
target_link_libraries(TestStability PRIVATE FacePlanCore GTest::gtest GTest::gtest_main)
target_include_directories(TestStability PRIVATE "${CMAKE_CURRENT_LIST_DIR}")
include(GoogleTest)
gtest_discover_tests(TestStability DISCOVERY_TIMEOUT 60 PROPERTIES LABELS "core;stability")
