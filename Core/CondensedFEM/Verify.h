// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Checks a solve against an independent one: the uncondensed reference solve for linear elements,
// or, for quadratic elements (which the reference does not support), a fresh uncached
// cached-factor precompute of the same request. The error measure is the largest displacement
// difference over the reported nodes relative to the largest reference displacement.
#include "CondensedFEM/CondensedFEM.h"

namespace faceplan {

Status VerifyAgainstReference(const PrecomputeRequest& request, const SolveInput& input,
                              const SolveResult& result, double& maxRelativeError);

} // namespace faceplan
