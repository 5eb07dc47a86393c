// SPDX-License-Identifier: BSD-3-Clause
#include "Mesh/MeshValidation.h"

#include "Common/GroupByKey.h"
#include "Common/ParallelFor.h"

#include "Mesh/TetGeometry.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <sstream>

namespace faceplan {

namespace {

// Lists the first few ids and the count, so a message stays readable on a large mesh.
std::string IdList(const std::vector<long long>& ids) {
  std::ostringstream out;
  const size_t shown = std::min<size_t>(ids.size(), 10);
  for (size_t k = 0; k < shown; ++k)
    out << (k ? ", " : "") << ids[k];
  if (ids.size() > shown)
    out << ", ... (" << ids.size() << " in all)";
  return out.str();
}

int FindRoot(std::vector<int>& parent, int i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

} // namespace

Status ValidateMeshAndMaterials(const TetMesh& mesh, const Materials& materials) {
  const Eigen::Index n = mesh.numPoints(), m = mesh.numTets();
  if (m == 0)
    return Status::Error("the mesh has no tetrahedra");
  if (!mesh.points.allFinite()) {
    std::vector<long long> bad;
    for (Eigen::Index i = 0; i < n; ++i)
      if (!mesh.points.row(i).allFinite())
        bad.push_back(i);
    return Status::Error("non-finite (NaN or infinite) coordinates at points " + IdList(bad));
  }
  std::vector<long long> outOfRange;
  for (Eigen::Index e = 0; e < m; ++e)
    for (int k = 0; k < 4; ++k)
      if (mesh.tets(e, k) < 0 || mesh.tets(e, k) >= n)
        outOfRange.push_back(e);
  if (!outOfRange.empty())
    return Status::Error("tetrahedra reference points that do not exist: cells " +
                         IdList(outOfRange));

  auto checkSize = [m](const Eigen::VectorXd& v, const char* what, bool optional) -> std::string {
    if (optional && v.size() == 0)
      return {};
    if (v.size() != 1 && v.size() != m)
      return std::string(what) + " must have 1 or " + std::to_string(m) + " values, not " +
             std::to_string(v.size());
    return {};
  };
  for (auto msg : {checkSize(materials.youngsModulus, "Young's modulus", false),
                   checkSize(materials.poissonRatio, "Poisson ratio", false),
                   checkSize(materials.density, "density", true)})
    if (!msg.empty())
      return Status::Error(msg);
  if (!materials.smallStrain.empty() &&
      static_cast<Eigen::Index>(materials.smallStrain.size()) != m)
    return Status::Error("the small-strain cell flags must have " + std::to_string(m) +
                         " values or none, not " + std::to_string(materials.smallStrain.size()));

  std::vector<long long> badE, badNu;
  for (Eigen::Index e = 0; e < materials.youngsModulus.size(); ++e)
    if (!(materials.youngsModulus[e] > 0.0) || !std::isfinite(materials.youngsModulus[e]))
      badE.push_back(e);
  for (Eigen::Index e = 0; e < materials.poissonRatio.size(); ++e)
    if (!(materials.poissonRatio[e] > -1.0 && materials.poissonRatio[e] < 0.5))
      badNu.push_back(e);
  if (!badE.empty())
    return Status::Error("Young's modulus must be positive and finite (E <= 0 or NaN in cells " +
                         IdList(badE) + ")");
  if (!badNu.empty())
    return Status::Error("Poisson ratio must lie in (-1, 0.5) (violated in cells " + IdList(badNu) +
                         ")");

  // A volume is "zero" relative to the cube of the mesh's edge scale.
  const double scale = (mesh.points.colwise().maxCoeff() - mesh.points.colwise().minCoeff()).norm();
  const double zeroVolume = 1e-14 * scale * scale * scale / static_cast<double>(m);
  std::vector<long long> inverted, flat;
  TetCorners corners;
  for (Eigen::Index e = 0; e < m; ++e) {
    for (int k = 0; k < 4; ++k)
      corners.row(k) = mesh.points.row(mesh.tets(e, k));
    const double v = TetVolume(corners);
    if (v < -zeroVolume)
      inverted.push_back(e);
    else if (v <= zeroVolume)
      flat.push_back(e);
  }
  if (!inverted.empty() || !flat.empty()) {
    std::string msg = "tetrahedra with non-positive volume:";
    if (!flat.empty())
      msg += " zero-volume cells " + IdList(flat) + ";";
    if (!inverted.empty())
      msg += " inverted cells " + IdList(inverted) + ";";
    return Status::Error(msg);
  }
  return Status::Ok();
}

int ConnectedComponents(const TetMesh& mesh, std::vector<int>& componentOfNode) {
  const Eigen::Index n = mesh.numPoints();
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<char> used(n, 0);
  for (Eigen::Index e = 0; e < mesh.numTets(); ++e) {
    const int r0 = FindRoot(parent, mesh.tets(e, 0));
    used[mesh.tets(e, 0)] = 1;
    for (int k = 1; k < 4; ++k) {
      used[mesh.tets(e, k)] = 1;
      const int rk = FindRoot(parent, mesh.tets(e, k));
      if (rk != r0)
        parent[rk] = r0;
    }
  }
  componentOfNode.assign(n, -1);
  std::vector<int> label(n, -1);
  int count = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!used[i])
      continue;
    const int root = FindRoot(parent, static_cast<int>(i));
    if (label[root] < 0)
      label[root] = count++;
    componentOfNode[i] = label[root];
  }
  return count;
}

