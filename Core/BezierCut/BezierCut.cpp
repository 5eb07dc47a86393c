#include "BezierCut/BezierCut.h"

#include "ROIExtract/ROIExtract.h"

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <unordered_map>
#include <unordered_set>

namespace faceplan {

using Eigen::Vector2d;
using Eigen::Vector3d;

namespace {

std::string Num(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return buf;
}
std::string Pt(const Vector3d& p) { return "(" + Num(p.x()) + ", " + Num(p.y()) + ", " + Num(p.z()) + ")"; }
std::string UV(double u, double v) { return "(u, v) = (" + Num(u) + ", " + Num(v) + ")"; }

double Clamp01(double x) { return std::min(1.0, std::max(0.0, x)); }

struct Tri {
  std::int64_t v[3];
};

// ---------------------------------------------------------------- intersection tests
double Cross2(const Vector2d& a, const Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

// Does segment pq meet the interior of triangle abc (touching an edge or vertex of the triangle, or
// the segment only touching it with an endpoint on its border, does not count)?
bool SegmentHitsTriangle(const Vector3d& p, const Vector3d& q, const Vector3d& a, const Vector3d& b,
                         const Vector3d& c) {
  Vector3d n = (b - a).cross(c - a);
  const double nn = n.norm();
  if (!(nn > 0)) return false; // degenerate triangles are reported by the flip check
  n /= nn;
  const double scale = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm(), (q - p).norm()});
  const double eps = 1e-9 * scale;
  const double dp = (p - a).dot(n), dq = (q - a).dot(n);
  if ((dp > eps && dq > eps) || (dp < -eps && dq < -eps)) return false;
  if (std::abs(dp) <= eps && std::abs(dq) <= eps) {
    // Coplanar: work in the plane of the two largest normal components.
    int ax = 0;
    n.cwiseAbs().maxCoeff(&ax);
    const int i = (ax + 1) % 3, j = (ax + 2) % 3;
    auto P2 = [&](const Vector3d& x) { return Vector2d(x[i], x[j]); };
    Vector2d P = P2(p), Q = P2(q), A = P2(a), B = P2(b), C = P2(c);
    if (Cross2(B - A, C - A) < 0) std::swap(B, C);
    const double area2 = Cross2(B - A, C - A);
    const double tolA = 1e-9 * area2;
    auto inside = [&](const Vector2d& X) {
      return Cross2(B - A, X - A) > tolA && Cross2(C - B, X - B) > tolA && Cross2(A - C, X - C) > tolA;
    };
    if (inside(P) || inside(Q)) return true;
    const double tolL = 1e-9 * scale * scale;
    auto proper = [&](const Vector2d& E0, const Vector2d& E1) {
      const double o1 = Cross2(Q - P, E0 - P), o2 = Cross2(Q - P, E1 - P);
      const double o3 = Cross2(E1 - E0, P - E0), o4 = Cross2(E1 - E0, Q - E0);
      return ((o1 > tolL && o2 < -tolL) || (o1 < -tolL && o2 > tolL)) &&
             ((o3 > tolL && o4 < -tolL) || (o3 < -tolL && o4 > tolL));
    };
    return proper(A, B) || proper(B, C) || proper(C, A);
  }
  const double s = Clamp01(dp / (dp - dq));
  const Vector3d x = p + s * (q - p);
  // Barycentric coordinates of x in abc.
  const Vector3d v0 = b - a, v1 = c - a, v2 = x - a;
  const double d00 = v0.dot(v0), d01 = v0.dot(v1), d11 = v1.dot(v1), d20 = v2.dot(v0), d21 = v2.dot(v1);
  const double den = d00 * d11 - d01 * d01;
  if (!(den > 0)) return false;
  const double bv = (d11 * d20 - d01 * d21) / den, bw = (d00 * d21 - d01 * d20) / den;
  const double bu = 1.0 - bv - bw;
  const double tol = 1e-9;
  return bu > tol && bv > tol && bw > tol;
}

// Triangles sharing two or more vertices are never reported (their folding is a flip);
// skipSharedVertex also skips pairs sharing one vertex.
bool TrianglesIntersect(const Tri& A, const Tri& B, const SurfacePoints& P, bool skipSharedVertex) {
  int shared = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (A.v[i] == B.v[j]) ++shared;
  if (shared >= 2 || (shared == 1 && skipSharedVertex)) return false;
  auto row = [&](std::int64_t k) { return Vector3d(P.row(k).transpose()); };
  const Vector3d a[3] = {row(A.v[0]), row(A.v[1]), row(A.v[2])};
  const Vector3d b[3] = {row(B.v[0]), row(B.v[1]), row(B.v[2])};
  for (int e = 0; e < 3; ++e) {
    if (SegmentHitsTriangle(a[e], a[(e + 1) % 3], b[0], b[1], b[2])) return true;
    if (SegmentHitsTriangle(b[e], b[(e + 1) % 3], a[0], a[1], a[2])) return true;
  }
  return false;
}

// Uniform spatial hash over triangle bounding boxes.
class TriangleHash {
public:
  TriangleHash(const std::vector<Tri>& tris, const SurfacePoints& P, const std::vector<std::int64_t>& ids,
               double cell)
      : tris_(tris), P_(P), h_(cell) {
    for (std::int64_t t : ids) {
      Eigen::Array3i lo, hi;
      Range(t, lo, hi);
      for (int x = lo[0]; x <= hi[0]; ++x)
        for (int y = lo[1]; y <= hi[1]; ++y)
          for (int z = lo[2]; z <= hi[2]; ++z) map_[Key(x, y, z)].push_back(t);
    }
  }
  // Candidate triangles whose cells overlap those of triangle t.
  void Candidates(std::int64_t t, std::vector<std::int64_t>& out) const {
    out.clear();
    Eigen::Array3i lo, hi;
    Range(t, lo, hi);
    for (int x = lo[0]; x <= hi[0]; ++x)
      for (int y = lo[1]; y <= hi[1]; ++y)
        for (int z = lo[2]; z <= hi[2]; ++z) {
          auto it = map_.find(Key(x, y, z));
          if (it != map_.end()) out.insert(out.end(), it->second.begin(), it->second.end());
        }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
  }

private:
  void Range(std::int64_t t, Eigen::Array3i& lo, Eigen::Array3i& hi) const {
    Eigen::Array3d mn = P_.row(tris_[t].v[0]).transpose().array(), mx = mn;
    for (int k = 1; k < 3; ++k) {
      mn = mn.min(P_.row(tris_[t].v[k]).transpose().array());
      mx = mx.max(P_.row(tris_[t].v[k]).transpose().array());
    }
    for (int d = 0; d < 3; ++d) {
      lo[d] = int(std::floor(mn[d] / h_));
      hi[d] = int(std::floor(mx[d] / h_));
      if (hi[d] - lo[d] > 64) hi[d] = lo[d] + 64; // guard against huge triangles
    }
  }
  static std::int64_t Key(int x, int y, int z) {
    return (std::int64_t(x) * 73856093) ^ (std::int64_t(y) * 19349663) ^ (std::int64_t(z) * 83492791);
  }
  const std::vector<Tri>& tris_;
  const SurfacePoints& P_;
  double h_;
  std::unordered_map<std::int64_t, std::vector<std::int64_t>> map_;
};

std::vector<Tri> FanTriangles(const SurfaceMesh& mesh) {
  std::vector<Tri> tris;
  for (std::int64_t c = 0; c < mesh.numCells(); ++c) {
    const std::int64_t m = mesh.cellSize(c);
    const std::int64_t* ids = mesh.cell(c);
    for (std::int64_t k = 1; k + 1 < m; ++k) tris.push_back(Tri{{ids[0], ids[k], ids[k + 1]}});
  }
  return tris;
}

Vector3d AreaVector(const Tri& t, const SurfacePoints& P) {
  const Vector3d a = P.row(t.v[0]).transpose(), b = P.row(t.v[1]).transpose(), c = P.row(t.v[2]).transpose();
  return 0.5 * (b - a).cross(c - a);
}

double Quality(const Tri& t, const SurfacePoints& P) {
  const Vector3d a = P.row(t.v[0]).transpose(), b = P.row(t.v[1]).transpose(), c = P.row(t.v[2]).transpose();
  const double l2 = (b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm();
  if (!(l2 > 0)) return 0;
  return 4.0 * std::sqrt(3.0) * (0.5 * (b - a).cross(c - a).norm()) / l2;
}

// Triangles (among `active`) that intersect another triangle in `after` but did not in `before`.
std::vector<std::int64_t> NewIntersections(const std::vector<Tri>& tris, const SurfacePoints& before,
                                           const SurfacePoints& after,
                                           const std::vector<std::uint8_t>& activeTri) {
  std::vector<std::int64_t> active;
  Eigen::Array3d lo = Eigen::Array3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  double edgeSum = 0;
  for (std::size_t t = 0; t < tris.size(); ++t) {
    if (!activeTri[t]) continue;
    active.push_back(std::int64_t(t));
    for (int k = 0; k < 3; ++k) {
      lo = lo.min(after.row(tris[t].v[k]).transpose().array());
      hi = hi.max(after.row(tris[t].v[k]).transpose().array());
      edgeSum += (after.row(tris[t].v[k]) - after.row(tris[t].v[(k + 1) % 3])).norm();
    }
  }
  std::vector<std::int64_t> result;
  if (active.empty()) return result;
  double h = 2.0 * edgeSum / (3.0 * double(active.size()));
  const double ext = (hi - lo).maxCoeff();
  if (!(h > 0)) h = ext > 0 ? ext : 1.0;
  h = std::max(h, ext / 200.0); // at most ~200^3 cells over the active region
  // Every triangle whose box meets the active region's box (grown by one cell).
  std::vector<std::int64_t> nearby;
  for (std::size_t t = 0; t < tris.size(); ++t) {
    bool meets = true;
    Eigen::Array3d mn = after.row(tris[t].v[0]).transpose().array(), mx = mn;
    for (int k = 1; k < 3; ++k) {
      mn = mn.min(after.row(tris[t].v[k]).transpose().array());
      mx = mx.max(after.row(tris[t].v[k]).transpose().array());
    }
    for (int d = 0; d < 3; ++d)
      if (mx[d] < lo[d] - h || mn[d] > hi[d] + h) meets = false;
    if (meets) nearby.push_back(std::int64_t(t));
  }
  TriangleHash hash(tris, after, nearby, h);
  std::vector<std::uint8_t> flagged(tris.size(), 0);
  std::vector<std::int64_t> cand;
  for (std::int64_t a : active) {
    hash.Candidates(a, cand);
    for (std::int64_t b : cand) {
      if (b == a || (activeTri[b] && b < a)) continue; // each pair once
      if (!TrianglesIntersect(tris[a], tris[b], after, false)) continue;
      if (TrianglesIntersect(tris[a], tris[b], before, false)) continue; // was already so
      flagged[a] = flagged[b] = 1;
    }
  }
  for (std::size_t t = 0; t < tris.size(); ++t)
    if (flagged[t]) result.push_back(std::int64_t(t));
  return result;
}

} // namespace

// ================================================================ BezierSurface

BezierSurface::CurveEval BezierSurface::EvalSegment(const std::vector<Vector3d>& P, int seg, double t) {
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

BezierSurface::CurveEval BezierSurface::EvalCurve(const std::vector<Vector3d>& P, double u) {
  const int k = int(P.size() - 1) / 3;
  u = Clamp01(u);
  int seg = std::min(int(std::floor(u * k)), k - 1);
  const double t = u * k - seg;
  CurveEval e = EvalSegment(P, seg, t);
  e.d1 *= k;
  e.d2 *= double(k) * k;
  return e;
}

Vector3d BezierSurface::Evaluate(double u, double v) const {
  return EvalCurve(U_, u).p + EvalCurve(V_, v).p - P0_;
}

void BezierSurface::Derivatives(double u, double v, Vector3d& S, Vector3d& Su, Vector3d& Sv,
                                Vector3d& Suu, Vector3d& Svv) const {
  const CurveEval a = EvalCurve(U_, u), b = EvalCurve(V_, v);
  S = a.p + b.p - P0_;
  Su = a.d1;
  Sv = b.d1;
  Suu = a.d2;
  Svv = b.d2;
}

Vector3d BezierSurface::UnitNormal(double u, double v) const {
  Vector3d n = EvalCurve(U_, u).d1.cross(EvalCurve(V_, v).d1);
  const double len = n.norm();
  if (len > 0) n /= len;
  return flip_ ? Vector3d(-n) : n;
}

Status BezierSurface::Create(const std::vector<Vector3d>& curveU, const std::vector<Vector3d>& curveV,
                             bool flipNormal, BezierSurface& out) {
  out = BezierSurface{};
  const std::vector<Vector3d>* curves[2] = {&curveU, &curveV};
  const char* names[2] = {"CurveU", "CurveV"};
  for (int c = 0; c < 2; ++c) {
    const std::size_t n = curves[c]->size();
    if (n < 4 || (n - 1) % 3 != 0)
      return Status::Error("invalid control points: " + std::string(names[c]) + " has " +
                           std::to_string(n) +
                           " points; a composite cubic Bezier curve needs 3k+1 (4, 7, 10, ...)");
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
  if (!(L > 0)) return Status::Error("degenerate surface: all control points coincide");
  if ((curveU[0] - curveV[0]).norm() > 1e-9 * L)
    return Status::Error("first control points not shared: CurveU point 0 " + Pt(curveU[0]) +
                         " differs from CurveV point 0 " + Pt(curveV[0]) +
                         "; both curves must start at the same point P0");
  for (int c = 0; c < 2; ++c)
    for (std::size_t i = 0; i + 1 < curves[c]->size(); ++i)
      if (((*curves[c])[i + 1] - (*curves[c])[i]).norm() <= 1e-9 * L)
        return Status::Error("degenerate surface: " + std::string(names[c]) + " control points " +
                             std::to_string(i) + " and " + std::to_string(i + 1) + " coincide at " +
                             Pt((*curves[c])[i]));

  out.U_ = curveU;
  out.V_ = curveV;
  out.P0_ = curveU[0];
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
        s.push_back({(seg + t) / k, EvalSegment(P, seg, t).d1 * k});
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
                             " vanishes at " + (c == 0 ? "u" : "v") + " = " + Num(x.param) +
                             " (coincident or cusped control points)");
  }
  for (const Sample& a : su)
    for (const Sample& b : sv) {
      const double sinAngle = a.d1.cross(b.d1).norm() / (a.d1.norm() * b.d1.norm());
      if (sinAngle < 1e-3)
        return Status::Error("degenerate surface: dS/du x dS/dv vanishes at " + UV(a.param, b.param) +
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
                               UV(su[i].param, sv[j].param) + " and " +
                               UV(su[i + 1].param, sv[j].param) + " (CurveU folds back)");
      }
      if (j + 1 < sv.size()) {
        const Vector3d m = su[i].d1.cross(sv[j + 1].d1).normalized();
        if (n.dot(m) < 0)
          return Status::Error("self-intersecting surface: the normal reverses between " +
                               UV(su[i].param, sv[j].param) + " and " +
                               UV(su[i].param, sv[j + 1].param) + " (CurveV folds back)");
      }
    }
  // Sampled patch triangles must not cross each other.
  {
    SurfaceMesh tess;
    std::vector<Vector2d> uv;
    out.Tessellate(per, tess, &uv);
    std::vector<Tri> tris = FanTriangles(tess);
    std::vector<std::int64_t> all(tris.size());
    double edge = 0;
    for (std::size_t t = 0; t < tris.size(); ++t) {
      all[t] = std::int64_t(t);
      edge = std::max(edge, (tess.points.row(tris[t].v[0]) - tess.points.row(tris[t].v[1])).norm());
      edge = std::max(edge, (tess.points.row(tris[t].v[0]) - tess.points.row(tris[t].v[2])).norm());
    }
    TriangleHash hash(tris, tess.points, all, std::max(edge, 1e-12 * L));
    std::vector<std::int64_t> cand;
    for (std::size_t a = 0; a < tris.size(); ++a) {
      hash.Candidates(std::int64_t(a), cand);
      for (std::int64_t b : cand) {
        if (b <= std::int64_t(a)) continue;
        if (TrianglesIntersect(tris[a], tris[b], tess.points, true)) {
          const Vector2d& pa = uv[tris[a].v[0]];
          const Vector2d& pb = uv[tris[b].v[0]];
          out = BezierSurface{};
          return Status::Error("self-intersecting surface: the patch crosses itself near " +
                               UV(pa.x(), pa.y()) + " and " + UV(pb.x(), pb.y()));
        }
      }
    }
  }
  // Initialisation grid.
  auto grid = [](const std::vector<Vector3d>& P, std::vector<double>& par, std::vector<Vector3d>& pts) {
    const int k = int(P.size() - 1) / 3;
    const int n = 8 * k;
    for (int i = 0; i <= n; ++i) {
      par.push_back(double(i) / n);
      pts.push_back(EvalCurve(P, par.back()).p);
    }
  };
  grid(out.U_, out.gridU_, out.gridUP_);
  grid(out.V_, out.gridV_, out.gridVP_);
  return Status::Ok();
}

