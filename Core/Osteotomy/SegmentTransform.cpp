// SPDX-License-Identifier: BSD-3-Clause
#include "Osteotomy/SegmentTransform.h"

#include <Eigen/Geometry>

#include <cmath>
#include <limits>

namespace faceplan {

Status RigidMotion(const SegmentMove& move, AffineMap& motion) {
  if (!move.translation.allFinite())
    return Status::Error("the translation is not finite");
  if (!move.rotationDegrees.allFinite())
    return Status::Error("a rotation angle is not finite");
  if (!move.pivot.allFinite())
    return Status::Error("the pivot is not finite");
  const Eigen::Vector3d a = move.rotationDegrees * (M_PI / 180.0);
  // Applied about X first: the rightmost factor acts first.
  const Eigen::Matrix3d r = (Eigen::AngleAxisd(a.z(), Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(a.y(), Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(a.x(), Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  motion.leftCols<3>() = r;
  motion.col(3) = move.pivot + move.translation - r * move.pivot;
  if (!IsFinite(motion))
    return Status::Error("the segment's transform is not finite");
  return Status::Ok();
}

AffineMap Compose(const AffineMap& outer, const AffineMap& inner) {
  AffineMap out;
  out.leftCols<3>() = outer.leftCols<3>() * inner.leftCols<3>();
  out.col(3) = outer.leftCols<3>() * inner.col(3) + outer.col(3);
  return out;
}

Eigen::Vector3d Apply(const AffineMap& map, const Eigen::Vector3d& x) {
  return map.leftCols<3>() * x + map.col(3);
}

AffineMap NotRigid() {
  return AffineMap::Constant(std::numeric_limits<double>::quiet_NaN());
}

bool IsFinite(const AffineMap& map) {
  return map.allFinite();
}

std::vector<double> PackSegmentTransforms(const std::vector<AffineMap>& maps) {
  std::vector<double> packed;
  packed.reserve(12 * maps.size());
  for (const AffineMap& m : maps)
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c)
        packed.push_back(m(r, c));
  return packed;
}

std::vector<AffineMap> UnpackSegmentTransforms(const std::vector<double>& packed, int count) {
  std::vector<AffineMap> maps(static_cast<std::size_t>(std::max(count, 0)), NotRigid());
  for (int s = 0; s < count; ++s) {
    if (12 * static_cast<std::size_t>(s + 1) > packed.size())
      break;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c)
        maps[s](r, c) = packed[12 * s + 4 * r + c];
  }
  return maps;
}

} // namespace faceplan
