// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Precompute under the promises every fuzz target checks: its status and system agree, and an
// error has a message. True when the precompute succeeded.
#include "FuzzBytes.h"

#include "CondensedFEM/CondensedFEM.h"

#include <memory>

namespace faceplan::fuzz {

inline bool CheckedPrecompute(const PrecomputeRequest& request,
                              std::shared_ptr<const CondensedSystem>& system) {
  const Status pre = Precompute(request, system);
  if (pre.ok != (system != nullptr))
    Violation("Precompute's status and system disagree");
  if (!pre && pre.message.empty())
    Violation("a Precompute error without a message");
  return pre.ok;
}

} // namespace faceplan::fuzz
