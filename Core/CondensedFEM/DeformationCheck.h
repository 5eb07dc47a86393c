// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The solve's large-strain and inversion check, and what makes it cheap on the RigidSegments path.
//
// Without loads, a RigidSegments edit's displacements on the checkable cells are linear in the
// segment parameters, so each cell's displacement gradient is G_e = sum_j q_j G_e^(j) over the
// parameter directions j and ||G_e||_F <= gain_e ||q||, gain_e = sqrt(sum_j ||G_e^(j)||_F^2)
// (Cauchy-Schwarz). The parameters are rescaled per segment, q = [L A, b + A c] for the motion
// u(x) = A x + b with c the segment's centroid and L its RMS radius, so that a translation and a
// rotation about the centroid of similar effect have similar size; without that the bound of a pure
// translation would carry the rotation columns' lever arm. Cells sorted by decreasing gain let the
// check stop as soon as no remaining cell can exceed the largest strain found or invert
// (a gradient of Frobenius norm < 1 cannot invert a cell): the result is exact, and an edit
// evaluates only the cells near the largest strain instead of every checkable cell.
#include "CondensedFEM/CondensedSystem.h"
#include "CondensedFEM/RigidSegments.h"
#include "Mesh/MeshValidation.h"

namespace faceplan {

// The displacement of a mesh node from the ROI DOF values and the free DOF values (which may hold
// only the kept-free block): zero for nodes without DOFs, the ROI value for ROI nodes, and a
// sliding node's normal-frame values turned back into x, y, z.
Eigen::RowVector3d NodeDisplacement(const CondensedSystem& sys, int node,
                                    const Eigen::VectorXd& roi, const Eigen::VectorXd& freeValues);

// Sorts the checkable cells by their gain (above) for a RigidSegments system with few parameters;
// leaves the system unchanged (every edit checks every checkable cell) otherwise.
void BuildStrainBounds(CondensedSystem& sys);

// ||q|| of the rescaled segment parameters (see above) for the parameters p of SegmentParameters.
double ScaledParameterNorm(const CondensedSystem& sys, const Eigen::VectorXd& p);

// The check over sys.boundedCells for a load-free RigidSegments edit with parameters p: the kept
// rows from the solve, the segment nodes' motion from their transforms (the given displacements
// agree with it to CheckSegmentDisplacements' tolerance), segment-0 nodes as given. Equal to
// CheckDeformation over sys.checkableCells; appends the same warnings.
DeformationReport CheckBoundedCells(const CondensedSystem& sys, const Eigen::VectorXd& p,
                                    const std::vector<SegmentTransform>& transforms,
                                    const RowVectors3d& movableDisplacement,
                                    const RowVectors3d& keptDisplacement,
                                    std::vector<std::string>& warnings);

} // namespace faceplan
