// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// How the precompute picks an exact solve method from the problem's sizes.
#include "CondensedFEM/CondensedFEM.h"

#include <string>

namespace faceplan {

// Flops of one solve with the factor for a right-hand side on the ROI-coupled DOFs: a backward
// substitution plus the trailing block's dense forward one when those DOFs were ordered last
// (trailingDofs > 0), else both full substitutions.
double FactorSolveFlops(double factorNonzeros, double trailingDofs);

// The requested method, or for Auto: RigidSegments when there are segments (`segmentColumns` > 0,
// the columns of their response) and it fits the memory budget, else the one with the cheaper edit
// within the budget; `reason` says why in words.
SolveMethod ChooseMethod(const PrecomputeOptions& options, double keptDofs, double roiDofs,
                         double segmentColumns, double factorNonzeros, double trailingDofs,
                         std::string& reason);

} // namespace faceplan