Status CheckEveryComponentConstrained(const TetMesh& mesh, const std::vector<int>& constrained) {
  if (constrained.empty())
    return Status::Error("no constrained node: the tissue is tied to nothing, so its stiffness "
                         "matrix is singular");
  std::vector<int> component;
  const int count = ConnectedComponents(mesh, component);
  std::vector<char> held(count, 0);
  for (int node : constrained)
    if (node >= 0 && node < mesh.numPoints() && component[node] >= 0)
      held[component[node]] = 1;
  for (int c = 0; c < count; ++c) {
    if (held[c])
      continue;
    long long cells = 0;
    Eigen::RowVector3d lo = Eigen::RowVector3d::Constant(INFINITY), hi = -lo;
    for (Eigen::Index e = 0; e < mesh.numTets(); ++e) {
      if (component[mesh.tets(e, 0)] != c)
        continue;
      ++cells;
      for (int k = 0; k < 4; ++k) {
        lo = lo.cwiseMin(mesh.points.row(mesh.tets(e, k)));
        hi = hi.cwiseMax(mesh.points.row(mesh.tets(e, k)));
      }
    }
    std::ostringstream out;
    out << "a free piece of the mesh is attached to no constrained node (component " << c << " of "
        << count << ": " << cells << " cells, bounds [" << lo(0) << ", " << hi(0) << "] x ["
        << lo(1) << ", " << hi(1) << "] x [" << lo(2) << ", " << hi(2)
        << "]); tie it to bone or remove it, or its stiffness matrix is singular";
    return Status::Error(out.str());
  }
  return Status::Ok();
}

double TetMeanRatio(const Eigen::Matrix<double, 4, 3>& c) {
  const double v = std::abs(TetVolume(c));
  double sum = 0.0;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j)
      sum += (c.row(i) - c.row(j)).squaredNorm();
  if (!(sum > 0.0))
    return 0.0;
  return 12.0 * std::cbrt(3.0 * v * 3.0 * v) / sum;
}

