// SPDX-License-Identifier: BSD-3-Clause
#include "Osteotomy/OperationPresets.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>

namespace faceplan {

namespace {

// Frame coordinates of one point: anterior, superior, lateral.
struct Frame {
  Eigen::Vector3d a, s, l;
  Eigen::Vector3d operator()(const Eigen::Vector3d& x) const {
    return {a.dot(x), s.dot(x), l.dot(x)};
  }
};

struct Extremes {
  int count = 0;
  double minA = std::numeric_limits<double>::infinity(), maxA = -minA;
  double minS = minA, maxS = -minA;
};

} // namespace

std::string OperationName(Operation operation) {
  switch (operation) {
  case Operation::Custom:
    return "Custom";
  case Operation::LeFortI:
    return "LeFortI";
  case Operation::BSSO:
    return "BSSO";
  case Operation::Genioplasty:
    return "Genioplasty";
  }
  return "";
}

Status NormalizeAxes(AnatomicalAxes& axes) {
  if (!axes.anterior.allFinite() || !axes.superior.allFinite())
    return Status::Error("the anterior or superior direction is not finite");
  if (!(axes.anterior.norm() > 0.0) || !(axes.superior.norm() > 0.0))
    return Status::Error("the anterior or superior direction has zero length");
  axes.anterior.normalize();
  axes.superior.normalize();
  if (std::abs(axes.anterior.dot(axes.superior)) > std::cos(10.0 * M_PI / 180.0))
    return Status::Error("the anterior and superior directions are (nearly) parallel: they "
                         "cannot define a frame");
  axes.superior = (axes.superior - axes.superior.dot(axes.anterior) * axes.anterior).normalized();
  return Status::Ok();
}

Status PlaceOperationCut(Operation operation, const RowVectors3d& points,
                         const AnatomicalAxes& inputAxes, OperationGeometry& geometry) {
  geometry = OperationGeometry();
  if (operation != Operation::LeFortI && operation != Operation::BSSO &&
      operation != Operation::Genioplasty)
    return Status::Error("Operation must be LeFortI (1), BSSO (2) or Genioplasty (3) for a preset");
  AnatomicalAxes axes = inputAxes;
  if (Status s = NormalizeAxes(axes); !s)
    return s;
  if (points.rows() < 4)
    return Status::Error("the bone has too few points for an operation preset");
  if (!points.allFinite())
    return Status::Error("the bone has a NaN or infinite coordinate");
  const Frame frame{axes.anterior, axes.superior, axes.superior.cross(axes.anterior)};
  const Eigen::Index n = points.rows();
  std::vector<Eigen::Vector3d> f(static_cast<std::size_t>(n));
  Extremes all;
  double minL = std::numeric_limits<double>::infinity(), maxL = -minL;
  for (Eigen::Index i = 0; i < n; ++i) {
    f[i] = frame(points.row(i).transpose());
    minL = std::min(minL, f[i].z());
    maxL = std::max(maxL, f[i].z());
    all.minA = std::min(all.minA, f[i].x());
    all.maxA = std::max(all.maxA, f[i].x());
    all.minS = std::min(all.minS, f[i].y());
    all.maxS = std::max(all.maxS, f[i].y());
  }
  const double midL = 0.5 * (minL + maxL), band = 0.05 * (maxL - minL);
  if (!(maxL - minL > 0.0) || !(all.maxA - all.minA > 0.0) || !(all.maxS - all.minS > 0.0))
    return Status::Error("the bone is flat: an operation preset needs a jaw with width, depth and "
                         "height");
  auto midline = [&](auto accept) {
    Extremes e;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (std::abs(f[i].z() - midL) > band || !accept(f[i]))
        continue;
      ++e.count;
      e.minS = std::min(e.minS, f[i].y());
      e.maxS = std::max(e.maxS, f[i].y());
      e.minA = std::min(e.minA, f[i].x());
      e.maxA = std::max(e.maxA, f[i].x());
    }
    return e;
  };
  geometry.operation = operation;
  geometry.axes = axes;
  geometry.frontA = all.maxA;
  geometry.backA = all.minA;
  const double depth = all.maxA - all.minA;
  const std::string noMidline = "the bone has no points on its midline: an operation preset needs "
                                "a whole jaw (both sides), seen along the anterior direction";

  if (operation == Operation::LeFortI) {
    // The front quarter of the midline: the alveolar process below, the anterior nasal spine at
    // its top.
    const double frontQuarter = all.maxA - 0.25 * depth;
    const Extremes front = midline([&](const Eigen::Vector3d& p) { return p.x() >= frontQuarter; });
    if (front.count == 0)
      return Status::Error(noMidline);
    geometry.crestS = front.minS;
    geometry.jawHeight = front.maxS - front.minS;
    if (!(geometry.jawHeight > 0.0))
      return Status::Error("the maxilla's front has no height between its crest and the nasal "
                           "spine");
    geometry.cutS = front.maxS + 0.1 * geometry.jawHeight;
    CutPlane below;
    below.origin = axes.superior * geometry.cutS + axes.anterior * (all.maxA - 0.5 * depth);
    below.normal = -axes.superior;
    geometry.planes = {below};
    return Status::Ok();
  }