SurfaceProjection BezierSurface::Finish(const Vector3d& x, double u, double v) const {
  SurfaceProjection r;
  Vector3d S, Su, Sv, Suu, Svv;
  Derivatives(u, v, S, Su, Sv, Suu, Svv);
  r.u = u;
  r.v = v;
  r.point = S;
  Vector3d n = Su.cross(Sv);
  if (n.norm() > 0) n.normalize();
  r.normal = flip_ ? Vector3d(-n) : n;
  const Vector3d F = S - x;
  r.signedDistance = (x - S).dot(r.normal);
  const double tol = 1e-6 * size_ + 1e-4 * F.norm();
  const double edge = 1e-12;
  bool in = true;
  if (u <= edge || u >= 1 - edge) in = in && std::abs(Su.dot(F)) <= tol * Su.norm();
  if (v <= edge || v >= 1 - edge) in = in && std::abs(Sv.dot(F)) <= tol * Sv.norm();
  r.inside = in;
  return r;
}

SurfaceProjection BezierSurface::Newton(const Vector3d& x, double u, double v) const {
  u = Clamp01(u);
  v = Clamp01(v);
  auto f = [&](double uu, double vv) { return (Evaluate(uu, vv) - x).squaredNorm(); };
  double fc = f(u, v);
  for (int it = 0; it < 60; ++it) {
    Vector3d S, Su, Sv, Suu, Svv;
    Derivatives(u, v, S, Su, Sv, Suu, Svv);
    const Vector3d F = S - x;
    const Vector2d g(Su.dot(F), Sv.dot(F));
    Eigen::Matrix2d JtJ;
    JtJ << Su.dot(Su), Su.dot(Sv), Su.dot(Sv), Sv.dot(Sv);
    Eigen::Matrix2d H = JtJ;
    H(0, 0) += Suu.dot(F);
    H(1, 1) += Svv.dot(F);
    const bool fixU = (u <= 0 && g[0] > 0) || (u >= 1 && g[0] < 0);
    const bool fixV = (v <= 0 && g[1] > 0) || (v >= 1 && g[1] < 0);
    if (fixU && fixV) break;
    Vector2d d = Vector2d::Zero();
    if (!fixU && !fixV) {
      const bool pd = H(0, 0) > 0 && H.determinant() > 0;
      Eigen::Matrix2d M = pd ? H : Eigen::Matrix2d(JtJ + 1e-3 * JtJ.trace() * Eigen::Matrix2d::Identity());
      d = -M.inverse() * g;
    } else if (!fixU) {
      const double h = H(0, 0) > 0 ? H(0, 0) : JtJ(0, 0);
      d[0] = -g[0] / h;
    } else {
      const double h = H(1, 1) > 0 ? H(1, 1) : JtJ(1, 1);
      d[1] = -g[1] / h;
    }
    if (!d.allFinite()) break;
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
    if (!improved) break;
    const double change = std::abs(un - u) + std::abs(vn - v);
    u = un;
    v = vn;
    fc = fn;
    if (change < 1e-15) break;
  }
  return Finish(x, u, v);
}

