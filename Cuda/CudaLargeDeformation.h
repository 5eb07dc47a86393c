// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The large-deformation solve's steps on the GPU (ComputeBackend::makeHyperelasticForces and
// makeFactorOnDevice; PrecomputedLargeDeformation.h runs the rest of each iteration on the CPU):
//
// - the cells' energy and internal force: one thread per cell in double precision, the forces
//   added to the nodes atomically (so their sums' order, and their last bits, vary from call to
//   call), the energy summed per block;
// - a substitution with a single-precision copy of a CHOLMOD supernodal factor: the supernodes
//   grouped by their height in the supernodal elimination tree, one kernel per level and sweep,
//   one thread block per small supernode (a warp solves its diagonal block 32 columns at a time,
//   the block updates the rows below), the forward sweep's updates added to the ancestors
//   atomically. A level's supernodes are independent, so a sweep costs as many launches as the
//   tree is high, not as it has supernodes. The large supernodes at the top of the tree (from 256
//   columns), where a level holds too few to fill the GPU one block each, are cuBLAS products
//   spread over the whole GPU: with their diagonal block's inverse (made once per factor with
//   cuBLAS STRSM on the identity) and their off-diagonal block. The whole substitution is one
//   CUDA graph (FACEPLAN_CUDA_NO_GRAPH=1: separate launches, for measuring);
// - the tangent's product, one thread per stored entry of its upper triangle.
//
// Each object has its own stream and page-locked buffers for the vectors it moves (3 doubles per
// node each way per call).
#include "Backend/ComputeBackend.h"

#include <memory>

namespace faceplan::cuda::detail {

Status MakeCudaHyperelasticForces(const HyperelasticCells& cells,
                                  std::unique_ptr<HyperelasticForces>& forces);
Status MakeCudaFactorOnDevice(const SinglePrecisionFactor& factor, const SparseMatrix& upper,
                              std::unique_ptr<FactorOnDevice>& device);

// The levels of a factor's supernodal tree as the sweeps use them (for tests and benchmarks).
struct SweepShape {
  int supernodes = 0, levels = 0, maxRows = 0; // maxRows: of the small supernodes
  int large = 0; // supernodes done with cuBLAS products (their diagonal block inverted)
  double valueBytes = 0.0;
};
bool ShapeOfFactorOnDevice(const FactorOnDevice& device, SweepShape& shape);

} // namespace faceplan::cuda::detail
