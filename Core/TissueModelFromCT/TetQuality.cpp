// SPDX-License-Identifier: BSD-3-Clause
#include "TissueModelFromCT/TetQuality.h"

#include "Mesh/MeshValidation.h"
#include "Mesh/TetGeometry.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>

namespace faceplan {

double TetMinDihedralAngle(const Eigen::Matrix<double, 4, 3>& c) {
  // The dihedral angle at edge (a, b) is pi minus the angle between the outward normals of the
  // two faces sharing it; face f is the one opposite corner f.
  Eigen::Vector3d normal[4];
  for (int f = 0; f < 4; ++f) {
    const int a = (f + 1) % 4, b = (f + 2) % 4, d = (f + 3) % 4;
    Eigen::Vector3d nrm =
        (c.row(b) - c.row(a)).transpose().cross((c.row(d) - c.row(a)).transpose());
    if (nrm.dot((c.row(f) - c.row(a)).transpose()) > 0)
      nrm = -nrm; // point away from corner f
    const double len = nrm.norm();
    if (len == 0.0)
      return 0.0;
    normal[f] = nrm / len;
  }
  double smallest = 180.0;
  for (int f = 0; f < 4; ++f)
    for (int g = f + 1; g < 4; ++g) {
      const double cosine = std::clamp(-normal[f].dot(normal[g]), -1.0, 1.0);
      smallest = std::min(smallest, std::acos(cosine) * 180.0 / M_PI);
    }
  return smallest;
}

TetQualitySummary MeasureTetQuality(const TetMesh& mesh, double bound) {
  TetQualitySummary s;
  s.cells = mesh.numTets();
  s.smallestVolume = mesh.numTets() ? std::numeric_limits<double>::infinity() : 0.0;
  TetCorners c;
  for (Eigen::Index e = 0; e < mesh.numTets(); ++e) {
    for (int k = 0; k < 4; ++k)
      c.row(k) = mesh.points.row(mesh.tets(e, k));
    const double volume = TetVolume(c);
    s.smallestVolume = std::min(s.smallestVolume, volume);
    if (!(volume > 0.0))
      ++s.nonPositive;
    const double angle = TetMinDihedralAngle(c);
    s.worstDihedralAngle = std::min(s.worstDihedralAngle, angle);
    if (angle < bound)
      ++s.belowDihedralBound;
    s.smallestMeanRatio = std::min(s.smallestMeanRatio, TetMeanRatio(c));
  }
  return s;
}

} // namespace faceplan