  // Mandible.
  // The front half of the midline: the symphysis from the crest to menton.
  const double frontHalf = all.maxA - 0.5 * depth;
  const Extremes front = midline([&](const Eigen::Vector3d& p) { return p.x() >= frontHalf; });
  if (front.count == 0)
    return Status::Error(noMidline);
  geometry.crestS = front.maxS;
  const double mentonS = front.minS;
  geometry.jawHeight = geometry.crestS - mentonS;
  if (!(geometry.jawHeight > 0.0))
    return Status::Error("the mandible's symphysis has no height between its crest and menton");
  const double H = geometry.jawHeight;
  // The ramus's anterior border: the most anterior bone 0.2 H to 0.4 H above the crest.
  double ramusA = -std::numeric_limits<double>::infinity();
  for (const Eigen::Vector3d& p : f)
    if (p.y() >= geometry.crestS + 0.2 * H && p.y() <= geometry.crestS + 0.4 * H)
      ramusA = std::max(ramusA, p.x());
  // A mandible's rami rise behind its body; a maxilla's bone above its front is in front.
  if (!std::isfinite(ramusA) || ramusA > all.maxA - 0.3 * depth)
    return Status::Error("the bone has no ramus above the alveolar crest behind its body: BSSO "
                         "and Genioplasty need a mandible (check Anterior and Superior Direction)");
  geometry.ramusBorderA = ramusA;
  geometry.cutA = ramusA + 0.25 * H; // in front of the ramus: a larger anterior coordinate
  if (operation == Operation::BSSO) {
    CutPlane coronal;
    coronal.origin = axes.anterior * geometry.cutA + axes.superior * (mentonS + 0.5 * H);
    coronal.normal = axes.anterior;
    geometry.planes = {coronal};
    return Status::Ok();
  }
  // Genioplasty.
  const double pogonionA = front.maxA;
  geometry.cutS = mentonS + 0.35 * H;
  const double chinBackA = pogonionA - 0.5 * H;
  CutPlane below, coronal;
  below.origin = axes.superior * geometry.cutS + axes.anterior * pogonionA;
  below.normal = -axes.superior;
  coronal.origin = axes.anterior * chinBackA + axes.superior * geometry.cutS;
  coronal.normal = axes.anterior;
  geometry.planes = {below, coronal};
  geometry.cutA = chinBackA;
  return Status::Ok();
}

void MarkOperationApproach(const OperationGeometry& g, const RowVectors3d& points,
                           const std::vector<std::uint8_t>& segment,
                           std::vector<std::uint8_t>& released,
                           std::vector<std::uint8_t>& sliding) {
  const Eigen::Index n = points.rows();
  released.assign(static_cast<std::size_t>(n), 0);
  sliding.assign(static_cast<std::size_t>(n), 0);
  const double H = g.jawHeight;
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector3d x = points.row(i).transpose();
    const double a = g.axes.anterior.dot(x), s = g.axes.superior.dot(x);
    const bool moving = segment[static_cast<std::size_t>(i)] != 0;
    bool r = false, t = false;
    switch (g.operation) {
    case Operation::LeFortI:
      // Degloved from the vestibular incision (the top of the teeth band) up to the infraorbital
      // foramina, about a third of the crest-to-cut height above the cut, on both sides of it:
      // the nasal base and the piriform rim's tissue are freed from the segment too, while the
      // nasal dorsum above stays on its bones.
      r = s > g.crestS + 0.4 * H && s <= g.cutS + 0.3 * (g.cutS - g.crestS);
      t = s <= g.crestS + 0.4 * H && a >= g.frontA - 0.5 * (g.frontA - g.backA);
      break;
    case Operation::BSSO:
      r = std::abs(a - g.cutA) <= 0.3 * H;
      t = s >= g.crestS - 0.25 * H && a >= g.cutA;
      break;
    case Operation::Genioplasty:
      r = !moving && s <= g.crestS - 0.25 * H && a >= g.cutA - 0.2 * H;
      t = s >= g.crestS - 0.25 * H && a >= g.ramusBorderA + 0.25 * H;
      break;
    case Operation::Custom:
      break;
    }
    released[static_cast<std::size_t>(i)] = r ? 1 : 0;
    sliding[static_cast<std::size_t>(i)] = t ? 1 : 0;
  }
}

} // namespace faceplan
