// SPDX-License-Identifier: BSD-3-Clause
#include "Osteotomy/CutPlanes.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <string>

namespace faceplan {

Status NormalizeCutPlanes(std::vector<CutPlane>& planes) {
  if (planes.empty())
    return Status::Error("no cut plane given");
  for (std::size_t i = 0; i < planes.size(); ++i) {
    CutPlane& p = planes[i];
    const std::string name = "cut plane " + std::to_string(i + 1);
    if (!p.origin.allFinite() || !p.normal.allFinite())
      return Status::Error(name + " has a non-finite origin or normal");
    // Scaled by its largest component first: the squared length of a normal near 1e-160 or
    // 1e160 underflows or overflows, which would give a normal that is not of unit length.
    const double largest = p.normal.cwiseAbs().maxCoeff();
    if (!(largest > 0.0))
      return Status::Error(name + " has a zero-length normal");
    p.normal /= largest;
    p.normal.normalize();
  }
  return Status::Ok();
}

bool OnSegmentSide(const std::vector<CutPlane>& planes, bool insideOut, const Eigen::Vector3d& x) {
  bool positive = true;
  for (const CutPlane& p : planes)
    positive = positive && p.normal.dot(x - p.origin) > 0.0;
  return positive != insideOut;
}

Status ClassifyCutSides(const RowVectors3d& points, const std::vector<CutPlane>& planes,
                        bool insideOut, std::vector<std::uint8_t>& onSegmentSide) {
  onSegmentSide.assign(static_cast<std::size_t>(points.rows()), 0);
  Eigen::Index moving = 0;
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    const bool side = OnSegmentSide(planes, insideOut, points.row(i).transpose());
    onSegmentSide[static_cast<std::size_t>(i)] = side ? 1 : 0;
    moving += side ? 1 : 0;
  }
  if (moving == 0)
    return Status::Error("the cut leaves no vertex of the bone on the moving side (move the cut "
                         "plane(s) into the bone or toggle InsideOut)");
  if (moving == points.rows())
    return Status::Error("the cut leaves no vertex of the bone on the fixed side (move the cut "
                         "plane(s) into the bone or toggle InsideOut)");
  return Status::Ok();
}

std::vector<ConvexPiece> ConvexPiecesOfCut(const std::vector<CutPlane>& planes, bool insideOut) {
  std::vector<ConvexPiece> pieces;
  ConvexPiece positive;
  positive.bounds = planes;
  positive.moves = !insideOut;
  pieces.push_back(positive);
  for (std::size_t i = 0; i < planes.size(); ++i) {
    ConvexPiece rest;
    rest.bounds.assign(planes.begin(), planes.begin() + static_cast<std::ptrdiff_t>(i));
    CutPlane flipped = planes[i];
    flipped.normal = -flipped.normal;
    rest.bounds.push_back(flipped);
    rest.moves = insideOut;
    pieces.push_back(rest);
  }
  return pieces;
}

std::vector<Eigen::Vector3d> PlaneBoxSection(const CutPlane& plane,
                                             const std::array<double, 6>& box) {
  std::vector<Eigen::Vector3d> corners;
  for (int k = 0; k < 8; ++k)
    corners.emplace_back(box[(k & 1) ? 1 : 0], box[(k & 2) ? 3 : 2], box[(k & 4) ? 5 : 4]);
  std::vector<Eigen::Vector3d> section;
  // The 12 edges join corners that differ in one bit.
  for (int a = 0; a < 8; ++a)
    for (int bit = 1; bit < 8; bit <<= 1) {
      const int b = a | bit;
      if (b == a)
        continue;
      const double da = plane.normal.dot(corners[a] - plane.origin);
      const double db = plane.normal.dot(corners[b] - plane.origin);
      if ((da < 0.0) == (db < 0.0) && da != 0.0)
        continue;
      if (da == db)
        continue; // the edge lies in the plane: its corners come from other edges
      section.push_back(corners[a] + (da / (da - db)) * (corners[b] - corners[a]));
    }
  if (section.size() < 3)
    return {};
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const auto& p : section)
    centre += p;
  centre /= static_cast<double>(section.size());
  // Two in-plane axes, then order the corners by angle.
  const Eigen::Vector3d n = plane.normal.normalized();
  const Eigen::Vector3d helper =
      std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d u = n.cross(helper).normalized(), v = n.cross(u);
  std::sort(section.begin(), section.end(),
            [&](const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
              return std::atan2((p - centre).dot(v), (p - centre).dot(u)) <
                     std::atan2((q - centre).dot(v), (q - centre).dot(u));
            });
  // Corners found from several edges (the plane through a box corner) appear more than once.
  const double scale = (Eigen::Vector3d(box[1] - box[0], box[3] - box[2], box[5] - box[4])).norm();
  std::vector<Eigen::Vector3d> unique;
  for (const auto& p : section)
    if (unique.empty() || (p - unique.back()).norm() > 1e-12 * scale)
      unique.push_back(p);
  if (unique.size() > 1 && (unique.front() - unique.back()).norm() <= 1e-12 * scale)
    unique.pop_back();
  if (unique.size() < 3)
    return {};
  return unique;
}

} // namespace faceplan
