// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The operative surface of BezierCut (no VTK): the translational surface S(u,v) = U(u) + V(v) - P0
// over two composite cubic Bezier curves U (3k+1 control points) and V (3m+1 control points)
// sharing their first control point P0; u and v run over [0,1] across all segments of each curve
// (segment s of k covers u in [s/k, (s+1)/k]). Its normal is n = dS/du x dS/dv, negated by
// flipNormal.
//
// Projection of a point x: (u*,v*) minimises |S(u,v) - x| over [0,1]^2 (grid initialisation,
// then projected Newton). x "projects inside the patch" when S(u*,v*) is an orthogonal foot point,
// i.e. x - S(u*,v*) has no tangential component (up to 1e-6 of the surface size plus 1e-4 of the
// distance); its signed distance is d = (x - S(u*,v*)) . n^(u*,v*).
#include "Common/Status.h"
#include "Mesh/SurfaceMesh.h"

#include <Eigen/Core>

#include <algorithm>
#include <vector>

namespace faceplan {

// Clamps a surface parameter to the patch [0,1].
inline double Clamp01(double x) {
  return std::min(1.0, std::max(0.0, x));
}

struct SurfaceProjection {
  double u = 0, v = 0;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  // S(u,v)
  Eigen::Vector3d normal = Eigen::Vector3d::Zero(); // unit normal (flip applied)
  double signedDistance = 0;                        // (x - S(u,v)) . normal
  bool inside = false;                              // orthogonal foot point within [0,1]^2
};

class BezierSurface {
public:
  // Validates the control points; the error names the problem:
  //  "invalid control points" (count not 3k+1, non-finite), "first control points not shared",
  //  "degenerate" (coincident consecutive control points, zero-area surface, Su x Sv vanishing),
  //  "self-intersecting" (sampled normals reversing, or sampled patch triangles crossing).
  static Status Create(const std::vector<Eigen::Vector3d>& curveU,
                       const std::vector<Eigen::Vector3d>& curveV, bool flipNormal,
                       BezierSurface& out);

  Eigen::Vector3d evaluate(double u, double v) const;
  // S and its derivatives (Suv = 0 for a translational surface).
  void derivatives(double u, double v, Eigen::Vector3d& S, Eigen::Vector3d& Su, Eigen::Vector3d& Sv,
                   Eigen::Vector3d& Suu, Eigen::Vector3d& Svv) const;
  Eigen::Vector3d unitNormal(double u, double v) const; // flip applied
  // Closest point of the patch to x (grid initialisation + projected Newton).
  SurfaceProjection project(const Eigen::Vector3d& x) const;
  // Triangles over a regular grid with `perSegment` intervals per Bezier segment, oriented along
  // the (flipped) normal. uv receives the parameters of each point, normals its unit normal.
  void tessellate(int perSegment, SurfaceMesh& out, std::vector<Eigen::Vector2d>* uv = nullptr,
                  RowVectors3d* normals = nullptr) const;

  int segmentsU() const { return int(curveU_.size() - 1) / 3; }
  int segmentsV() const { return int(curveV_.size() - 1) / 3; }
  double size() const { return size_; } // diagonal of the control points' bounding box

private:
  struct CurveEval {
    Eigen::Vector3d p, d1, d2;
  };
  static CurveEval evalCurve(const std::vector<Eigen::Vector3d>& P, double u);
  static CurveEval evalSegment(const std::vector<Eigen::Vector3d>& P, int seg, double t);
  SurfaceProjection finish(const Eigen::Vector3d& x, double u, double v) const;
  SurfaceProjection newton(const Eigen::Vector3d& x, double u, double v) const;

  std::vector<Eigen::Vector3d> curveU_, curveV_;
  Eigen::Vector3d p0_ = Eigen::Vector3d::Zero();
  bool flip_ = false;
  double size_ = 0;
  // Initialisation grid: samples of U and V.
  std::vector<double> gridU_, gridV_;
  std::vector<Eigen::Vector3d> gridUPoints_, gridVPoints_;
};

} // namespace faceplan
