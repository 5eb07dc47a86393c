// SPDX-License-Identifier: BSD-3-Clause
#include "TissueModelFromCT/BoundaryDistance.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace faceplan {

int InterpolatedLabel(const LabelImage& image, const Eigen::Vector3d& world) {
  const ImageGrid& g = image.grid;
  const Eigen::Vector3d p = g.toScaled(world);
  double l[3];
  for (int a = 0; a < 3; ++a) {
    l[a] = p[a] / g.spacing[a];
    if (!(l[a] >= 0.0) || l[a] >= double(g.dims[a] - 1))
      return kAir;
  }
  const int i = int(l[0]), j = int(l[1]), k = int(l[2]);
  const double fx = l[0] - i, fy = l[1] - j, fz = l[2] - k;
  // Corners in Mesh_3's order (x fastest, then y, then z); the first label to reach the largest
  // weight wins, as there.
  std::array<int, 8> label;
  std::array<double, 8> weight;
  for (int c = 0; c < 8; ++c) {
    const int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
    label[c] = image.labels[g.index(i + dx, j + dy, k + dz)];
    weight[c] = (dx ? fx : 1 - fx) * (dy ? fy : 1 - fy) * (dz ? fz : 1 - fz);
  }
  int best = label[0];
  double bestWeight = -1.0;
  for (int c = 0; c < 8; ++c) {
    bool seen = false;
    for (int b = 0; b < c; ++b)
      seen = seen || label[b] == label[c];
    if (seen)
      continue;
    double w = 0.0;
    for (int b = c; b < 8; ++b)
      if (label[b] == label[c])
        w += weight[b];
    if (w > bestWeight) {
      bestWeight = w;
      best = label[c];
    }
  }
  return best;
}

namespace {

// Distance along `dir` from q to the first label change, or a negative value when there is none
// within `radius`.
double DistanceAlong(const LabelImage& image, const Eigen::Vector3d& q, const Eigen::Vector3d& dir,
                     int start, double radius, double step) {
  double previous = 0.0;
  for (double t = step; t <= radius + 1e-12; t += step) {
    if (InterpolatedLabel(image, q + t * dir) != start) {
      double lo = previous, hi = t;
      for (int it = 0; it < 30; ++it) {
        const double mid = 0.5 * (lo + hi);
        (InterpolatedLabel(image, q + mid * dir) != start ? hi : lo) = mid;
      }
      return 0.5 * (lo + hi);
    }
    previous = t;
  }
  return -1.0;
}

} // namespace

// Directions spread evenly over the sphere (a Fibonacci lattice).
std::vector<Eigen::Vector3d> SphereDirections(int count) {
  std::vector<Eigen::Vector3d> out;
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < count; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / count, r = std::sqrt(1.0 - z * z);
    out.emplace_back(r * std::cos(golden * i), r * std::sin(golden * i), z);
  }
  return out;
}

BoundaryDistanceResult MeasureBoundaryDistance(const LabelImage& image,
                                               const Eigen::MatrixXd& points, const Facets& facets,
                                               double radius, double refineAbove) {
  BoundaryDistanceResult r;
  const auto& s = image.grid.spacing;
  const double step = std::min({s[0], s[1], s[2], radius}) / 8.0;
  std::vector<Eigen::Vector3d> directions;
  for (int dx = -1; dx <= 1; ++dx)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dz = -1; dz <= 1; ++dz)
        if (dx || dy || dz)
          directions.push_back(image.grid.direction * Eigen::Vector3d(dx, dy, dz).normalized());
  const std::vector<Eigen::Vector3d> fine = SphereDirections(kFineDirections);
  // Barycentric lattice of step 1/4 without the corners (which Mesh_3 puts on the interface):
  // three points on each edge, three inside.
  std::vector<Eigen::Vector3d> weights;
  for (int i = 0; i <= 4; ++i)
    for (int j = 0; i + j <= 4; ++j)
      if (i < 4 && j < 4 && i + j > 0)
        weights.emplace_back(i / 4.0, j / 4.0, (4 - i - j) / 4.0);
  double sum = 0.0;
  for (Eigen::Index f = 0; f < facets.rows(); ++f) {
    const Eigen::Vector3d a = points.row(facets(f, 0)).transpose(),
                          b = points.row(facets(f, 1)).transpose(),
                          c = points.row(facets(f, 2)).transpose();
    Eigen::Vector3d n = (b - a).cross(c - a);
    if (n.norm() == 0.0)
      continue;
    n.normalize();
    for (const Eigen::Vector3d& w : weights) {
      const Eigen::Vector3d q = w[0] * a + w[1] * b + w[2] * c;
      const int start = InterpolatedLabel(image, q);
      // The normal first; then the 26 grid directions, each searched only up to the best so far.
      double d = -1.0;
      auto tryDirection = [&](const Eigen::Vector3d& dir) {
        const double limit = d < 0 ? radius : d;
        const double t = DistanceAlong(image, q, dir, start, limit, step);
        if (t >= 0 && (d < 0 || t < d))
          d = t;
      };
      tryDirection(n);
      tryDirection(-n);
      for (const Eigen::Vector3d& dir : directions)
        tryDirection(dir);
      if (d < 0 || d > refineAbove)
        for (const Eigen::Vector3d& dir : fine)
          tryDirection(dir);
      if (d < 0) {
        d = radius;
        ++r.notFound;
      }
      r.largest = std::max(r.largest, d);
      sum += d;
      ++r.samples;
    }
  }
  r.mean = r.samples ? sum / double(r.samples) : 0.0;
  return r;
}

} // namespace faceplan
