// The Reordering stage: fill-reducing ordering of K_FF and its symbolic analysis.
#include "CondensedFEM/PrecomputeStages.h"

#include "CondensedFEM/MethodChoice.h"
#include "SparseSolver/FillReducingOrdering.h"

namespace faceplan {

Status ReorderFreeDofs(PrecomputeState& state) {
  CondensedSystem& sys = *state.sys;
  if (sys.kff.rows() == 0)
    return Status::Ok();
  // METIS on the node graph with the ROI-coupled nodes last (FillReducingOrdering.h). That
  // halves a response solve but makes those nodes a dense block of the factor, which does not
  // pay when the ROI is large; then the ordering without it is analysed too and the one with
  // the lower estimated precompute is kept: factorization flops plus one solve per ROI DOF
  // (forward + backward, or backward + the trailing block). CHOLMOD's own choice if neither
  // ordering can be made.
  const double roiColumns =
      double(state.segmentCoupling.cols() > 0 ? state.segmentCoupling.cols() : sys.kfr.cols());
  auto estimatedCost = [roiColumns](double nonzeros, double flops, int trailing) {
    return flops + roiColumns * FactorSolveFlops(nonzeros, trailing);
  };
  std::vector<FillReducingOrdering> candidates;
  bool settled = false;
  FillReducingOrdering trailingLast;
  // Rigid segments need a dozen response columns per segment: too few for the trailing block's
  // cheaper substitutions to pay for its fill, so only the plain ordering is made.
  const bool fewColumns = state.segmentCoupling.cols() > 0;
  if (sys.kfr.cols() > 0 && !fewColumns &&
      OrderNodesWithTrailing(sys.kff, 3, NodesCoupledTo(sys.kfr, sys.layout.freeNodes(), 3),
                             trailingLast)
          .ok) {
    candidates.push_back(std::move(trailingLast));
    Status as = sys.factor.analyze(sys.kff, candidates, estimatedCost);
    if (!as)
      return as;
    // Settled without the other ordering when even losing the whole trailing block (t^3/3
    // flops, t^2/2 entries) could not make full solves cheaper: t^3/3 + 3 r t^2 <= 2 r nnz(L).
    const double block = sys.factor.trailingDofs(), r = roiColumns;
    settled = block > 0 && block * block * block / 3.0 + 3.0 * r * block * block <=
                               2.0 * r * sys.factor.factorNonzeros();
  }
  if (!settled) {
    // Both candidates analysed together (the trailing one a second time: CholmodFactor keeps
    // one analysis; this only happens for ROIs large enough to doubt the trailing block).
    FillReducingOrdering plain;
    if (OrderNodesWithTrailing(sys.kff, 3, {}, plain).ok)
      candidates.push_back(std::move(plain));
    Status as = sys.factor.analyze(sys.kff, candidates, estimatedCost);
    if (!as)
      return as; // (not into the state's status: that would drop its warnings)
  }
  SystemInfo& info = sys.info;
  info.ordering = candidates.empty()
                      ? "CHOLMOD default"
                      : std::string(candidates.front().method) +
                            (sys.factor.trailingDofs() > 0 ? ", ROI-coupled DOFs last" : "");
  state.time(Stage::Reordering).ms = state.clock.lapMs();
  info.factorNonzeros = sys.factor.factorNonzeros();
  state.report(0.25, "reordering");
  return state.cancelled() ? Status::Error("cancelled") : Status::Ok();
}

} // namespace faceplan
