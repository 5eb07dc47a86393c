// SPDX-License-Identifier: BSD-3-Clause
#include "CondensedFEM/Verify.h"

#include "Common/RelativeDifference.h"

#include <algorithm>

namespace faceplan {

namespace {

// Relative to the largest reference value over both blocks, so the interior does not get its own,
// possibly tiny, scale.
double RelativeError(const SolveResult& result, const SolveResult& reference, bool withInterior) {
  auto size = [](const RowVectors3d& d) { return static_cast<std::size_t>(d.size()); };
  double scale = MaxAbs(reference.keptDisplacement.data(), size(reference.keptDisplacement));
  if (withInterior)
    scale =
        std::max(scale, MaxAbs(reference.allDisplacement.data(), size(reference.allDisplacement)));
  auto difference = [&](const RowVectors3d& a, const RowVectors3d& b) {
    if (a.size() != b.size())
      return std::numeric_limits<double>::infinity();
    return MaxAbsDifference(a.data(), b.data(), size(a));
  };
  double diff = difference(result.keptDisplacement, reference.keptDisplacement);
  if (withInterior)
    diff = std::max(diff, difference(result.allDisplacement, reference.allDisplacement));
  return scale > 0.0 ? diff / scale : diff;
}

} // namespace

Status VerifyAgainstReference(const PrecomputeRequest& request, const SolveInput& input,
                              const SolveResult& result, double& maxRelativeError) {
  SolveResult reference;
  Status status;
  if (request.options.elementOrder != ElementOrder::Linear &&
      result.method != SolveMethod::FullReference) {
    PrecomputeRequest fresh = request;
    fresh.options.method = SolveMethod::CachedFactor;
    std::shared_ptr<const CondensedSystem> system;
    status = Precompute(fresh, system);
    if (status)
      status = Solve(*system, input, reference);
  } else {
    status = SolveFullReference(request, input, reference);
  }
  if (!status)
    return Status::Error("verification solve failed: " + status.message);
  maxRelativeError = RelativeError(result, reference, input.recoverInterior);
  return Status::Ok();
}

} // namespace faceplan
