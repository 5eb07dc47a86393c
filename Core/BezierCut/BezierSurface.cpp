// SPDX-License-Identifier: BSD-3-Clause
#include "BezierCut/BezierSurface.h"

#include "BezierCut/MeshIntersection.h"
#include "BezierCut/MessageFormat.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>

namespace faceplan {

using Eigen::Vector2d;
using Eigen::Vector3d;

BezierSurface::CurveEval BezierSurface::evalSegment(const std::vector<Vector3d>& P, int seg,
                                                    double t) {
  const Vector3d& p0 = P[3 * seg];
  const Vector3d& p1 = P[3 * seg + 1];
  const Vector3d& p2 = P[3 * seg + 2];
  const Vector3d& p3 = P[3 * seg + 3];
  const double s = 1.0 - t;
  CurveEval e;
  e.p = s * s * s * p0 + 3 * s * s * t * p1 + 3 * s * t * t * p2 + t * t * t * p3;
  e.d1 = 3 * (s * s * (p1 - p0) + 2 * s * t * (p2 - p1) + t * t * (p3 - p2));
  e.d2 = 6 * (s * (p2 - 2 * p1 + p0) + t * (p3 - 2 * p2 + p1));
  return e;
}

BezierSurface::CurveEval BezierSurface::evalCurve(const std::vector<Vector3d>& P, double u) {
  const int k = int(P.size() - 1) / 3;
  u = Clamp01(u);
  int seg = std::min(int(std::floor(u * k)), k - 1);
  const double t = u * k - seg;
  CurveEval e = evalSegment(P, seg, t);
  e.d1 *= k;
  e.d2 *= double(k) * k;
  return e;
}

Vector3d BezierSurface::evaluate(double u, double v) const {
  return evalCurve(curveU_, u).p + evalCurve(curveV_, v).p - p0_;
}

void BezierSurface::derivatives(double u, double v, Vector3d& S, Vector3d& Su, Vector3d& Sv,
                                Vector3d& Suu, Vector3d& Svv) const {
  const CurveEval a = evalCurve(curveU_, u), b = evalCurve(curveV_, v);
  S = a.p + b.p - p0_;
  Su = a.d1;
  Sv = b.d1;
  Suu = a.d2;
  Svv = b.d2;
}

Vector3d BezierSurface::unitNormal(double u, double v) const {
  Vector3d n = evalCurve(curveU_, u).d1.cross(evalCurve(curveV_, v).d1);
  const double len = n.norm();
  if (len > 0)
    n /= len;
  return flip_ ? Vector3d(-n) : n;
}

Status BezierSurface::Create(const std::vector<Vector3d>& curveU,
                             const std::vector<Vector3d>& curveV, bool flipNormal,
                             BezierSurface& out) {
  out = BezierSurface{};
  const std::vector<Vector3d>* curves[2] = {&curveU, &curveV};
  const char* names[2] = {"CurveU", "CurveV"};
  for (int c = 0; c < 2; ++c) {
    const std::size_t n = curves[c]->size();
    if (n < 4 || (n - 1) % 3 != 0)
      return Status::Error("invalid control points: " + std::string(names[c]) + " has " +
                           std::to_string(n) +
                           " points; a composite cubic Bezier curve needs 3k+1 (4, 7, 10, ...): "
                           "add or remove points three at a time, one Bezier segment each");
    for (std::size_t i = 0; i < n; ++i)
      if (!(*curves[c])[i].allFinite())
        return Status::Error("invalid control points: " + std::string(names[c]) + " point " +
                             std::to_string(i) + " is not finite");
  }
  Eigen::Array3d lo = curveU[0].array(), hi = lo;
  for (int c = 0; c < 2; ++c)
    for (const Vector3d& p : *curves[c]) {
      lo = lo.min(p.array());
      hi = hi.max(p.array());
    }
  const double L = (hi - lo).matrix().norm();
  if (!(L > 0))
    return Status::Error("degenerate surface: all control points coincide");
  // Squared coordinates beyond ~1e154 overflow: every distance test below would then fail.
  if (!std::isfinite(L))
    return Status::Error("invalid control points: their coordinates are too large (the extent of "
                         "the control points overflows double precision)");
  if ((curveU[0] - curveV[0]).norm() > 1e-9 * L)
    return Status::Error("first control points not shared: CurveU point 0 " +
                         FormatPoint(curveU[0]) + " differs from CurveV point 0 " +
                         FormatPoint(curveV[0]) + "; both curves must start at the same point P0");
  for (int c = 0; c < 2; ++c)
    for (std::size_t i = 0; i + 1 < curves[c]->size(); ++i)
      if (((*curves[c])[i + 1] - (*curves[c])[i]).norm() <= 1e-9 * L)
        return Status::Error("degenerate surface: " + std::string(names[c]) + " control points " +
                             std::to_string(i) + " and " + std::to_string(i + 1) + " coincide at " +
                             FormatPoint((*curves[c])[i]) +
                             " (closer than 1e-9 times the control points' extent, " +
                             std::to_string(L) + ")");

  out.curveU_ = curveU;
  out.curveV_ = curveV;
  out.p0_ = curveU[0];
  out.flip_ = flipNormal;
  out.size_ = L;

  // Samples of each curve, including both one-sided ends of every segment.
  struct Sample {
    double param;
    Vector3d d1;
  };
  auto samples = [](const std::vector<Vector3d>& P, int per) {
    std::vector<Sample> s;
    const int k = int(P.size() - 1) / 3;
    for (int seg = 0; seg < k; ++seg)
      for (int i = 0; i <= per; ++i) {
        const double t = double(i) / per;
        s.push_back({(seg + t) / k, evalSegment(P, seg, t).d1 * k});
      }
    return s;
  };
  const int per = 8;
  const std::vector<Sample> su = samples(curveU, per), sv = samples(curveV, per);
  for (int c = 0; c < 2; ++c) {
    const std::vector<Sample>& s = c == 0 ? su : sv;
    for (const Sample& x : s)
      if (x.d1.norm() <= 1e-9 * L)
        return Status::Error("degenerate surface: the tangent of " + std::string(names[c]) +
                             " vanishes at " + (c == 0 ? "u" : "v") + " = " +
                             FormatNumber(x.param) + " (coincident or cusped control points)");
  }
  for (const Sample& a : su)
    for (const Sample& b : sv) {
      const double sinAngle = a.d1.cross(b.d1).norm() / (a.d1.norm() * b.d1.norm());
      if (sinAngle < 1e-3)
        return Status::Error("degenerate surface: dS/du x dS/dv vanishes at " +
                             FormatParameters(a.param, b.param) +
                             " (CurveU and CurveV are parallel there, the surface has no area)");
    }
  // Normals of neighbouring samples must not reverse (a fold).
  for (std::size_t i = 0; i < su.size(); ++i)
    for (std::size_t j = 0; j < sv.size(); ++j) {
      const Vector3d n = su[i].d1.cross(sv[j].d1).normalized();
      if (i + 1 < su.size()) {
        const Vector3d m = su[i + 1].d1.cross(sv[j].d1).normalized();
        if (n.dot(m) < 0)
          return Status::Error("self-intersecting surface: the normal reverses between " +
                               FormatParameters(su[i].param, sv[j].param) + " and " +
                               FormatParameters(su[i + 1].param, sv[j].param) +
                               " (CurveU folds back)");
      }
      if (j + 1 < sv.size()) {
        const Vector3d m = su[i].d1.cross(sv[j + 1].d1).normalized();
        if (n.dot(m) < 0)
          return Status::Error("self-intersecting surface: the normal reverses between " +
                               FormatParameters(su[i].param, sv[j].param) + " and " +
                               FormatParameters(su[i].param, sv[j + 1].param) +
                               " (CurveV folds back)");
      }
    }
  // Sampled patch triangles must not cross each other.
  {
    SurfaceMesh tess;
    std::vector<Vector2d> uv;
    out.tessellate(per, tess, &uv);
    std::vector<Tri> tris = FanTriangles(tess);
    std::vector<std::int64_t> all(tris.size());
    for (std::size_t t = 0; t < tris.size(); ++t)
      all[t] = std::int64_t(t);
    const TriangleBoxTree tree(tris, tess.points, all);
    std::vector<std::int64_t> cand;
    for (std::size_t a = 0; a < tris.size(); ++a) {
      tree.candidates(std::int64_t(a), cand);
      for (std::int64_t b : cand) {
        if (b <= std::int64_t(a))
          continue; // each pair once; the tree already left out pairs whose boxes are apart
        if (TrianglesIntersect(tris[a], tris[b], tess.points, true)) {
          const Vector2d& pa = uv[tris[a].v[0]];
          const Vector2d& pb = uv[tris[b].v[0]];
          out = BezierSurface{};
          return Status::Error("self-intersecting surface: the patch crosses itself near " +
                               FormatParameters(pa.x(), pa.y()) + " and " +
                               FormatParameters(pb.x(), pb.y()));
        }
      }
    }
  }
  // Initialisation grid.
  auto grid = [](const std::vector<Vector3d>& P, std::vector<double>& par,
                 std::vector<Vector3d>& pts) {
    const int k = int(P.size() - 1) / 3;
    const int n = 8 * k;
    for (int i = 0; i <= n; ++i) {
      par.push_back(double(i) / n);
      pts.push_back(evalCurve(P, par.back()).p);
    }
  };
  grid(out.curveU_, out.gridU_, out.gridUPoints_);
  grid(out.curveV_, out.gridV_, out.gridVPoints_);
  return Status::Ok();
}

SurfaceProjection BezierSurface::finish(const Vector3d& x, double u, double v) const {
  SurfaceProjection r;
  Vector3d S, Su, Sv, Suu, Svv;
  derivatives(u, v, S, Su, Sv, Suu, Svv);
  r.u = u;
  r.v = v;
  r.point = S;
  Vector3d n = Su.cross(Sv);
  if (n.norm() > 0)
    n.normalize();
  r.normal = flip_ ? Vector3d(-n) : n;
  const Vector3d F = S - x;
  r.signedDistance = (x - S).dot(r.normal);
  const double tol = 1e-6 * size_ + 1e-4 * F.norm();
  const double edge = 1e-12;
  bool in = true;
  if (u <= edge || u >= 1 - edge)
    in = in && std::abs(Su.dot(F)) <= tol * Su.norm();
  if (v <= edge || v >= 1 - edge)
    in = in && std::abs(Sv.dot(F)) <= tol * Sv.norm();
  r.inside = in;
  return r;
}

SurfaceProjection BezierSurface::newton(const Vector3d& x, double u, double v) const {
  u = Clamp01(u);
  v = Clamp01(v);
  auto f = [&](double uu, double vv) { return (evaluate(uu, vv) - x).squaredNorm(); };
  double fc = f(u, v);
  for (int it = 0; it < 60; ++it) {
    Vector3d S, Su, Sv, Suu, Svv;
    derivatives(u, v, S, Su, Sv, Suu, Svv);
    const Vector3d F = S - x;
    const Vector2d g(Su.dot(F), Sv.dot(F));
    Eigen::Matrix2d JtJ;
    JtJ << Su.dot(Su), Su.dot(Sv), Su.dot(Sv), Sv.dot(Sv);
    Eigen::Matrix2d H = JtJ;
    H(0, 0) += Suu.dot(F);
    H(1, 1) += Svv.dot(F);
    const bool fixU = (u <= 0 && g[0] > 0) || (u >= 1 && g[0] < 0);
    const bool fixV = (v <= 0 && g[1] > 0) || (v >= 1 && g[1] < 0);
    if (fixU && fixV)
      break;
    Vector2d d = Vector2d::Zero();
    if (!fixU && !fixV) {
      const bool pd = H(0, 0) > 0 && H.determinant() > 0;
      Eigen::Matrix2d M =
          pd ? H : Eigen::Matrix2d(JtJ + 1e-3 * JtJ.trace() * Eigen::Matrix2d::Identity());
      d = -M.inverse() * g;
    } else if (!fixU) {
      const double h = H(0, 0) > 0 ? H(0, 0) : JtJ(0, 0);
      d[0] = -g[0] / h;
    } else {
      const double h = H(1, 1) > 0 ? H(1, 1) : JtJ(1, 1);
      d[1] = -g[1] / h;
    }
    if (!d.allFinite())
      break;
    double alpha = 1.0;
    bool improved = false;
    double un = u, vn = v, fn = fc;
    for (int ls = 0; ls < 40; ++ls) {
      un = Clamp01(u + alpha * d[0]);
      vn = Clamp01(v + alpha * d[1]);
      fn = f(un, vn);
      if (fn < fc) {
        improved = true;
        break;
      }
      alpha *= 0.5;
    }
    if (!improved)
      break;
    const double change = std::abs(un - u) + std::abs(vn - v);
    u = un;
    v = vn;
    fc = fn;
    if (change < 1e-15)
      break;
  }
  return finish(x, u, v);
}

SurfaceProjection BezierSurface::project(const Vector3d& x) const {
  double best = std::numeric_limits<double>::infinity();
  std::size_t bi = 0, bj = 0;
  for (std::size_t i = 0; i < gridUPoints_.size(); ++i) {
    const Vector3d a = gridUPoints_[i] - p0_ - x;
    for (std::size_t j = 0; j < gridVPoints_.size(); ++j) {
      const double d = (a + gridVPoints_[j]).squaredNorm();
      if (d < best) {
        best = d;
        bi = i;
        bj = j;
      }
    }
  }
  if (gridU_.empty())
    return finish(x, 0, 0);
  return newton(x, gridU_[bi], gridV_[bj]);
}

void BezierSurface::tessellate(int perSegment, SurfaceMesh& out, std::vector<Vector2d>* uv,
                               RowVectors3d* normals) const {
  out = SurfaceMesh{};
  perSegment = std::max(perSegment, 1);
  const int nu = perSegment * segmentsU(), nv = perSegment * segmentsV();
  out.points.resize((nu + 1) * (nv + 1), 3);
  if (uv)
    uv->assign((nu + 1) * (nv + 1), Vector2d::Zero());
  if (normals)
    normals->resize((nu + 1) * (nv + 1), 3);
  auto id = [&](int i, int j) { return std::int64_t(j) * (nu + 1) + i; };
  for (int j = 0; j <= nv; ++j)
    for (int i = 0; i <= nu; ++i) {
      const double u = double(i) / nu, v = double(j) / nv;
      out.points.row(id(i, j)) = evaluate(u, v).transpose();
      if (uv)
        (*uv)[id(i, j)] = Vector2d(u, v);
      if (normals)
        normals->row(id(i, j)) = unitNormal(u, v).transpose();
    }
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const std::int64_t a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      if (!flip_) {
        out.addCell({a, b, c});
        out.addCell({a, c, d});
      } else {
        out.addCell({a, c, b});
        out.addCell({a, d, c});
      }
    }
}

} // namespace faceplan