std::string CheckElementQuality(const TetMesh& mesh, double threshold, QualityReport* out) {
  QualityReport report;
  // One chunk of cells per core; merged in chunk order, so the worst cell (the first of the lowest
  // quality) and the low list are those of one pass in cell order.
  struct Chunk {
    double worst = 1.0;
    long long worstCell = -1;
    std::vector<std::pair<double, long long>> low;
  };
  const std::int64_t chunks = mesh.numTets() < 20000 ? 1 : WorkerThreads(16);
  std::vector<Chunk> found(chunks);
  const std::int64_t perChunk = (mesh.numTets() + chunks - 1) / chunks;
  ParallelFor(chunks, 2, [&](std::int64_t c0, std::int64_t c1) {
    for (std::int64_t c = c0; c < c1; ++c) {
      TetCorners corners;
      Chunk& chunk = found[c];
      const Eigen::Index end = std::min<Eigen::Index>(mesh.numTets(), (c + 1) * perChunk);
      for (Eigen::Index e = c * perChunk; e < end; ++e) {
        for (int k = 0; k < 4; ++k)
          corners.row(k) = mesh.points.row(mesh.tets(e, k));
        const double q = TetMeanRatio(corners);
        if (q < chunk.worst) {
          chunk.worst = q;
          chunk.worstCell = e;
        }
        if (q < threshold)
          chunk.low.push_back({q, e});
      }
    }
  });
  std::vector<std::pair<double, long long>> low;
  for (const Chunk& chunk : found) {
    if (chunk.worstCell >= 0 && chunk.worst < report.worstQuality) {
      report.worstQuality = chunk.worst;
      report.worstCell = chunk.worstCell;
    }
    low.insert(low.end(), chunk.low.begin(), chunk.low.end());
  }
  report.belowThreshold = static_cast<long long>(low.size());
  const size_t shown = std::min<size_t>(low.size(), 10);
  std::partial_sort(low.begin(), low.begin() + shown, low.end());
  for (size_t k = 0; k < shown; ++k)
    report.worstIds.push_back(low[k].second);
  std::string warning;
  if (!low.empty()) {
    std::ostringstream msg;
    msg.precision(3);
    msg << low.size() << " sliver tetrahedra with mean-ratio quality below " << threshold
        << " (worst " << report.worstQuality << " in cell " << report.worstCell << "; worst cells "
        << IdList(report.worstIds) << "); the solve is exact, but stresses there are unreliable";
    warning = msg.str();
  }
  if (out)
    *out = report;
  return warning;
}

void AddCellDeformation(DeformationReport& report, long long cell,
                        const Eigen::Matrix3d& gradient) {
  ++report.cellsChecked;
  const double norm = gradient.norm();
  if (norm <= report.largestStrain && norm < 1.0)
    return;
  const Eigen::Matrix3d strain = 0.5 * (gradient + gradient.transpose());
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(strain, Eigen::EigenvaluesOnly);
  const double largest = eig.eigenvalues().cwiseAbs().maxCoeff();
  if (largest > report.largestStrain) {
    report.largestStrain = largest;
    report.largestStrainCell = cell;
  }
  if (!((Eigen::Matrix3d::Identity() + gradient).determinant() > 0.0))
    report.invertedCells.push_back(cell);
}

void AppendDeformationWarnings(const DeformationReport& report, double strainLimit,
                               std::vector<std::string>& warnings) {
  if (report.largestStrain > strainLimit) {
    std::ostringstream msg;
    msg.precision(3);
    msg << "the tissue is stretched or compressed by up to " << 100.0 * report.largestStrain
        << "% (largest strain, cell " << report.largestStrainCell << "), beyond the "
        << 100.0 * strainLimit
        << "% small-strain range of linear FEM: this result is only qualitative";
    warnings.push_back(msg.str());
  }
  if (!report.invertedCells.empty())
    warnings.push_back(std::to_string(report.invertedCells.size()) +
                       " tetrahedra are inverted in the deformed result (cells " +
                       IdList(report.invertedCells) +
                       "): the displacement is too large for linear FEM");
}

DeformationReport CheckDeformation(
    const TetMesh& mesh, const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>& u,
    std::vector<std::string>& warnings, double strainLimit, const std::vector<int>* cells) {
  DeformationReport report;
  const Eigen::Index count = cells ? static_cast<Eigen::Index>(cells->size()) : mesh.numTets();
  if (u.rows() < mesh.numPoints())
    return report;
  for (Eigen::Index k = 0; k < count; ++k) {
    const Eigen::Index e = cells ? (*cells)[k] : k;
    Eigen::Matrix3d edges, du;
    for (int j = 0; j < 3; ++j) {
      edges.col(j) =
          (mesh.points.row(mesh.tets(e, j + 1)) - mesh.points.row(mesh.tets(e, 0))).transpose();
      du.col(j) = (u.row(mesh.tets(e, j + 1)) - u.row(mesh.tets(e, 0))).transpose();
    }
    if (!(edges.determinant() > 0.0))
      continue;
    AddCellDeformation(report, e, du * edges.inverse());
  }
  AppendDeformationWarnings(report, strainLimit, warnings);
  return report;
}

