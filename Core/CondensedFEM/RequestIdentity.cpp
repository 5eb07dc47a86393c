// SPDX-License-Identifier: BSD-3-Clause
#include "CondensedFEM/RequestIdentity.h"

#include <cstring>

namespace faceplan {

namespace {

// The sizes the comparisons below were written for (x86-64, libstdc++). A new field changes them:
// extend the comparison, then the number.
static_assert(sizeof(NodeSets) ==
                  5 * sizeof(std::vector<int>) + sizeof(std::vector<Eigen::Vector3d>),
              "SameRequest must compare every NodeSets field");
static_assert(sizeof(Materials) == 3 * sizeof(Eigen::VectorXd) + sizeof(std::vector<unsigned char>),
              "SameRequest must compare every Materials field");
static_assert(sizeof(TetMesh) == sizeof(RowVectors3d) + sizeof(Tets),
              "SameRequest must compare every TetMesh field");
static_assert(sizeof(PrecomputeOptions) == 128,
              "SameOptions must compare every PrecomputeOptions field");

// Byte for byte (the filter compares its whole mesh on every edit, and memcmp is several times
// cheaper than Eigen's coefficient-wise ==). Stricter than ==, never looser: -0.0 and
// 0.0 differ here, which only costs a precompute; equal bytes are equal inputs.
template <class Matrix> bool SameMatrix(const Matrix& a, const Matrix& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() &&
         (a.size() == 0 ||
          std::memcmp(a.data(), b.data(),
                      sizeof(typename Matrix::Scalar) * static_cast<size_t>(a.size())) == 0);
}

} // namespace

bool SameOptions(const PrecomputeOptions& a, const PrecomputeOptions& b) {
  // A mid-edge projection is a function: two of them cannot be compared, so a request that sets one
  // never matches (it is always precomputed afresh).
  if (a.midEdgeProjection || b.midEdgeProjection)
    return false;
  return a.method == b.method && a.denseResponseBudgetBytes == b.denseResponseBudgetBytes &&
         a.memoryBudgetBytes == b.memoryBudgetBytes && a.backend == b.backend &&
         a.responseBlockColumns == b.responseBlockColumns && a.elementOrder == b.elementOrder &&
         a.quadraticMeanDilatation == b.quadraticMeanDilatation &&
         a.sliverQualityThreshold == b.sliverQualityThreshold &&
         a.residualTolerance == b.residualTolerance &&
         a.maxRefinementSteps == b.maxRefinementSteps &&
         a.responseTolerance == b.responseTolerance && a.strainWarningLimit == b.strainWarningLimit;
}

bool SameInputs(const PrecomputeRequest& a, const PrecomputeRequest& b) {
  return SameMatrix(a.mesh.points, b.mesh.points) && SameMatrix(a.mesh.tets, b.mesh.tets) &&
         SameMatrix(a.materials.youngsModulus, b.materials.youngsModulus) &&
         SameMatrix(a.materials.poissonRatio, b.materials.poissonRatio) &&
         SameMatrix(a.materials.density, b.materials.density) &&
         a.materials.smallStrain == b.materials.smallStrain &&
         a.sets.constrained == b.sets.constrained && a.sets.movable == b.sets.movable &&
         a.sets.kept == b.sets.kept && a.sets.movableSegment == b.sets.movableSegment &&
         a.sets.sliding == b.sets.sliding && a.sets.slidingNormal == b.sets.slidingNormal;
}

bool SameRequest(const PrecomputeRequest& a, const PrecomputeRequest& b) {
  return SameInputs(a, b) && SameOptions(a.options, b.options);
}

} // namespace faceplan
