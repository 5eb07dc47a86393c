#include "MeshValidation.h"

#include "ElementStiffness.h"

#include <cmath>
#include <numeric>
#include <sstream>

namespace faceplan {

namespace {

// Lists the first few ids and the count, so a message stays readable on a large mesh.
std::string IdList(const std::vector<long long>& ids) {
  std::ostringstream out;
  const size_t shown = std::min<size_t>(ids.size(), 10);
  for (size_t k = 0; k < shown; ++k) out << (k ? ", " : "") << ids[k];
  if (ids.size() > shown) out << ", ... (" << ids.size() << " in all)";
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
  if (m == 0) return Status::Error("the mesh has no tetrahedra");
  if (!mesh.points.allFinite()) {
    std::vector<long long> bad;
    for (Eigen::Index i = 0; i < n; ++i)
      if (!mesh.points.row(i).allFinite()) bad.push_back(i);
    return Status::Error("non-finite (NaN or infinite) coordinates at points " + IdList(bad));
  }
  std::vector<long long> outOfRange;
  for (Eigen::Index e = 0; e < m; ++e)
    for (int k = 0; k < 4; ++k)
      if (mesh.tets(e, k) < 0 || mesh.tets(e, k) >= n) outOfRange.push_back(e);
  if (!outOfRange.empty())
    return Status::Error("tetrahedra reference points that do not exist: cells " + IdList(outOfRange));

  auto checkSize = [m](const Eigen::VectorXd& v, const char* what, bool optional) -> std::string {
    if (optional && v.size() == 0) return {};
    if (v.size() != 1 && v.size() != m)
      return std::string(what) + " must have 1 or " + std::to_string(m) + " values, not " +
             std::to_string(v.size());
    return {};
  };
  for (auto msg : {checkSize(materials.youngsModulus, "Young's modulus", false),
                   checkSize(materials.poissonRatio, "Poisson ratio", false),
                   checkSize(materials.density, "density", true)})
    if (!msg.empty()) return Status::Error(msg);

  std::vector<long long> badE, badNu;
  for (Eigen::Index e = 0; e < materials.youngsModulus.size(); ++e)
    if (!(materials.youngsModulus[e] > 0.0) || !std::isfinite(materials.youngsModulus[e])) badE.push_back(e);
  for (Eigen::Index e = 0; e < materials.poissonRatio.size(); ++e)
    if (!(materials.poissonRatio[e] > -1.0 && materials.poissonRatio[e] < 0.5)) badNu.push_back(e);
  if (!badE.empty())
    return Status::Error("Young's modulus must be positive and finite (E <= 0 or NaN in cells " +
                         IdList(badE) + ")");
  if (!badNu.empty())
    return Status::Error("Poisson ratio must lie in (-1, 0.5) (violated in cells " + IdList(badNu) + ")");

  // A volume is "zero" relative to the cube of the mesh's edge scale.
  const double scale = (mesh.points.colwise().maxCoeff() - mesh.points.colwise().minCoeff()).norm();
  const double zeroVolume = 1e-14 * scale * scale * scale / static_cast<double>(m);
  std::vector<long long> inverted, flat;
  TetCorners corners;
  for (Eigen::Index e = 0; e < m; ++e) {
    for (int k = 0; k < 4; ++k) corners.row(k) = mesh.points.row(mesh.tets(e, k));
    const double v = TetVolume(corners);
    if (v < -zeroVolume) inverted.push_back(e);
    else if (v <= zeroVolume) flat.push_back(e);
  }
  if (!inverted.empty() || !flat.empty()) {
    std::string msg = "tetrahedra with non-positive volume:";
    if (!flat.empty()) msg += " zero-volume cells " + IdList(flat) + ";";
    if (!inverted.empty()) msg += " inverted cells " + IdList(inverted) + ";";
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
      if (rk != r0) parent[rk] = r0;
    }
  }
  componentOfNode.assign(n, -1);
  std::vector<int> label(n, -1);
  int count = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!used[i]) continue;
    const int root = FindRoot(parent, static_cast<int>(i));
    if (label[root] < 0) label[root] = count++;
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
    if (node >= 0 && node < mesh.numPoints() && component[node] >= 0) held[component[node]] = 1;
  for (int c = 0; c < count; ++c) {
    if (held[c]) continue;
    long long cells = 0;
    Eigen::RowVector3d lo = Eigen::RowVector3d::Constant(INFINITY), hi = -lo;
    for (Eigen::Index e = 0; e < mesh.numTets(); ++e) {
      if (component[mesh.tets(e, 0)] != c) continue;
      ++cells;
      for (int k = 0; k < 4; ++k) {
        lo = lo.cwiseMin(mesh.points.row(mesh.tets(e, k)));
        hi = hi.cwiseMax(mesh.points.row(mesh.tets(e, k)));
      }
    }
    std::ostringstream out;
    out << "a free piece of the mesh is attached to no constrained node (component " << c << " of "
        << count << ": " << cells << " cells, bounds [" << lo(0) << ", " << hi(0) << "] x [" << lo(1)
        << ", " << hi(1) << "] x [" << lo(2) << ", " << hi(2)
        << "]); tie it to bone or remove it, or its stiffness matrix is singular";
    return Status::Error(out.str());
  }
  return Status::Ok();
}

} // namespace faceplan
