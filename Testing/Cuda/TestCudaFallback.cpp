// Runs on every machine (label `cuda`): the CUDA backend either works or refuses with a message,
// so that callers can fall back to the CPU; it never throws or aborts.
#include "CudaBackend.h"

#include <gtest/gtest.h>

#include <cstdlib>

namespace faceplan {
namespace {

TEST(CudaFallback, BackendIsUsableOrRefusesWithAMessage) {
  std::string why;
  const bool available = cuda::DeviceAvailable(&why);
  std::string error;
  auto backend = cuda::MakeCudaBackend(error);
  if (available) {
    ASSERT_TRUE(backend) << error;
    EXPECT_EQ(backend->name().rfind("CUDA", 0), 0u);
    EXPECT_FALSE(cuda::DeviceDescription().empty());
  } else {
    EXPECT_FALSE(backend);
    EXPECT_FALSE(why.empty());
    EXPECT_FALSE(error.empty());
    std::printf("no GPU: %s\n", error.c_str());
  }
}

TEST(CudaFallback, DisabledByEnvironment) {
  setenv("FACEPLAN_DISABLE_CUDA", "1", 1);
  std::string error;
  auto backend = cuda::MakeCudaBackend(error);
  unsetenv("FACEPLAN_DISABLE_CUDA");
  EXPECT_FALSE(backend);
  EXPECT_NE(error.find("FACEPLAN_DISABLE_CUDA"), std::string::npos) << error;
}

} // namespace
} // namespace faceplan
