// SPDX-License-Identifier: BSD-3-Clause
#include "CondensedFEM/MethodChoice.h"

#include <sstream>

namespace faceplan {

namespace {
// Per-edit cost decides between a dense product and a sparse solve (both exact). A sparse
// triangular solve runs at about a third of a dense product's flop rate (scripts/report measures
// both over its scenes), so its flops are weighted by that ratio.
constexpr double kSparseSolveFlopWeight = 3.0;
} // namespace

double FactorSolveFlops(double factorNonzeros, double trailingDofs) {
  return trailingDofs > 0 ? 2.0 * factorNonzeros + trailingDofs * trailingDofs
                          : 4.0 * factorNonzeros;
}

SolveMethod ChooseMethod(const PrecomputeOptions& options, double keptDofs, double roiDofs,
                         double segmentColumns, double factorNonzeros, double trailingDofs,
                         std::string& reason) {
  const double denseBytes = 8.0 * keptDofs * roiDofs;
  const double denseFlops = 2.0 * keptDofs * roiDofs;
  const double factorFlops =
      FactorSolveFlops(factorNonzeros, trailingDofs) * kSparseSolveFlopWeight;
  std::ostringstream why;
  why.precision(3);
  if (options.method == SolveMethod::DenseResponse || options.method == SolveMethod::CachedFactor ||
      options.method == SolveMethod::RigidSegments) {
    why << "requested";
    reason = why.str();
    return options.method;
  }
  if (roiDofs == 0 || keptDofs == 0) {
    reason = "nothing moves or nothing is kept: a cached factor serves loads alone";
    return SolveMethod::CachedFactor;
  }
  const double segmentBytes = 8.0 * keptDofs * segmentColumns;
  if (segmentColumns > 0 && segmentBytes <= options.denseResponseBudgetBytes) {
    why << "rigid segments: the response needs " << segmentColumns
        << " columns (12 per segment plus "
        << "the general ROI DOFs) instead of " << roiDofs;
    reason = why.str();
    return SolveMethod::RigidSegments;
  }
  if (denseBytes > options.denseResponseBudgetBytes) {
    why << "dense response would take " << denseBytes / 1e6 << " MB, over the "
        << options.denseResponseBudgetBytes / 1e6 << " MB budget";
    reason = why.str();
    return SolveMethod::CachedFactor;
  }
  if (denseFlops < factorFlops) {
    why << "an edit costs " << denseFlops / 1e6 << " MFLOP as a dense product against "
        << factorFlops / 1e6 << " dense-equivalent MFLOP as a factor solve";
    reason = why.str();
    return SolveMethod::DenseResponse;
  }
  why << "a factor solve (" << factorFlops / 1e6
      << " dense-equivalent MFLOP) is cheaper than the dense product (" << denseFlops / 1e6
      << " MFLOP)";
  reason = why.str();
  return SolveMethod::CachedFactor;
}

} // namespace faceplan