std::vector<SharedFace> SharedFaces(const TetMesh& mesh) {
  using Face = std::pair<std::array<int, 3>, int>;
  const Eigen::Index m = mesh.numTets();
  std::vector<Face> faces(static_cast<size_t>(m) * 4);
  ParallelFor(m, 50000, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t e = begin; e < end; ++e)
      for (int k = 0; k < 4; ++k) {
        std::array<int, 3> f;
        for (int j = 0, t = 0; j < 4; ++j)
          if (j != k)
            f[t++] = mesh.tets(e, j);
        std::sort(f.begin(), f.end());
        faces[e * 4 + k] = {f, static_cast<int>(e)};
      }
  });
  // Sorted in buckets of the smallest vertex, one per thread: equal faces share a bucket, and the
  // buckets in order are the whole sort (the same order as one sort, on every core).
  const std::int64_t buckets = faces.size() < 200000 ? 1 : WorkerThreads(16);
  const std::int64_t points = std::max<std::int64_t>(1, mesh.numPoints());
  auto bucketOf = [&](const Face& f) {
    return std::clamp<std::int64_t>(f.first[0] * buckets / points, 0, buckets - 1);
  };
  std::vector<size_t> start(static_cast<size_t>(buckets) + 1, 0);
  for (const Face& f : faces)
    ++start[bucketOf(f) + 1];
  for (std::int64_t b = 0; b < buckets; ++b)
    start[b + 1] += start[b];
  std::vector<Face> sorted(faces.size());
  {
    std::vector<size_t> fill(start.begin(), start.end() - 1);
    for (const Face& f : faces)
      sorted[fill[bucketOf(f)]++] = f;
  }
  faces = std::vector<Face>();
  ParallelFor(buckets, 2, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t b = begin; b < end; ++b)
      std::sort(sorted.begin() + start[b], sorted.begin() + start[b + 1]);
  });
  std::vector<SharedFace> shared;
  for (size_t k = 1; k < sorted.size(); ++k)
    if (sorted[k].first == sorted[k - 1].first)
      shared.push_back({sorted[k].first, sorted[k - 1].second, sorted[k].second});
  return shared;
}

std::string CheckFoldedFaces(const TetMesh& mesh, const std::vector<SharedFace>& shared,
                             FoldReport* out) {
  FoldReport report;
  auto opposite = [&](int cell, const std::array<int, 3>& f) {
    for (int j = 0; j < 4; ++j) {
      const int v = mesh.tets(cell, j);
      if (v != f[0] && v != f[1] && v != f[2])
        return v;
    }
    return -1;
  };
  for (const SharedFace& s : shared) {
    const Eigen::Vector3d p = mesh.points.row(s.face[0]).transpose();
    const Eigen::Vector3d n = (mesh.points.row(s.face[1]).transpose() - p)
                                  .cross(mesh.points.row(s.face[2]).transpose() - p);
    const int va = opposite(s.a, s.face), vb = opposite(s.b, s.face);
    if (va < 0 || vb < 0 || va == vb)
      continue; // repeated ids: refused by the mesh validation
    const double sa = n.dot(mesh.points.row(va).transpose() - p);
    const double sb = n.dot(mesh.points.row(vb).transpose() - p);
    if (sa * sb > 0.0) {
      ++report.foldedFaces;
      if (report.cells.size() < 10) {
        report.cells.push_back(s.a);
        report.cells.push_back(s.b);
      }
    }
  }
  std::string warning;
  if (report.foldedFaces > 0) {
    std::ostringstream msg;
    msg << report.foldedFaces
        << " pairs of tetrahedra that share a face lie on the same side of it "
        << "(cells " << IdList(report.cells)
        << "): they overlap, so the mesh folds over itself there and results near them are "
           "unreliable";
    warning = msg.str();
  }
  if (out)
    *out = report;
  return warning;
}

Status CheckRigidModesHeld(const TetMesh& mesh, const std::vector<int>& constrained) {
  return CheckRigidModesHeld(mesh, constrained, SharedFaces(mesh));
}

