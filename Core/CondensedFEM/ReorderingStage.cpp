// SPDX-License-Identifier: BSD-3-Clause
// The Reordering stage: fill-reducing ordering of K_FF and its symbolic analysis, either on its own
// thread from the node graph while the assembly and separation go on (StartEarlyOrdering), or
// after them from the separated blocks.
#include "CondensedFEM/PrecomputeStages.h"

#include "SparseSolver/MetisRandom.h"

#include "Common/ExceptionBoundary.h"
#include "CondensedFEM/MethodChoice.h"
#include "SparseSolver/FillReducingOrdering.h"

#include <functional>

namespace faceplan {

namespace {

// What ordering K_FF needs, from either source: its upper structure, the marks of the free nodes
// coupled to the ROI (K_FR's rows), and a way to order with given trailing marks.
struct OrderingInputs {
  const SparseMatrix& kffPattern;
  std::vector<char> coupled;
  std::function<Status(const std::vector<char>& trailing, FillReducingOrdering&)> order;
  double roiColumns = 0.0; // the response's columns: ROI DOFs, or segment parameters
  bool fewColumns = false; // rigid segments
  bool hasRoi = false;
  // The backend factors on the GPU (coarse supernodes there: SupernodeRelaxation).
  bool gpuFactorization = false;
};

// METIS on the node graph with the ROI-coupled nodes last (FillReducingOrdering.h). That halves a
// response solve but makes those nodes a dense block of the factor, which does not pay when the
// ROI is large; then the ordering without it is analysed too and the one with the lower estimated
// precompute is kept: factorization flops plus one solve per ROI DOF (forward + backward, or
// backward + the trailing block). CHOLMOD's own choice if neither ordering can be made.
Status OrderAndAnalyse(const OrderingInputs& in, CholmodFactor& factor, std::string& ordering) {
  factor.setSupernodeRelaxation(in.gpuFactorization ? SupernodeRelaxation::Coarse
                                                    : SupernodeRelaxation::Cholmod);
  const double roiColumns = in.roiColumns;
  auto estimatedCost = [roiColumns](double nonzeros, double flops, int trailing) {
    return flops + roiColumns * FactorSolveFlops(nonzeros, trailing);
  };
  std::vector<FillReducingOrdering> candidates;
  bool settled = false;
  FillReducingOrdering trailingLast;
  // Rigid segments need a dozen response columns per segment: too few for the trailing block's
  // cheaper substitutions to pay for its fill, so only the plain ordering is made.
  if (in.hasRoi && !in.fewColumns && in.order(in.coupled, trailingLast).ok) {
    candidates.push_back(std::move(trailingLast));
    Status as = factor.analyze(in.kffPattern, candidates, estimatedCost);
    if (!as)
      return as;
    // Settled without the other ordering when even losing the whole trailing block (t^3/3
    // flops, t^2/2 entries) could not make full solves cheaper: t^3/3 + 3 r t^2 <= 2 r nnz(L).
    const double block = factor.trailingDofs(), r = roiColumns;
    settled = block > 0 && block * block * block / 3.0 + 3.0 * r * block * block <=
                               2.0 * r * factor.factorNonzeros();
  }
  if (!settled) {
    // Both candidates analysed together (the trailing one a second time: CholmodFactor keeps
    // one analysis; this only happens for ROIs large enough to doubt the trailing block).
    FillReducingOrdering plain;
    if (in.order({}, plain).ok)
      candidates.push_back(std::move(plain));
    Status as = factor.analyze(in.kffPattern, candidates, estimatedCost);
    if (!as)
      return as;
  }
  ordering = "CHOLMOD default";
  if (!candidates.empty()) {
    const FillReducingOrdering& used = candidates.front();
    ordering = used.method;
    if (used.leaves > 1)
      ordering += " (dissection's top split into " + std::to_string(used.leaves) +
                  " parts on threads" +
                  (MetisRandomIsPerThread() ? ")" : ", METIS calls serialised)");
    if (factor.trailingDofs() > 0)
      ordering += ", ROI-coupled DOFs last";
  }
  return Status::Ok();
}

// The response's column count as SeparateBlocks will make it (segmentCoupling or K_FR).
double ResponseColumns(const PrecomputeState& state, bool& segmentColumns) {
  const CondensedSystem& sys = *state.sys;
  const SolveMethod requested = state.request.options.method;
  segmentColumns = sys.segments > 0 &&
                   (requested == SolveMethod::Auto || requested == SolveMethod::RigidSegments) &&
                   sys.segmentToRoi.cols() > 0;
  return double(segmentColumns ? sys.segmentToRoi.cols() : sys.layout.roiDofs());
}

void Finish(PrecomputeState& state, const std::string& ordering, double ms) {
  SystemInfo& info = state.sys->info;
  info.ordering = ordering;
  info.factorNonzeros = state.sys->factor.factorNonzeros();
  state.time(Stage::Reordering).ms = ms;
  state.report(0.25, "reordering");
}

// Whether the backend asked for will factor on the GPU (known before the assembly picks it).
bool GpuFactorization(const PrecomputeState& state) {
  const auto& backend = state.request.options.backend;
  return backend && backend->providesFactorAndResponse();
}

} // namespace

bool StartEarlyOrdering(PrecomputeState& state, std::shared_ptr<const NodeNeighbours> lower) {
  const CondensedSystem& sys = *state.sys;
  // Sliding nodes turn and pin DOFs, and nodal pressure widens the pattern, after the cells'
  // pattern: their K_FF is only known after the separation.
  if (state.nodalPressure || !sys.slidingFrame.empty() || sys.layout.freeNodes() == 0)
    return false;
  bool segmentColumns = false;
  const double roiColumns = ResponseColumns(state, segmentColumns);
  const int freeNodes = sys.layout.freeNodes();
  const bool hasRoi = sys.layout.roiDofs() > 0;
  const bool gpuFactorization = GpuFactorization(state);
  std::shared_ptr<CondensedSystem> system = state.sys;
  const std::atomic<bool>* cancel = state.cancel;
  state.earlyOrdering = std::async(std::launch::async, [=]() {
    EarlyOrdering out;
    StageClock clock;
    out.status = ReturnStatusOnException("the reordering", [&]() -> Status {
      if (Status built = UpperPatternOfNodes(*lower, freeNodes, false, out.kffPattern); !built)
        return built;
      OrderingInputs in{out.kffPattern,
                        hasRoi ? NodesCoupledToLaterNodes(*lower, freeNodes) : std::vector<char>{},
                        [&](const std::vector<char>& trailing, FillReducingOrdering& o) {
                          return OrderNodeGraphWithTrailing(*lower, freeNodes, 3, trailing, o);
                        },
                        roiColumns,
                        segmentColumns,
                        hasRoi,
                        gpuFactorization};
      out.coupled = in.coupled;
      if (cancel && cancel->load())
        return Status::Error("cancelled");
      return OrderAndAnalyse(in, system->factor, out.ordering);
    });
    out.ms = clock.elapsedMs();
    return out;
  });
  return true;
}

Status ReorderFreeDofs(PrecomputeState& state) {
  CondensedSystem& sys = *state.sys;
  if (state.earlyOrdering.valid()) {
    EarlyOrdering early = state.earlyOrdering.get();
    // The row holds the wait for it, so that the rows still add up to the precompute's time; its
    // own time is in SystemInfo::orderingThreadMs.
    const double waitMs = state.clock.lapMs();
    sys.info.orderingThreadMs = early.ms;
    if (!early.status)
      return early.status;
    // Its inputs came from the node graph: they must be K_FF's structure and K_FR's rows exactly
    // (else the trailing block would not hold every right-hand side); otherwise order again.
    const bool samePattern =
        early.kffPattern.rows() == sys.kff.rows() &&
        early.kffPattern.nonZeros() == sys.kff.nonZeros() &&
        std::equal(sys.kff.outerIndexPtr(), sys.kff.outerIndexPtr() + sys.kff.cols() + 1,
                   early.kffPattern.outerIndexPtr()) &&
        std::equal(sys.kff.innerIndexPtr(), sys.kff.innerIndexPtr() + sys.kff.nonZeros(),
                   early.kffPattern.innerIndexPtr());
    bool segmentColumns = false;
    const double roiColumns = ResponseColumns(state, segmentColumns);
    const bool sameColumns =
        roiColumns == double(segmentColumns ? state.segmentCoupling.cols() : sys.kfr.cols());
    if (samePattern && sameColumns &&
        (sys.kfr.cols() == 0 ||
         early.coupled == NodesCoupledTo(sys.kfr, sys.layout.freeNodes(), 3))) {
      sys.info.orderedBesideAssembly = true;
      Finish(state, early.ordering, waitMs);
      return state.cancelled() ? Status::Error("cancelled") : Status::Ok();
    }
  }
  if (sys.kff.rows() == 0)
    return Status::Ok();
  const bool segments = state.segmentCoupling.cols() > 0;
  OrderingInputs in{sys.kff,
                    sys.kfr.cols() > 0 ? NodesCoupledTo(sys.kfr, sys.layout.freeNodes(), 3)
                                       : std::vector<char>{},
                    [&](const std::vector<char>& trailing, FillReducingOrdering& o) {
                      return OrderNodesWithTrailing(sys.kff, 3, trailing, o);
                    },
                    double(segments ? state.segmentCoupling.cols() : sys.kfr.cols()),
                    segments,
                    sys.kfr.cols() > 0,
                    GpuFactorization(state)};
  std::string ordering;
  if (Status s = OrderAndAnalyse(in, sys.factor, ordering); !s)
    return s; // (not into the state's status: that would drop its warnings)
  const double ms = state.clock.lapMs();
  sys.info.orderingThreadMs = 0.0;
  Finish(state, ordering, ms);
  return state.cancelled() ? Status::Error("cancelled") : Status::Ok();
}

} // namespace faceplan
