# ROI / Bezier-cut Core tests (GoogleTest), included from Testing/Core/CMakeLists.txt.
find_package(GTest REQUIRED)
add_executable(TestBezierCutCore
  "${CMAKE_CURRENT_LIST_DIR}/TestROIExtract.cpp"
  "${CMAKE_CURRENT_LIST_DIR}/TestBezierCut.cpp")
target_link_libraries(TestBezierCutCore PRIVATE FacePlanCore GTest::gtest GTest::gtest_main)
target_include_directories(TestBezierCutCore PRIVATE "${CMAKE_CURRENT_LIST_DIR}")
include(GoogleTest)
gtest_discover_tests(TestBezierCutCore TEST_PREFIX "BezierCutCore." DISCOVERY_TIMEOUT 60)
