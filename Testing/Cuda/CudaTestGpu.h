// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What every GPU test case starts with: skip (GTEST_SKIP, reported as skipped, never passed) where
// no usable GPU is present, and the CUDA backend on device 0.
#include "CudaBackend.h"

#include <gtest/gtest.h>

#include <memory>
#include <string>

#define REQUIRE_GPU_OR_SKIP()                                                                      \
  do {                                                                                             \
    std::string why_;                                                                              \
    if (!::faceplan::cuda::DeviceAvailable(&why_))                                                 \
      GTEST_SKIP() << "no usable GPU: " << why_;                                                   \
  } while (0)

namespace faceplan::testing {

inline std::shared_ptr<ComputeBackend> Gpu() {
  std::shared_ptr<ComputeBackend> backend;
  const Status made = cuda::MakeCudaBackend(backend);
  EXPECT_TRUE(made && backend) << made.message;
  return backend;
}

} // namespace faceplan::testing
