// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A CPU backend whose per-edit response operator stores and applies the response in single
// precision (like a float GPU path). Used to test the precision fallback; assembly is in double.
#include "Backend/ComputeBackend.h"

#include <memory>

namespace faceplan {

std::shared_ptr<ComputeBackend> MakeFloatCpuBackend();

} // namespace faceplan
