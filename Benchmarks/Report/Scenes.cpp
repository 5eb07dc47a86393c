// SPDX-License-Identifier: BSD-3-Clause
#include "Report/Scenes.h"

#include "Support/BoundaryNodes.h"
#include "Support/ShellMeshGenerator.h"
#include "Support/VtuReader.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

namespace faceplan::report {

namespace {

// A smooth surgical edit of the face-like shell's ROI cap (a few millimetres).
RowVectors3d ShellEdit(const PrecomputeRequest& r) {
  RowVectors3d u(static_cast<Eigen::Index>(r.sets.movable.size()), 3);
  for (size_t k = 0; k < r.sets.movable.size(); ++k) {
    const Eigen::RowVector3d p = r.mesh.points.row(r.sets.movable[k]);
    u.row(k) << 1.5 * std::sin(0.05 * p(0)), -1.0 * std::cos(0.04 * p(1)),
        2.0 + 0.5 * std::sin(0.03 * (p(0) + p(1)));
  }
  return u;
}

// Organ / face scenes from Data/: BoneContact nodes fixed, an ROI patch of them moved smoothly,
// boundary nodes not in contact kept.

} // namespace

Scene FaceLikeShell(const std::string& name, int subdivisions, int layers) {
  const FaceLikeScene f = MakeFaceLikeScene(subdivisions, layers, 0.1);
  Scene s;
  s.name = name;
  s.family = "shell";
  s.request.mesh = f.shell.mesh;
  s.request.materials = Materials::Uniform(3.0e3, 0.45);
  s.request.sets = {f.constrained, f.movable, f.kept};
  s.edit = ShellEdit(s.request);
  std::ostringstream d;
  d << "face-like shell (MakeFaceLikeScene(" << subdivisions << ", " << layers
    << ")): inner surface on bone, 10 % ROI cap moved smoothly, outer surface kept; E = 3 kPa, nu "
       "= 0.45";
  s.description = d.str();
  s.large = s.request.mesh.numTets() > 60000;
  return s;
}

Scene Sphere(int level) {
  Scene s;
  s.name = "sphere" + std::to_string(level);
  s.family = "sphere";
  s.analytic = true;
  const ShellMesh shell = MakeSphericalShell(3 * level, level, s.exact.a, s.exact.b);
  s.request.mesh = shell.mesh;
  s.request.materials = Materials::Uniform(s.exact.E, s.exact.nu);
  s.request.sets = {shell.innerNodes, shell.innerNodes, shell.outerNodes};
  s.edit.resize(static_cast<Eigen::Index>(shell.innerNodes.size()), 3);
  for (size_t k = 0; k < shell.innerNodes.size(); ++k)
    s.edit.row(k) =
        s.exact.displacement(shell.mesh.points.row(shell.innerNodes[k]).transpose()).transpose();
  s.h = (s.exact.b - s.exact.a) / level;
  std::ostringstream d;
  d << "analytic hollow sphere a = 1, b = 2 (MakeSphericalShell(" << 3 * level << ", " << level
    << ")), exact radial displacement on the inner surface, outer surface free and kept; E = 1, nu "
       "= 0.3";
  s.description = d.str();
  s.large = s.request.mesh.numTets() > 60000;
  return s;
}

// Boundary nodes: nodes of faces used by a single tetrahedron.
bool DataScene(const std::string& name, const std::string& path, bool face, Scene& s,
               std::string& error) {
  bench::VtuMesh vtu;
  if (!bench::ReadVtuTets(path, vtu, error))
    return false;
  auto contact = vtu.pointData.find("BoneContact");
  if (contact == vtu.pointData.end())
    return error = path + " has no BoneContact array", false;
  const TetMesh& mesh = vtu.mesh;
  const Eigen::Index n = mesh.numPoints();
  const std::vector<char> boundary = bench::BoundaryNodes(mesh);
  s.name = name;
  s.family = face ? "face" : "organ";
  s.request.mesh = mesh;
  s.request.materials = Materials::Uniform(3.0e3, 0.45);
  std::vector<int> contactNodes;
  for (Eigen::Index i = 0; i < n; ++i)
    if (contact->second[i] > 0.5)
      contactNodes.push_back(static_cast<int>(i));
  if (contactNodes.empty())
    return error = path + ": no BoneContact nodes", false;
  for (Eigen::Index i = 0; i < n; ++i)
    if (boundary[i] && contact->second[i] <= 0.5)
      s.request.sets.kept.push_back(static_cast<int>(i));
  s.request.sets.constrained = contactNodes;
  const Eigen::RowVector3d extent =
      mesh.points.colwise().maxCoeff() - mesh.points.colwise().minCoeff();
  const Eigen::RowVector3d meshCentre = mesh.points.colwise().mean();
  std::ostringstream d;
  if (face && vtu.pointData.count("ContactBone")) {
    // The mandible's contact nodes move together (a mandibular advancement), the maxilla's and
    // cranium's stay.
    const auto& bone = vtu.pointData["ContactBone"];
    Eigen::RowVector3d roiCentre = Eigen::RowVector3d::Zero(),
                       contactCentre = Eigen::RowVector3d::Zero();
    for (int i : contactNodes) {
      contactCentre += mesh.points.row(i);
      if (std::lround(bone[i]) == 1) {
        s.request.sets.movable.push_back(i);
        roiCentre += mesh.points.row(i);
      }
    }
    if (s.request.sets.movable.empty())
      return error = path + ": no mandible contact nodes", false;
    roiCentre /= double(s.request.sets.movable.size());
    contactCentre /= double(contactNodes.size());
    const Eigen::RowVector3d dir = (roiCentre - contactCentre).normalized();
    s.edit.resize(static_cast<Eigen::Index>(s.request.sets.movable.size()), 3);
    for (Eigen::Index k = 0; k < s.edit.rows(); ++k)
      s.edit.row(k) = 3.0 * dir;
    d << "Badin face tissue (Data/face/face_tissue.vtu): BoneContact nodes fixed, the mandible's ("
      << s.request.sets.movable.size()
      << " nodes) translated 3 mm, boundary nodes not in contact kept; E = 3 kPa, nu = 0.45";
  } else {
    // ROI: the 30 % of contact nodes nearest to the contact node closest to the contact centroid,
    // moved by a smooth bump (zero slope at the patch rim) away from the mesh centre.
    Eigen::RowVector3d contactCentre = Eigen::RowVector3d::Zero();
    for (int i : contactNodes)
      contactCentre += mesh.points.row(i);
    contactCentre /= double(contactNodes.size());
    int seed = contactNodes[0];
    for (int i : contactNodes)
      if ((mesh.points.row(i) - contactCentre).norm() <
          (mesh.points.row(seed) - contactCentre).norm())
        seed = i;
    std::vector<std::pair<double, int>> byDistance;
    for (int i : contactNodes)
      byDistance.push_back({(mesh.points.row(i) - mesh.points.row(seed)).norm(), i});
    std::sort(byDistance.begin(), byDistance.end());
    const size_t count = std::max<size_t>(1, byDistance.size() * 3 / 10);
    const double radius = 1.05 * std::max(1e-9, byDistance[count - 1].first);
    const Eigen::RowVector3d dir = (mesh.points.row(seed) - meshCentre).normalized();
    const double amplitude = 0.03 * extent.maxCoeff();
    for (size_t k = 0; k < count; ++k)
      s.request.sets.movable.push_back(byDistance[k].second);
    s.edit.resize(static_cast<Eigen::Index>(count), 3);
    for (size_t k = 0; k < count; ++k) {
      const double q = byDistance[k].first / radius;
      s.edit.row(k) = amplitude * (1 - q * q) * (1 - q * q) * dir;
    }
    d.precision(3);
    d << path << ": BoneContact nodes fixed, a patch of " << count
      << " of them pushed by a smooth bump (peak " << amplitude
      << " mm, 3 % of the extent), boundary nodes not in contact kept; E = 3 kPa, nu = 0.45";
  }
  s.description = d.str();
  return true;
}

} // namespace faceplan::report
