// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Input checks shared by every entry point, each failing with a message that names the problem.
#include "Common/Status.h"
#include "Mesh/TetMesh.h"

#include <array>
#include <string>
#include <vector>

namespace faceplan {

// Coordinates finite, node ids in range, volumes positive (ids of the offenders listed),
// materials in range (E > 0, -1 < nu < 0.5).
Status ValidateMeshAndMaterials(const TetMesh& mesh, const Materials& materials);

// Connected components of the tetrahedra (sharing a node connects two cells).
// componentOfNode[i] is -1 for nodes used by no tetrahedron.
int ConnectedComponents(const TetMesh& mesh, std::vector<int>& componentOfNode);

// Every component must hold at least one constrained node, or the stiffness matrix is singular.
Status CheckEveryComponentConstrained(const TetMesh& mesh, const std::vector<int>& constrained);

// Stricter than CheckEveryComponentConstrained: pieces of tetrahedra connected through shared
// faces must each be held by at least three non-collinear nodes that are constrained or shared with
// an already held piece; a piece hanging on one node or one edge (free to rotate) fails with its
// cell count and bounds, instead of a singular stiffness matrix.
Status CheckRigidModesHeld(const TetMesh& mesh, const std::vector<int>& constrained);

// Two cells that share a triangle (sorted node ids).
struct SharedFace {
  std::array<int, 3> face;
  int a = -1, b = -1;
};
// Every triangle shared by two cells (one sort over the cells' faces; both checks below use it).
std::vector<SharedFace> SharedFaces(const TetMesh& mesh);
Status CheckRigidModesHeld(const TetMesh& mesh, const std::vector<int>& constrained,
                           const std::vector<SharedFace>& shared);

// A valid mesh has the two cells of a shared face on opposite sides of it. Cells on the same side
// overlap (the mesh folds over itself) although each has a positive volume: the mesh then does not
// partition the volume. Returns a warning naming the count and cells (empty when none).
struct FoldReport {
  long long foldedFaces = 0;
  std::vector<long long> cells; // the first few cells involved
};
std::string CheckFoldedFaces(const TetMesh& mesh, const std::vector<SharedFace>& shared,
                             FoldReport* report = nullptr);

// Mean-ratio quality of a tetrahedron, 12 (3 |V|)^(2/3) / sum of squared edge lengths: 1 for a
// regular tetrahedron, tending to 0 for slivers, needles and caps (scale invariant).
double TetMeanRatio(const Eigen::Matrix<double, 4, 3>& corners);

struct QualityReport {
  long long belowThreshold = 0;    // cells with quality < threshold
  std::vector<long long> worstIds; // the first few of them, worst first
  double worstQuality = 1.0;
  long long worstCell = -1;
};

// Cells whose mean ratio is below `threshold` (slivers). Returns a warning text (empty when none).
std::string CheckElementQuality(const TetMesh& mesh, double threshold,
                                QualityReport* report = nullptr);

struct DeformationReport {
  double largestStrain = 0.0; // largest |principal value| of the small strain, over cells
  long long largestStrainCell = -1;
  long long cellsChecked = 0;
  std::vector<long long> invertedCells; // det(I + grad u) <= 0
};

// Adds one cell's displacement gradient (d u_i / d x_j) to a report: its largest |principal
// strain| and whether the deformed cell is inverted (det(I + grad) <= 0). A cell that can change
// neither the largest strain nor the inverted list is only counted (||grad||_F bounds every
// principal strain, and ||grad||_F < 1 keeps det(I + grad) > 0).
void AddCellDeformation(DeformationReport& report, long long cell, const Eigen::Matrix3d& gradient);

// The warnings CheckDeformation appends for a report (strain over `strainLimit`, inverted cells).
void AppendDeformationWarnings(const DeformationReport& report, double strainLimit,
                               std::vector<std::string>& warnings);

// Checks a displacement field (n x 3, mesh numbering) on every cell, or only on `cells` when given
// (cells whose corners all have known values). Appends warnings when the largest strain exceeds
// `strainLimit` (linear FEM is outside its range) and when cells invert in the deformed result.
DeformationReport
CheckDeformation(const TetMesh& mesh,
                 const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>& displacement,
                 std::vector<std::string>& warnings, double strainLimit = 0.1,
                 const std::vector<int>* cells = nullptr);

} // namespace faceplan
