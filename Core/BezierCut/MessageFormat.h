// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Numbers, points and surface parameters as they appear in BezierCut's error messages.
#include <Eigen/Core>

#include <cstdio>
#include <string>

namespace faceplan {

inline std::string FormatNumber(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return buf;
}

inline std::string FormatPoint(const Eigen::Vector3d& p) {
  return "(" + FormatNumber(p.x()) + ", " + FormatNumber(p.y()) + ", " + FormatNumber(p.z()) + ")";
}

inline std::string FormatParameters(double u, double v) {
  return "(u, v) = (" + FormatNumber(u) + ", " + FormatNumber(v) + ")";
}

} // namespace faceplan
