# Tests of the extra solve paths of the error-against-time report (issue 5): conjugate gradients,
# single precision, the traditional band Cholesky, the mass-spring model. Included from
# Testing/Core/CMakeLists.txt.
find_package(GTest REQUIRED)
include(GoogleTest)
add_executable(TestSolvePaths "${CMAKE_CURRENT_LIST_DIR}/TestSolvePaths.cpp")
target_link_libraries(TestSolvePaths PRIVATE FacePlanCore GTest::gtest GTest::gtest_main)
gtest_discover_tests(TestSolvePaths TEST_PREFIX "SolvePaths." DISCOVERY_TIMEOUT 60 PROPERTIES LABELS "core")