SurfaceProjection BezierSurface::Project(const Vector3d& x) const {
  double best = std::numeric_limits<double>::infinity();
  std::size_t bi = 0, bj = 0;
  for (std::size_t i = 0; i < gridUP_.size(); ++i) {
    const Vector3d a = gridUP_[i] - P0_ - x;
    for (std::size_t j = 0; j < gridVP_.size(); ++j) {
      const double d = (a + gridVP_[j]).squaredNorm();
      if (d < best) {
        best = d;
        bi = i;
        bj = j;
      }
    }
  }
  if (gridU_.empty()) return Finish(x, 0, 0);
  return Newton(x, gridU_[bi], gridV_[bj]);
}

SurfaceProjection BezierSurface::ProjectFrom(const Vector3d& x, double u0, double v0) const {
  return Newton(x, u0, v0);
}

void BezierSurface::Tessellate(int perSegment, SurfaceMesh& out, std::vector<Vector2d>* uv) const {
  out = SurfaceMesh{};
  perSegment = std::max(perSegment, 1);
  const int nu = perSegment * SegmentsU(), nv = perSegment * SegmentsV();
  out.points.resize((nu + 1) * (nv + 1), 3);
  if (uv) uv->assign((nu + 1) * (nv + 1), Vector2d::Zero());
  auto id = [&](int i, int j) { return std::int64_t(j) * (nu + 1) + i; };
  for (int j = 0; j <= nv; ++j)
    for (int i = 0; i <= nu; ++i) {
      const double u = double(i) / nu, v = double(j) / nv;
      out.points.row(id(i, j)) = Evaluate(u, v).transpose();
      if (uv) (*uv)[id(i, j)] = Vector2d(u, v);
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

// ================================================================ the cut

std::int64_t CountNewIntersections(const SurfaceMesh& cells, const SurfacePoints& before,
                                   const SurfacePoints& after, const std::vector<std::uint8_t>& active,
                                   std::int64_t* firstTriangle) {
  std::vector<Tri> tris = FanTriangles(cells);
  std::vector<std::uint8_t> activeTri(tris.size(), 0);
  for (std::size_t t = 0; t < tris.size(); ++t)
    for (int k = 0; k < 3; ++k)
      if (std::size_t(tris[t].v[k]) < active.size() && active[tris[t].v[k]]) activeTri[t] = 1;
  std::vector<std::int64_t> bad = NewIntersections(tris, before, after, activeTri);
  if (firstTriangle) *firstTriangle = bad.empty() ? -1 : bad.front();
  return std::int64_t(bad.size());
}

namespace {

enum class TriState { Ok, Degenerate, Flipped, Squashed };

class CutMapper {
public:
  CutMapper(const BezierSurface& surf, const std::vector<Tri>& tris,
            const std::vector<std::vector<std::int64_t>>& nbrs, const SurfacePoints& X0,
            const std::vector<std::uint8_t>& moved, const std::vector<Vector2d>& foot)
      : S_(surf), tris_(tris), nbrs_(nbrs), X0_(X0), moved_(moved), foot_(foot) {
    for (std::size_t t = 0; t < tris_.size(); ++t) {
      int m = 0;
      for (int k = 0; k < 3; ++k) m += moved_[tris_[t].v[k]];
      if (m > 0) {
        touched_.push_back(std::int64_t(t));
        a0_.push_back(AreaVector(tris_[t], X0_));
        q0_.push_back(Quality(tris_[t], X0_));
        full_.push_back(m == 3);
      }
    }
    for (std::size_t i = 0; i < moved_.size(); ++i)
      if (moved_[i]) movedIds_.push_back(std::int64_t(i));
    incident_.assign(moved_.size(), {});
    for (std::size_t k = 0; k < touched_.size(); ++k)
      for (int j = 0; j < 3; ++j) {
        const std::int64_t v = tris_[touched_[k]].v[j];
        if (moved_[v]) incident_[v].push_back(std::int64_t(k));
      }
    // Expected orientation of the moved region within S.
    double s = 0;
    for (std::size_t k = 0; k < touched_.size(); ++k) {
      if (!full_[k]) continue;
      const Tri& t = tris_[touched_[k]];
      Vector3d n = Vector3d::Zero();
      for (int j = 0; j < 3; ++j) n += S_.UnitNormal(foot_[t.v[j]].x(), foot_[t.v[j]].y());
      s += a0_[k].dot(n);
    }
    sigma_ = s < 0 ? -1.0 : 1.0;
    // The rim: moved vertices next to unmoved ones. Their direct projection keeps the direction
    // of their edges, which keeps the steep triangles joining them to the unmoved bone oriented, so
    // relaxation only moves them when they are part of a bad triangle themselves.
    rim_.assign(moved_.size(), 0);
    for (std::int64_t i : movedIds_)
      for (std::int64_t j : nbrs_[i])
        if (!moved_[j]) rim_[i] = 1;
    activeTri_.assign(tris_.size(), 0);
    for (std::int64_t t : touched_) activeTri_[t] = 1;
  }

  // Direct projection.
  bool Direct(SurfacePoints& P, std::string& why) {
    uv_ = foot_;
    P = X0_;
    for (std::int64_t i : movedIds_) P.row(i) = S_.Evaluate(uv_[i].x(), uv_[i].y()).transpose();
    return FinalCheck(P, nullptr, why);
  }

  // Local repair on S itself: relax growing neighbourhoods of the bad triangles of the direct
  // projection (the rest keeps its direct projection).
  bool LocalRepair(int maxRelax, SurfacePoints& P, std::string& why) {
    uv_ = foot_;
    P = X0_;
    ResetRegion();
    for (std::int64_t i : movedIds_) Place(P, i, 1.0);
    std::vector<std::int64_t> bad;
    if (Untangle(P, 200) && FinalCheck(P, nullptr, why)) return true;
    // Harmonic relaxation of growing neighbourhoods, each followed by untangling.
    uv_ = foot_;
    for (std::int64_t i : movedIds_) Place(P, i, 1.0);
    for (int iter = 0; iter < maxRelax; ++iter) {
      if (FinalCheck(P, &bad, why)) return true;
      if (!Relax(P, bad, 1.0, 1 << std::min(iter, 20))) break;
      Untangle(P, 100);
    }
    return FinalCheck(P, nullptr, why);
  }

  // Signed size of touched triangle k with its current points, relative to its original area:
  // for a triangle whose vertices all moved, sigma * (area vector . n(uv of `at`)) / |a0|; for the
  // others, (area vector . a0) / |a0|^2. Positive = correctly oriented.
  double SignedSize(std::size_t k, const SurfacePoints& P, std::int64_t at) const {
    const double A0 = a0_[k].norm();
    if (!(A0 > 0)) return 1.0;
    const Vector3d a1 = AreaVector(tris_[touched_[k]], P);
    if (full_[k]) return sigma_ * a1.dot(S_.UnitNormal(uv_[at].x(), uv_[at].y())) / A0;
    return a1.dot(a0_[k]) / (A0 * A0);
  }

  // Untangling: each moved vertex of a flipped or degenerate triangle (and its moved neighbours)
  // moves within S to maximise the smallest signed size of its triangles (pattern search in
  // (u,v)). Returns true when no triangle is flipped or degenerate any more.
  bool Untangle(SurfacePoints& P, int maxSweeps) {
    std::vector<std::int64_t> bad, verts;
    std::vector<std::uint8_t> mark(moved_.size(), 0);
    for (int sweep = 0; sweep < maxSweeps; ++sweep) {
      CollectBad(P, a0_, false, true, bad);
      if (bad.empty()) return true;
      verts.clear();
      for (std::int64_t tr : bad)
        for (int j = 0; j < 3; ++j) {
          const std::int64_t v = tris_[tr].v[j];
          if (!moved_[v]) continue;
          if (!mark[v]) { mark[v] = 1; verts.push_back(v); }
          if (sweep % 2 == 1)
            for (std::int64_t w : nbrs_[v])
              if (moved_[w] && !mark[w]) { mark[w] = 1; verts.push_back(w); }
        }
      for (std::int64_t v : verts) {
        mark[v] = 0;
        OptimizeVertex(P, v);
      }
    }
    CollectBad(P, a0_, false, true, bad);
    return bad.empty();
  }

  void OptimizeVertex(SurfacePoints& P, std::int64_t i) {
    auto worst = [&]() {
      double w = std::numeric_limits<double>::infinity();
      for (std::int64_t k : incident_[i]) w = std::min(w, SignedSize(std::size_t(k), P, i));
      return w;
    };
    double h = 0;
    for (std::int64_t j : nbrs_[i]) h += ((moved_[j] ? uv_[j] : foot_[j]) - uv_[i]).norm();
    h = nbrs_[i].empty() ? 1e-3 : 0.5 * h / double(nbrs_[i].size());
    if (!(h > 1e-12)) h = 1e-3;
    double best = worst();
    Vector2d bestUV = uv_[i];
    static const double dirs[8][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}, {0.7071, 0.7071}, {-0.7071, 0.7071}, {0.7071, -0.7071}, {-0.7071, -0.7071}};
    for (int it = 0; it < 40 && h > 1e-9; ++it) {
      bool improved = false;
      const Vector2d base = bestUV;
      for (const auto& d : dirs) {
        uv_[i] = Vector2d(Clamp01(base.x() + h * d[0]), Clamp01(base.y() + h * d[1]));
        Place(P, i, 1.0);
        const double w = worst();
        if (w > best) {
          best = w;
          bestUV = uv_[i];
          improved = true;
        }
      }
      if (!improved) h *= 0.5;
    }
    uv_[i] = bestUV;
    Place(P, i, 1.0);
  }

  // Mapping through T intermediary surfaces.
  bool Intermediary(int T, int maxRelax, SurfacePoints& P, std::string& why) {
    uv_ = foot_;
    P = X0_;
    ResetRegion();
    std::vector<Vector3d> prev = a0_;
    std::vector<std::int64_t> bad;
    for (int s = 1; s <= T; ++s) {
      const double t = double(s) / T;
      for (std::int64_t i : movedIds_) Place(P, i, t);
      if (s < T) {
        for (int iter = 0; iter < maxRelax; ++iter) {
          CollectBad(P, prev, true, false, bad);
          if (bad.empty() || !Relax(P, bad, t, 1 << std::min(iter, 20))) break;
        }
        for (std::size_t k = 0; k < touched_.size(); ++k) prev[k] = AreaVector(tris_[touched_[k]], P);
      }
    }
    // Last surface (t = 1): the final criteria, intersections included.
    for (int iter = 0; iter < maxRelax; ++iter) {
      if (FinalCheck(P, &bad, why)) return true;
      if (!Relax(P, bad, 1.0, 1 << std::min(iter, 20))) break;
    }
    return FinalCheck(P, nullptr, why);
  }

  const std::vector<Vector2d>& Parameters() const { return uv_; }

  void ResetRegion() {
    region_.clear();
    inRegion_.assign(moved_.size(), 0);
    solvedOnce_ = false;
  }

private:
  void Place(SurfacePoints& P, std::int64_t i, double t) const {
    const Vector3d s = S_.Evaluate(uv_[i].x(), uv_[i].y());
    if (t >= 1.0)
      P.row(i) = s.transpose();
    else
      P.row(i) = ((1.0 - t) * X0_.row(i).transpose() + t * s).transpose();
  }

  TriState State(std::size_t k, const SurfacePoints& P, const Vector3d& ref, bool finalStage,
                 bool quality) const {
    const Tri& t = tris_[touched_[k]];
    const double A0 = a0_[k].norm();
    if (!(A0 > 0)) return TriState::Ok; // degenerate before: not ours to judge
    const Vector3d a1 = AreaVector(t, P);
    if (!(a1.norm() > 1e-8 * A0)) return TriState::Degenerate;
    if (finalStage && full_[k]) {
      Vector3d n = Vector3d::Zero();
      for (int j = 0; j < 3; ++j) n += S_.UnitNormal(uv_[t.v[j]].x(), uv_[t.v[j]].y());
      if (!(sigma_ * a1.dot(n) > 0)) return TriState::Flipped;
    } else if (!(a1.dot(ref) > 0)) {
      return TriState::Flipped;
    }
    if (quality && Quality(t, P) < 0.2 * q0_[k]) return TriState::Squashed;
    return TriState::Ok;
  }

  void CollectBad(const SurfacePoints& P, const std::vector<Vector3d>& ref, bool quality,
                  bool finalStage, std::vector<std::int64_t>& bad) const {
    bad.clear();
    for (std::size_t k = 0; k < touched_.size(); ++k)
      if (State(k, P, ref[k], finalStage, quality) != TriState::Ok) bad.push_back(touched_[k]);
  }

  bool FinalCheck(const SurfacePoints& P, std::vector<std::int64_t>* badOut, std::string& why) const {
    std::vector<std::int64_t> bad;
    std::int64_t flipped = 0, degenerate = 0;
    for (std::size_t k = 0; k < touched_.size(); ++k) {
      const TriState s = State(k, P, a0_[k], true, false);
      if (s == TriState::Ok) continue;
      bad.push_back(touched_[k]);
      (s == TriState::Degenerate ? degenerate : flipped)++;
    }
    if (bad.empty()) {
      bad = NewIntersections(tris_, X0_, P, activeTri_);
      if (!bad.empty())
        why = std::to_string(bad.size()) + " triangles intersect other triangles (first: triangle " +
              std::to_string(bad.front()) + " of the fan triangulation)";
    } else {
      why = std::to_string(flipped) + " triangles flipped and " + std::to_string(degenerate) +
            " degenerate (first: triangle " + std::to_string(bad.front()) + ")";
    }
    if (badOut) *badOut = bad;
    return bad.empty();
  }

  // Tangential relaxation within the intermediary surface at t: the moved vertices of `bad`
  // triangles join the relaxed region, which then grows by `rings` rings of moved neighbours; the
  // region's (u,v) are replaced by the solution of the uniform graph Laplace equation (a Tutte /
  // harmonic map: every vertex at the average of its neighbours), with Dirichlet values from the
  // vertices around the region (the (u,v) of other moved vertices, the foot points of unmoved
  // ones). Returns false when the region did not change (nothing more to gain).
  bool Relax(SurfacePoints& P, const std::vector<std::int64_t>& bad, double t, int rings) {
    const std::size_t before = region_.size();
    for (std::int64_t tr : bad)
      for (int k = 0; k < 3; ++k) {
        const std::int64_t v = tris_[tr].v[k];
        if (moved_[v] && !inRegion_[v]) {
          inRegion_[v] = 1;
          region_.push_back(v);
        }
      }
    std::size_t begin = 0;
    for (int r = 0; r < rings; ++r) {
      const std::size_t end = region_.size();
      for (std::size_t k = begin; k < end; ++k)
        for (std::int64_t w : nbrs_[region_[k]])
          if (moved_[w] && !inRegion_[w] && !rim_[w]) {
            inRegion_[w] = 1;
            region_.push_back(w);
          }
      if (region_.size() == end) break;
      begin = 0; // grow from the whole region each ring
    }
    const bool grew = region_.size() != before || !solvedOnce_;
    if (!grew) return false;
    solvedOnce_ = true;

    const std::size_t m = region_.size();
    std::vector<std::int64_t> index(moved_.size(), -1);
    for (std::size_t k = 0; k < m; ++k) index[region_[k]] = std::int64_t(k);
    std::vector<Eigen::Triplet<double>> trip;
    Eigen::MatrixX2d rhs = Eigen::MatrixX2d::Zero(Eigen::Index(m), 2);
    const double eps = 1e-9;
    for (std::size_t k = 0; k < m; ++k) {
      const std::int64_t i = region_[k];
      trip.emplace_back(Eigen::Index(k), Eigen::Index(k), double(nbrs_[i].size()) + eps);
      rhs.row(Eigen::Index(k)) += eps * uv_[i].transpose();
      for (std::int64_t j : nbrs_[i]) {
        if (index[j] >= 0)
          trip.emplace_back(Eigen::Index(k), Eigen::Index(index[j]), -1.0);
        else
          rhs.row(Eigen::Index(k)) += (moved_[j] ? uv_[j] : foot_[j]).transpose();
      }
    }
    Eigen::SparseMatrix<double> A{Eigen::Index(m), Eigen::Index(m)};
    A.setFromTriplets(trip.begin(), trip.end());
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(A);
    if (solver.info() != Eigen::Success) return false;
    const Eigen::MatrixX2d sol = solver.solve(rhs);
    if (solver.info() != Eigen::Success || !sol.allFinite()) return false;
    for (std::size_t k = 0; k < m; ++k) {
      const std::int64_t i = region_[k];
      uv_[i] = Vector2d(Clamp01(sol(Eigen::Index(k), 0)), Clamp01(sol(Eigen::Index(k), 1)));
      Place(P, i, t);
    }
    return true;
  }

  const BezierSurface& S_;
  const std::vector<Tri>& tris_;
  const std::vector<std::vector<std::int64_t>>& nbrs_;
  const SurfacePoints& X0_;
  const std::vector<std::uint8_t>& moved_;
  const std::vector<Vector2d>& foot_;
  std::vector<Vector2d> uv_;
  std::vector<std::int64_t> touched_, movedIds_;
  std::vector<Vector3d> a0_;
  std::vector<double> q0_;
  std::vector<bool> full_;
  std::vector<std::uint8_t> activeTri_;
  std::vector<std::int64_t> region_; // vertices relaxed so far (this schedule)
  std::vector<std::uint8_t> inRegion_;
  std::vector<std::uint8_t> rim_;
  std::vector<std::vector<std::int64_t>> incident_; // touched triangles (indices into touched_) per moved vertex
  bool solvedOnce_ = false;
  double sigma_ = 1.0;
};

} // namespace

Status BezierCut(const SurfaceMesh& mesh, const std::vector<std::uint8_t>& roiMask,
                 const std::vector<std::uint8_t>& roiBoundary, const std::vector<Vector3d>& curveU,
                 const std::vector<Vector3d>& curveV, const BezierCutOptions& options,
                 BezierCutResult& result) {
  result = BezierCutResult{};
  Status s = ValidateSurfaceMesh(mesh);
  if (!s) return s;
  const std::int64_t n = mesh.numPoints();
  if (std::int64_t(roiMask.size()) != n || std::int64_t(roiBoundary.size()) != n)
    return Status::Error("ROIMask and ROIBoundary need one entry per point (" + std::to_string(n) +
                         "), got " + std::to_string(roiMask.size()) + " and " +
                         std::to_string(roiBoundary.size()));
  BezierSurface surf;
  s = BezierSurface::Create(curveU, curveV, options.flipNormal, surf);
  if (!s) return s;

  std::int64_t numROI = 0;
  for (std::int64_t i = 0; i < n; ++i) numROI += roiMask[i] ? 1 : 0;
  if (numROI == 0) return Status::Error("the ROI is empty (ROIMask is 0 everywhere)");

  std::vector<std::uint8_t> moved(n, 0);
  std::vector<Vector2d> foot(n, Vector2d::Zero());
  std::int64_t inside = 0;
  std::vector<std::int64_t> boundaryOnSide; // ROIBoundary vertices beyond the surface (never move)
  for (std::int64_t i = 0; i < n; ++i) {
    if (!roiMask[i]) continue;
    const SurfaceProjection pr = surf.Project(mesh.points.row(i).transpose());
    foot[i] = Vector2d(pr.u, pr.v); // also for unmoved ROI vertices: relaxation boundary values
    if (!pr.inside) continue;
    ++inside;
    const bool side = options.operation == CutOperation::Cut ? pr.signedDistance > 0 : pr.signedDistance < 0;
    if (side && !roiBoundary[i]) moved[i] = 1;
    if (side && roiBoundary[i] && std::abs(pr.signedDistance) > 1e-9 * surf.Size()) boundaryOnSide.push_back(i);
  }
  if (inside == 0)
    return Status::Error("surface not meeting the ROI: no ROI vertex projects inside the (u,v) "
                         "patch [0,1]^2 of the Bezier surface");

  BezierCutResult r;
  r.numInsidePatch = inside;
  surf.Tessellate(options.displayResolution, r.operativeSurface);
  r.moved = moved;
  for (std::int64_t i = 0; i < n; ++i) r.numMoved += moved[i];
  r.points = mesh.points;
  r.displacement = SurfacePoints::Zero(n, 3);
  r.parameters.assign(n, Vector2d::Zero());
  if (r.numMoved == 0) {
    r.warnings.push_back(std::string("no ROI vertex lies on the ") +
                         (options.operation == CutOperation::Cut ? "cut (normal) side" : "fill side (against the normal)") +
                         " inside the patch: nothing moved");
    result = std::move(r);
    return Status::Ok();
  }

  const std::vector<Tri> tris = FanTriangles(mesh);
  std::vector<std::vector<std::int64_t>> nbrs(n);
  auto addEdge = [&](std::int64_t a, std::int64_t b) {
    if (a == b) return;
    nbrs[a].push_back(b);
    nbrs[b].push_back(a);
  };
  for (std::int64_t c = 0; c < mesh.numCells(); ++c) {
    const std::int64_t m = mesh.cellSize(c);
    const std::int64_t* ids = mesh.cell(c);
    if (m == 2) addEdge(ids[0], ids[1]);
    else if (m >= 3)
      for (std::int64_t k = 0; k < m; ++k) addEdge(ids[k], ids[(k + 1) % m]);
  }
  for (auto& nb : nbrs) {
    std::sort(nb.begin(), nb.end());
    nb.erase(std::unique(nb.begin(), nb.end()), nb.end());
  }

  CutMapper mapper(surf, tris, nbrs, mesh.points, moved, foot);
  SurfacePoints P;
  std::string why;
  bool ok = mapper.Direct(P, why);
  std::string directWhy = why;
  if (!ok && options.localRepair && mapper.LocalRepair(options.maxRelaxIterations, P, why)) {
    ok = true;
    r.intermediarySteps = 1; // S itself is the only surface used
  }
  if (!ok) {
    for (int T : options.stepSchedules) {
      if (T < 1) continue;
      if (mapper.Intermediary(T, options.maxRelaxIterations, P, why)) {
        ok = true;
        r.intermediarySteps = T;
        break;
      }
    }
  }
  if (!ok) {
    std::string hint = "Try a smaller cut, a larger ROI, a finer mesh or a smoother surface";
    std::int64_t nearMoved = 0, example = -1;
    for (std::int64_t b : boundaryOnSide)
      for (std::int64_t j : nbrs[b])
        if (moved[j]) {
          ++nearMoved;
          if (example < 0) example = b;
          break;
        }
    if (nearMoved > 0)
      hint = std::to_string(nearMoved) + " ROIBoundary vertices (which never move) lie on the " +
             (options.operation == CutOperation::Cut ? "cut" : "fill") +
             " side next to moved vertices (e.g. vertex " + std::to_string(example) + " at " +
             Pt(mesh.points.row(example).transpose()) +
             "): enlarge the ROI so that its boundary stays on the other side of the surface";
    return Status::Error("the cut could not be mapped onto the surface without folding the mesh: direct "
                         "projection gave " + directWhy + "; after the intermediary surfaces " + why +
                         ". " + hint);
  }

  const std::vector<Vector2d>& uv = mapper.Parameters();
  for (std::int64_t i = 0; i < n; ++i) {
    if (!moved[i]) continue;
    r.points.row(i) = P.row(i);
    r.displacement.row(i) = P.row(i) - mesh.points.row(i);
    r.parameters[i] = uv[i];
    r.maxDistanceToSurface = std::max(
        r.maxDistanceToSurface, (P.row(i).transpose() - surf.Evaluate(uv[i].x(), uv[i].y())).norm());
  }
  if (r.intermediarySteps > 0) r.mappingNote = "direct projection would fold the mesh (" + directWhy + ")";
  result = std::move(r);
  return Status::Ok();
}

} // namespace faceplan
