// SPDX-License-Identifier: BSD-3-Clause
#include "BezierCut/CutMapping.h"

#include "BezierCut/MeshIntersection.h"

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

#include <algorithm>
#include <cmath>
#include <limits>

namespace faceplan {

using Eigen::Vector2d;
using Eigen::Vector3d;

namespace {

Vector3d AreaVector(const Tri& t, const RowVectors3d& P) {
  const Vector3d a = P.row(t.v[0]).transpose(), b = P.row(t.v[1]).transpose(),
                 c = P.row(t.v[2]).transpose();
  return 0.5 * (b - a).cross(c - a);
}

double Quality(const Tri& t, const RowVectors3d& P) {
  const Vector3d a = P.row(t.v[0]).transpose(), b = P.row(t.v[1]).transpose(),
                 c = P.row(t.v[2]).transpose();
  const double l2 = (b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm();
  if (!(l2 > 0))
    return 0;
  return 4.0 * std::sqrt(3.0) * (0.5 * (b - a).cross(c - a).norm()) / l2;
}

enum class TriState { Ok, Degenerate, Flipped, Squashed };

class CutMapper {
public:
  CutMapper(const BezierSurface& surf, const std::vector<Tri>& tris,
            const std::vector<std::vector<std::int64_t>>& nbrs, const RowVectors3d& X0,
            const std::vector<std::uint8_t>& moved, const std::vector<Vector2d>& foot)
      : surface_(surf), tris_(tris), nbrs_(nbrs), original_(X0), moved_(moved), foot_(foot) {
    for (std::size_t t = 0; t < tris_.size(); ++t) {
      int m = 0;
      for (int k = 0; k < 3; ++k)
        m += moved_[tris_[t].v[k]];
      if (m > 0) {
        touched_.push_back(std::int64_t(t));
        a0_.push_back(AreaVector(tris_[t], original_));
        q0_.push_back(Quality(tris_[t], original_));
        full_.push_back(m == 3);
      }
    }
    for (std::size_t i = 0; i < moved_.size(); ++i)
      if (moved_[i])
        movedIds_.push_back(std::int64_t(i));
    incident_.assign(moved_.size(), {});
    for (std::size_t k = 0; k < touched_.size(); ++k)
      for (int j = 0; j < 3; ++j) {
        const std::int64_t v = tris_[touched_[k]].v[j];
        if (moved_[v])
          incident_[v].push_back(std::int64_t(k));
      }
    // Expected orientation of the moved region within S.
    double s = 0;
    for (std::size_t k = 0; k < touched_.size(); ++k) {
      if (!full_[k])
        continue;
      const Tri& t = tris_[touched_[k]];
      Vector3d n = Vector3d::Zero();
      for (int j = 0; j < 3; ++j)
        n += surface_.unitNormal(foot_[t.v[j]].x(), foot_[t.v[j]].y());
      s += a0_[k].dot(n);
    }
    sigma_ = s < 0 ? -1.0 : 1.0;
    // The rim: moved vertices next to unmoved ones. Their direct projection keeps the direction
    // of their edges, which keeps the steep triangles joining them to the unmoved bone oriented, so
    // relaxation only moves them when they are part of a bad triangle themselves.
    rim_.assign(moved_.size(), 0);
    for (std::int64_t i : movedIds_)
      for (std::int64_t j : nbrs_[i])
        if (!moved_[j])
          rim_[i] = 1;
    activeTri_.assign(tris_.size(), 0);
    for (std::int64_t t : touched_)
      activeTri_[t] = 1;
  }

  // Direct projection.
  bool direct(RowVectors3d& P, std::string& why) {
    uv_ = foot_;
    P = original_;
    for (std::int64_t i : movedIds_)
      P.row(i) = surface_.evaluate(uv_[i].x(), uv_[i].y()).transpose();
    return finalCheck(P, nullptr, why);
  }

  // Local repair on S itself: relax growing neighbourhoods of the bad triangles of the direct
  // projection (the rest keeps its direct projection).
  bool localRepair(int maxRelax, RowVectors3d& P, std::string& why) {
    uv_ = foot_;
    P = original_;
    resetRegion();
    for (std::int64_t i : movedIds_)
      place(P, i, 1.0);
    std::vector<std::int64_t> bad;
    if (untangle(P, 200) && finalCheck(P, nullptr, why))
      return true;
    // Harmonic relaxation of growing neighbourhoods, each followed by untangling.
    uv_ = foot_;
    for (std::int64_t i : movedIds_)
      place(P, i, 1.0);
    for (int iter = 0; iter < maxRelax; ++iter) {
      if (finalCheck(P, &bad, why))
        return true;
      if (!relax(P, bad, 1.0, 1 << std::min(iter, 20)))
        break;
      untangle(P, 100);
    }
    return finalCheck(P, nullptr, why);
  }

  // Signed size of touched triangle k with its current points, relative to its original area:
  // for a triangle whose vertices all moved, sigma * (area vector . normal) / |a0|, with the unit
  // normal of S at the (u,v) of the vertex being optimised; for the others,
  // (area vector . a0) / |a0|^2. Positive = correctly oriented.
  double signedSize(std::size_t k, const RowVectors3d& P, const Vector3d& normal) const {
    const double A0 = a0_[k].norm();
    if (!(A0 > 0))
      return 1.0;
    const Vector3d a1 = AreaVector(tris_[touched_[k]], P);
    if (full_[k])
      return sigma_ * a1.dot(normal) / A0;
    return a1.dot(a0_[k]) / (A0 * A0);
  }

  // Untangling: each moved vertex of a flipped or degenerate triangle (and its moved neighbours)
  // moves within S to maximise the smallest signed size of its triangles (pattern search in
  // (u,v)). Returns true when no triangle is flipped or degenerate any more. Sweeps stop early
  // when they cannot help: two sweeps in a row that move no vertex (the odd and even sweep differ
  // in the vertices they visit; after both, every later sweep would repeat them), or
  // kStagnantSweeps sweeps without fewer bad triangles than the fewest seen (the searches then
  // only shuffle vertices around the same tangle; relaxation or intermediary surfaces follow).
  bool untangle(RowVectors3d& P, int maxSweeps) {
    constexpr int kStagnantSweeps = 16;
    std::vector<std::int64_t> bad, verts;
    std::vector<std::uint8_t> mark(moved_.size(), 0);
    std::size_t fewestBad = std::numeric_limits<std::size_t>::max();
    int sinceFewest = 0;
    bool previousMovedNone = false;
    for (int sweep = 0; sweep < maxSweeps; ++sweep) {
      collectBad(P, a0_, false, true, bad);
      if (bad.empty())
        return true;
      if (bad.size() < fewestBad) {
        fewestBad = bad.size();
        sinceFewest = 0;
      } else if (++sinceFewest >= kStagnantSweeps) {
        break;
      }
      verts.clear();
      for (std::int64_t tr : bad)
        for (int j = 0; j < 3; ++j) {
          const std::int64_t v = tris_[tr].v[j];
          if (!moved_[v])
            continue;
          if (!mark[v]) {
            mark[v] = 1;
            verts.push_back(v);
          }
          if (sweep % 2 == 1)
            for (std::int64_t w : nbrs_[v])
              if (moved_[w] && !mark[w]) {
                mark[w] = 1;
                verts.push_back(w);
              }
        }
      bool movedNone = true;
      for (std::int64_t v : verts) {
        mark[v] = 0;
        if (optimizeVertex(P, v))
          movedNone = false;
      }
      if (movedNone && previousMovedNone)
        break;
      previousMovedNone = movedNone;
    }
    collectBad(P, a0_, false, true, bad);
    return bad.empty();
  }

  // Returns true when the vertex moved.
  bool optimizeVertex(RowVectors3d& P, std::int64_t i) {
    ++vertexSearches_;
    // One normal per trial position, shared by the vertex's triangles.
    auto worst = [&]() {
      const Vector3d normal = surface_.unitNormal(uv_[i].x(), uv_[i].y());
      double w = std::numeric_limits<double>::infinity();
      for (std::int64_t k : incident_[i])
        w = std::min(w, signedSize(std::size_t(k), P, normal));
      return w;
    };
    double h = 0;
    for (std::int64_t j : nbrs_[i])
      h += ((moved_[j] ? uv_[j] : foot_[j]) - uv_[i]).norm();
    h = nbrs_[i].empty() ? 1e-3 : 0.5 * h / double(nbrs_[i].size());
    if (!(h > 1e-12))
      h = 1e-3;
    double best = worst();
    const Vector2d startUV = uv_[i];
    Vector2d bestUV = startUV;
    static const double dirs[8][2] = {{1, 0},
                                      {-1, 0},
                                      {0, 1},
                                      {0, -1},
                                      {0.7071, 0.7071},
                                      {-0.7071, 0.7071},
                                      {0.7071, -0.7071},
                                      {-0.7071, -0.7071}};
    for (int it = 0; it < 40 && h > 1e-9; ++it) {
      bool improved = false;
      const Vector2d base = bestUV;
      for (const auto& d : dirs) {
        uv_[i] = Vector2d(Clamp01(base.x() + h * d[0]), Clamp01(base.y() + h * d[1]));
        place(P, i, 1.0);
        const double w = worst();
        if (w > best) {
          best = w;
          bestUV = uv_[i];
          improved = true;
        }
      }
      if (!improved)
        h *= 0.5;
    }
    uv_[i] = bestUV;
    place(P, i, 1.0);
    return bestUV != startUV;
  }

  // Mapping through T intermediary surfaces.
  bool intermediary(int T, int maxRelax, RowVectors3d& P, std::string& why) {
    uv_ = foot_;
    P = original_;
    resetRegion();
    std::vector<Vector3d> prev = a0_;
    std::vector<std::int64_t> bad;
    for (int s = 1; s <= T; ++s) {
      const double t = double(s) / T;
      for (std::int64_t i : movedIds_)
        place(P, i, t);
      if (s < T) {
        for (int iter = 0; iter < maxRelax; ++iter) {
          collectBad(P, prev, true, false, bad);
          if (bad.empty() || !relax(P, bad, t, 1 << std::min(iter, 20)))
            break;
        }
        for (std::size_t k = 0; k < touched_.size(); ++k)
          prev[k] = AreaVector(tris_[touched_[k]], P);
      }
    }
    // Last surface (t = 1): the final criteria, intersections included.
    for (int iter = 0; iter < maxRelax; ++iter) {
      if (finalCheck(P, &bad, why))
        return true;
      if (!relax(P, bad, 1.0, 1 << std::min(iter, 20)))
        break;
    }
    return finalCheck(P, nullptr, why);
  }

  const std::vector<Vector2d>& parameters() const { return uv_; }
  std::int64_t vertexSearches() const { return vertexSearches_; }

  void resetRegion() {
    region_.clear();
    inRegion_.assign(moved_.size(), 0);
    solvedOnce_ = false;
  }

private:
  void place(RowVectors3d& P, std::int64_t i, double t) const {
    const Vector3d s = surface_.evaluate(uv_[i].x(), uv_[i].y());
    if (t >= 1.0)
      P.row(i) = s.transpose();
    else
      P.row(i) = ((1.0 - t) * original_.row(i).transpose() + t * s).transpose();
  }

  TriState state(std::size_t k, const RowVectors3d& P, const Vector3d& ref, bool finalStage,
                 bool quality) const {
    const Tri& t = tris_[touched_[k]];
    const double A0 = a0_[k].norm();
    if (!(A0 > 0))
      return TriState::Ok; // degenerate before: not ours to judge
    const Vector3d a1 = AreaVector(t, P);
    if (!(a1.norm() > 1e-8 * A0))
      return TriState::Degenerate;
    if (finalStage && full_[k]) {
      Vector3d n = Vector3d::Zero();
      for (int j = 0; j < 3; ++j)
        n += surface_.unitNormal(uv_[t.v[j]].x(), uv_[t.v[j]].y());
      if (!(sigma_ * a1.dot(n) > 0))
        return TriState::Flipped;
    } else if (!(a1.dot(ref) > 0)) {
      return TriState::Flipped;
    }
    if (quality && Quality(t, P) < 0.2 * q0_[k])
      return TriState::Squashed;
    return TriState::Ok;
  }

  void collectBad(const RowVectors3d& P, const std::vector<Vector3d>& ref, bool quality,
                  bool finalStage, std::vector<std::int64_t>& bad) const {
    bad.clear();
    for (std::size_t k = 0; k < touched_.size(); ++k)
      if (state(k, P, ref[k], finalStage, quality) != TriState::Ok)
        bad.push_back(touched_[k]);
  }

  bool finalCheck(const RowVectors3d& P, std::vector<std::int64_t>* badOut,
                  std::string& why) const {
    std::vector<std::int64_t> bad;
    std::int64_t flipped = 0, degenerate = 0;
    for (std::size_t k = 0; k < touched_.size(); ++k) {
      const TriState s = state(k, P, a0_[k], true, false);
      if (s == TriState::Ok)
        continue;
      bad.push_back(touched_[k]);
      (s == TriState::Degenerate ? degenerate : flipped)++;
    }
    if (bad.empty()) {
      bad = NewIntersections(tris_, original_, P, activeTri_);
      if (!bad.empty())
        why = std::to_string(bad.size()) +
              " triangles intersect other triangles (first: triangle " +
              std::to_string(bad.front()) + " of the fan triangulation)";
    } else {
      why = std::to_string(flipped) + " triangles flipped and " + std::to_string(degenerate) +
            " degenerate (first: triangle " + std::to_string(bad.front()) + ")";
    }
    if (badOut)
      *badOut = bad;
    return bad.empty();
  }

  // Tangential relaxation within the intermediary surface at t: the moved vertices of `bad`
  // triangles join the relaxed region, which then grows by `rings` rings of moved neighbours; the
  // region's (u,v) are replaced by the solution of the uniform graph Laplace equation (a Tutte /
  // harmonic map: every vertex at the average of its neighbours), with Dirichlet values from the
  // vertices around the region (the (u,v) of other moved vertices, the foot points of unmoved
  // ones). Returns false when the region did not change (nothing more to gain).
  bool relax(RowVectors3d& P, const std::vector<std::int64_t>& bad, double t, int rings) {
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
      if (region_.size() == end)
        break;
      begin = 0; // grow from the whole region each ring
    }
    const bool grew = region_.size() != before || !solvedOnce_;
    if (!grew)
      return false;
    solvedOnce_ = true;

    const std::size_t m = region_.size();
    std::vector<std::int64_t> index(moved_.size(), -1);
    for (std::size_t k = 0; k < m; ++k)
      index[region_[k]] = std::int64_t(k);
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
    if (solver.info() != Eigen::Success)
      return false;
    const Eigen::MatrixX2d sol = solver.solve(rhs);
    if (solver.info() != Eigen::Success || !sol.allFinite())
      return false;
    for (std::size_t k = 0; k < m; ++k) {
      const std::int64_t i = region_[k];
      uv_[i] = Vector2d(Clamp01(sol(Eigen::Index(k), 0)), Clamp01(sol(Eigen::Index(k), 1)));
      place(P, i, t);
    }
    return true;
  }

  const BezierSurface& surface_;
  const std::vector<Tri>& tris_;
  const std::vector<std::vector<std::int64_t>>& nbrs_;
  const RowVectors3d& original_;
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
  std::vector<std::vector<std::int64_t>>
      incident_; // touched triangles (indices into touched_) per moved vertex
  bool solvedOnce_ = false;
  double sigma_ = 1.0;
  std::int64_t vertexSearches_ = 0;
};

} // namespace

CutMapping MapCutOntoSurface(const BezierSurface& surface, const SurfaceMesh& mesh,
                             const std::vector<Tri>& triangles,
                             const std::vector<std::vector<std::int64_t>>& neighbours,
                             const std::vector<std::uint8_t>& moved,
                             const std::vector<Vector2d>& footParameters,
                             const CutMappingOptions& options) {
  CutMapper mapper(surface, triangles, neighbours, mesh.points, moved, footParameters);
  CutMapping m;
  m.ok = mapper.direct(m.points, m.directProblem);
  m.problem = m.directProblem;
  if (!m.ok && options.localRepair &&
      mapper.localRepair(options.maxRelaxIterations, m.points, m.problem)) {
    m.ok = true;
    m.intermediarySteps = 1; // S itself is the only surface used
  }
  if (!m.ok) {
    for (int T : options.stepSchedules) {
      if (T < 1)
        continue;
      if (mapper.intermediary(T, options.maxRelaxIterations, m.points, m.problem)) {
        m.ok = true;
        m.intermediarySteps = T;
        break;
      }
    }
  }
  m.parameters = mapper.parameters();
  m.repairVertexSearches = mapper.vertexSearches();
  return m;
}

} // namespace faceplan