Status CheckRigidModesHeld(const TetMesh& mesh, const std::vector<int>& constrained,
                           const std::vector<SharedFace>& shared) {
  const Eigen::Index n = mesh.numPoints(), m = mesh.numTets();
  // Face-connected pieces: union cells that share a triangle.
  std::vector<int> parent(m);
  std::iota(parent.begin(), parent.end(), 0);
  for (const SharedFace& f : shared) {
    const int a = FindRoot(parent, f.a), b = FindRoot(parent, f.b);
    if (a != b)
      parent[a] = b;
  }
  std::vector<int> pieceOf(m), label(m, -1);
  int pieces = 0;
  for (Eigen::Index e = 0; e < m; ++e) {
    const int r = FindRoot(parent, static_cast<int>(e));
    if (label[r] < 0)
      label[r] = pieces++;
    pieceOf[e] = label[r];
  }
  if (pieces == 0)
    return Status::Ok();
  // Each piece's nodes, ascending: cells grouped by piece, nodes deduplicated with a stamp per
  // node, then the (much shorter) lists sorted.
  const Groups cellsOf = GroupByKey(m, pieces, [&](std::int64_t e) { return pieceOf[e]; });
  std::vector<std::vector<int>> nodesOf(pieces);
  std::vector<int> stamp(n, -1);
  for (int p = 0; p < pieces; ++p) {
    for (int k = cellsOf.start[p]; k < cellsOf.start[p + 1]; ++k)
      for (int j = 0; j < 4; ++j) {
        const int v = mesh.tets(cellsOf.items[k], j);
        if (v >= 0 && v < n && stamp[v] != p) {
          stamp[v] = p;
          nodesOf[p].push_back(v);
        }
      }
    std::sort(nodesOf[p].begin(), nodesOf[p].end());
  }
  const double scale = (mesh.points.colwise().maxCoeff() - mesh.points.colwise().minCoeff()).norm();
  // True when the held nodes among `nodes` include three non-collinear points.
  std::vector<char> held(n, 0);
  for (int i : constrained)
    if (i >= 0 && i < n)
      held[i] = 1;
  auto spans = [&](const std::vector<int>& nodes) {
    int first = -1, second = -1;
    double farthest = 0.0;
    for (int i : nodes) {
      if (!held[i])
        continue;
      if (first < 0) {
        first = i;
        continue;
      }
      const double d = (mesh.points.row(i) - mesh.points.row(first)).norm();
      if (d > farthest) {
        farthest = d;
        second = i;
      }
    }
    if (second < 0 || farthest <= 1e-9 * scale)
      return false;
    const Eigen::RowVector3d axis = (mesh.points.row(second) - mesh.points.row(first)) / farthest;
    for (int i : nodes) {
      if (!held[i])
        continue;
      const Eigen::RowVector3d d = mesh.points.row(i) - mesh.points.row(first);
      if ((d - d.dot(axis) * axis).norm() > 1e-6 * farthest)
        return true;
    }
    return false;
  };
  std::vector<char> pieceHeld(pieces, 0);
  for (bool changed = true; changed;) {
    changed = false;
    for (int p = 0; p < pieces; ++p) {
      if (pieceHeld[p] || !spans(nodesOf[p]))
        continue;
      pieceHeld[p] = 1;
      changed = true;
      for (int i : nodesOf[p])
        held[i] = 1; // a held piece holds the nodes it shares
    }
  }
  for (int p = 0; p < pieces; ++p) {
    if (pieceHeld[p])
      continue;
    long long cells = 0;
    Eigen::RowVector3d lo = Eigen::RowVector3d::Constant(INFINITY), hi = -lo;
    for (Eigen::Index e = 0; e < m; ++e) {
      if (pieceOf[e] != p)
        continue;
      ++cells;
      for (int k = 0; k < 4; ++k) {
        lo = lo.cwiseMin(mesh.points.row(mesh.tets(e, k)));
        hi = hi.cwiseMax(mesh.points.row(mesh.tets(e, k)));
      }
    }
    int heldNodes = 0;
    for (int i : nodesOf[p])
      heldNodes += held[i];
    std::ostringstream out;
    out << "a piece of the mesh can move rigidly (piece " << p << " of " << pieces
        << " face-connected pieces: " << cells << " cells, bounds [" << lo(0) << ", " << hi(0)
        << "] x [" << lo(1) << ", " << hi(1) << "] x [" << lo(2) << ", " << hi(2)
        << "]); it is held by " << heldNodes
        << " node(s) that are constrained or shared with held tissue, which do not span "
        << "a plane (it hangs on a node or an edge); tie it to bone or remove it, or its stiffness "
        << "matrix is singular";
    return Status::Error(out.str());
  }
  return Status::Ok();
}

} // namespace faceplan
