// SPDX-License-Identifier: BSD-3-Clause
// Core's input checks on arbitrary meshes, materials, node sets and surfaces: never a crash, and
// when every check passes, Precompute and Solve either fail with a message or give finite results.
#include "FuzzBytes.h"
#include "FuzzPrecompute.h"

#include "CondensedFEM/CondensedFEM.h"
#include "Mesh/MeshValidation.h"
#include "Mesh/NodeSetValidation.h"
#include "ROIExtract/ROIExtract.h"

#include <cstdint>
#include <memory>
#include <vector>

using namespace faceplan;
using faceplan::fuzz::CheckedPrecompute;
using faceplan::fuzz::FuzzBytes;
using faceplan::fuzz::Violation;

namespace {

Eigen::VectorXd MaterialValues(FuzzBytes& in, Eigen::Index cells, double typical) {
  Eigen::Index count = 1;
  switch (in.byte() % 5) {
  case 0:
    count = 0;
    break;
  case 1:
    count = 1;
    break;
  case 2:
    count = cells + 1;
    break;
  case 3:
    count = cells > 0 ? cells - 1 : 0;
    break;
  default:
    count = cells;
  }
  Eigen::VectorXd values(count);
  for (Eigen::Index k = 0; k < count; ++k)
    values[k] = in.number(typical);
  return values;
}

std::vector<int> NodeIds(FuzzBytes& in, int points, bool rawIds) {
  std::vector<int> ids(std::size_t(in.range(0, 6)));
  for (int& id : ids)
    id = rawIds ? in.int32() : in.range(-1, points);
  return ids;
}

void CheckTetMesh(FuzzBytes& in) {
  const int n = in.range(0, 10), m = in.range(0, 8);
  const bool rawIds = in.flag(), rawCoordinates = in.flag();
  TetMesh mesh;
  mesh.points.resize(n, 3);
  for (int i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c)
      mesh.points(i, c) = rawCoordinates ? in.number(1.0) : in.scaled(2.0);
  mesh.tets.resize(m, 4);
  for (int e = 0; e < m; ++e)
    for (int k = 0; k < 4; ++k)
      mesh.tets(e, k) = rawIds ? in.int32() : in.range(-1, n);
  Materials materials;
  materials.youngsModulus = MaterialValues(in, m, 3000.0);
  materials.poissonRatio = MaterialValues(in, m, 0.3);
  materials.density = MaterialValues(in, m, 1e-6);
  NodeSets sets;
  sets.constrained = NodeIds(in, n, rawIds);
  sets.movable = NodeIds(in, n, rawIds);
  sets.kept = NodeIds(in, n, rawIds);

  const Status meshStatus = ValidateMeshAndMaterials(mesh, materials);
  const Status setStatus = ValidateNodeSets(mesh, sets);
  if (!meshStatus && meshStatus.message.empty())
    Violation("a mesh error without a message");
  if (!meshStatus || !setStatus)
    return;

  std::vector<int> components;
  if (ConnectedComponents(mesh, components) < 0)
    Violation("negative component count");
  CheckEveryComponentConstrained(mesh, sets.constrained);
  CheckRigidModesHeld(mesh, sets.constrained);
  CheckElementQuality(mesh, 0.02);

  PrecomputeRequest request{mesh, materials, sets, {}};
  request.options.method = static_cast<SolveMethod>(in.range(0, 2));
  request.options.elementOrder = static_cast<ElementOrder>(in.range(0, 2));
  std::shared_ptr<const CondensedSystem> system;
  if (!CheckedPrecompute(request, system))
    return;
  SolveInput input;
  const Eigen::Index rows = Eigen::Index(sets.movable.size()) + (in.flag() ? in.range(-1, 1) : 0);
  input.movableDisplacement.resize(rows < 0 ? 0 : rows, 3);
  for (Eigen::Index i = 0; i < input.movableDisplacement.rows(); ++i)
    for (int c = 0; c < 3; ++c)
      input.movableDisplacement(i, c) = in.number(0.5);
  if (in.flag())
    input.gravity << in.number(1.0), in.number(1.0), in.number(1.0); // sequenced reads
  input.recoverInterior = in.flag();
  SolveResult result;
  const Status solved = Solve(*system, input, result);
  if (solved && !(result.keptDisplacement.allFinite() && result.allDisplacement.allFinite()))
    Violation("Solve succeeded with a non-finite displacement");
  if (!solved && solved.message.empty())
    Violation("a Solve error without a message");
}

void CheckSurface(FuzzBytes& in) {
  SurfaceMesh surface;
  const int n = in.range(0, 8);
  surface.points.resize(n, 3);
  for (int i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c)
      surface.points(i, c) = in.flag() ? in.number(1.0) : in.scaled(1.0);
  surface.offsets.resize(std::size_t(in.range(0, 5)));
  for (auto& o : surface.offsets)
    o = in.flag() ? std::int64_t(in.int32()) : in.range(-1, 12);
  surface.connectivity.resize(std::size_t(in.range(0, 12)));
  for (auto& id : surface.connectivity)
    id = in.flag() ? std::int64_t(in.int32()) : in.range(-1, n);
  const Status valid = ValidateSurfaceMesh(surface);
  if (!valid && valid.message.empty())
    Violation("a surface error without a message");
  std::vector<std::uint8_t> selected(std::size_t(in.flag() ? in.range(0, 9) : n));
  for (auto& s : selected)
    s = in.byte();
  ROIResult roi;
  const Status fromMask = ComputeROI(surface, selected, roi);
  if (fromMask && (roi.mask.size() != std::size_t(n) || roi.boundary.size() != std::size_t(n)))
    Violation("ROI arrays of the wrong length");
  std::vector<std::int64_t> ids(std::size_t(in.range(0, 6)));
  for (auto& id : ids)
    id = in.flag() ? std::int64_t(in.int32()) : in.range(-1, n);
  ComputeROIFromIds(surface, ids, roi);
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  FuzzBytes in(data, size);
  if (in.flag())
    CheckTetMesh(in);
  else
    CheckSurface(in);
  return 0;
}
