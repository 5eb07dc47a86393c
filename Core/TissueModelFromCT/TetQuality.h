// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Shape quality of a tetrahedral mesh: dihedral angles and mean ratio.
#include "Mesh/TetMesh.h"

namespace faceplan {

// Smallest of the six dihedral angles of a tetrahedron, degrees (70.5 for a regular one).
double TetMinDihedralAngle(const Eigen::Matrix<double, 4, 3>& corners);

struct TetQualitySummary {
  long long cells = 0;
  long long nonPositive = 0; // cells with volume <= 0
  double smallestVolume = 0.0;
  double worstDihedralAngle = 180.0; // degrees
  double smallestMeanRatio = 1.0;
  long long belowDihedralBound = 0; // cells whose smallest dihedral angle is below the bound
};

TetQualitySummary MeasureTetQuality(const TetMesh& mesh, double dihedralBoundDegrees);

} // namespace faceplan
