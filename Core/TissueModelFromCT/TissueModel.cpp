// SPDX-License-Identifier: BSD-3-Clause
#include "TissueModelFromCT/TissueModel.h"

#include "Mesh/TetGeometry.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <sstream>
#include <unordered_map>

namespace faceplan {

namespace {

bool Finite(double v) {
  return std::isfinite(v);
}

double RegularTetVolume(double edge) {
  return edge * edge * edge / (6.0 * std::sqrt(2.0));
}

std::string Fmt(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

} // namespace

Status ValidateParameters(const TissueModelParameters& p) {
  const MeshingParameters& m = p.meshing;
  const LabellingOptions& l = p.labelling;
  if (!Finite(l.boneThreshold) || !Finite(l.skinThreshold))
    return Status::Error("BoneThreshold and SkinThreshold must be finite");
  if (!(l.skinThreshold < l.boneThreshold))
    return Status::Error("thresholds in the wrong order: SkinThreshold (" + Fmt(l.skinThreshold) +
                         ") must be below BoneThreshold (" + Fmt(l.boneThreshold) + ")");
  if (!(m.cellSize > 0.0) || !Finite(m.cellSize))
    return Status::Error("CellSize must be positive (got " + Fmt(m.cellSize) + ")");
  if (!(m.surfaceDistance > 0.0) || !Finite(m.surfaceDistance))
    return Status::Error("SurfaceDistance must be positive (got " + Fmt(m.surfaceDistance) + ")");
  if (!(m.sliverBound >= 0.0 && m.sliverBound < 30.0))
    return Status::Error("QualityBound must be in [0, 30) degrees (got " + Fmt(m.sliverBound) +
                         ")");
  if (!(m.facetAngle > 0.0 && m.facetAngle <= 30.0))
    return Status::Error("the facet angle must be in (0, 30] degrees");
  if (!(m.radiusEdgeRatio >= 2.0))
    return Status::Error("the radius-edge ratio must be at least 2");
  if (!(p.boneCellSizeFactor >= 1.0) || !Finite(p.boneCellSizeFactor))
    return Status::Error("BoneCellSizeFactor must be at least 1");
  if (p.maximumCells <= 0)
    return Status::Error("MaximumCells must be positive");
  if (!(l.minimumBoneComponentVolume >= 0.0) || !(l.maximumBoneHoleVolume >= 0.0))
    return Status::Error("component and hole volumes must not be negative");
  if (l.separateMandible && (l.openingRadius < 1 || l.openingRadius > 5))
    return Status::Error("the mandible opening radius must be 1 to 5 voxels");
  return Status::Ok();
}

double EstimateCellCount(const LabellingSummary& s, const TissueModelParameters& p) {
  const double tissue = double(s.softTissueVoxels) * s.voxelVolume;
  const double bone = double(s.boneVoxels + s.mandibleVoxels) * s.voxelVolume;
  const double h = p.meshing.cellSize;
  const double volumeCells =
      tissue / RegularTetVolume(h) + bone / RegularTetVolume(h * p.boneCellSizeFactor);
  // Boundary facets no longer than CellSize, nor than the first attempt's facet distance allows.
  const double facetEdge =
      std::min(h, kFacetEdgePerDistance * kFacetDistanceMargins[0] * p.meshing.surfaceDistance);
  const double boundaryFacets = s.interfaceArea / (std::sqrt(3.0) / 4.0 * facetEdge * facetEdge);
  return kCellsPerVolumeCell * volumeCells + kCellsPerBoundaryFacet * boundaryFacets;
}

namespace {

struct FaceUse {
  long long cell[2] = {-1, -1};
  int slot[2] = {-1, -1}; // the corner opposite the face
};
using FaceMap = std::map<std::array<int, 3>, FaceUse>;

// Faces of every cell, keyed by their sorted corners: which cells hold them.
Status CollectFaces(const TetMesh& mesh, FaceMap& faces) {
  faces.clear();
  for (Eigen::Index e = 0; e < mesh.numTets(); ++e)
    for (int f = 0; f < 4; ++f) {
      std::array<int, 3> key{mesh.tets(e, (f + 1) % 4), mesh.tets(e, (f + 2) % 4),
                             mesh.tets(e, (f + 3) % 4)};
      std::sort(key.begin(), key.end());
      FaceUse& use = faces[key];
      const int side = use.cell[0] < 0 ? 0 : 1;
      if (side == 1 && use.cell[1] >= 0)
        return Status::Error("the mesher returned a face shared by three cells");
      use.cell[side] = e;
      use.slot[side] = f;
    }
  return Status::Ok();
}

} // namespace

long long PeelBoundarySlivers(LabeledTetMesh& labelled, double bound, int rounds) {
  const TetMesh& mesh = labelled.mesh;
  std::vector<double> angle(std::size_t(mesh.numTets()));
  TetCorners c;
  for (Eigen::Index e = 0; e < mesh.numTets(); ++e) {
    for (int k = 0; k < 4; ++k)
      c.row(k) = mesh.points.row(mesh.tets(e, k));
    angle[std::size_t(e)] = TetMinDihedralAngle(c);
  }
  FaceMap faces;
  if (!CollectFaces(mesh, faces))
    return 0;
  long long peeled = 0;
  for (int round = 0; round < rounds; ++round) {
    std::vector<std::pair<long long, int>> changes;
    for (const auto& entry : faces) {
      const FaceUse& use = entry.second;
      for (int side = 0; side < 2; ++side) {
        const long long e = use.cell[side];
        if (e < 0 || labelled.tetLabel[std::size_t(e)] != kSoftTissue ||
            angle[std::size_t(e)] >= bound)
          continue;
        const long long other = use.cell[1 - side];
        const int otherLabel = other < 0 ? kAir : labelled.tetLabel[std::size_t(other)];
        if (otherLabel != kSoftTissue)
          changes.emplace_back(e, otherLabel);
      }
    }
    if (changes.empty())
      break;
    for (const auto& change : changes)
      if (labelled.tetLabel[std::size_t(change.first)] == kSoftTissue) {
        labelled.tetLabel[std::size_t(change.first)] = change.second;
        ++peeled;
      }
  }
  return peeled;
}

Status ExtractTissueModel(const LabeledTetMesh& in, TissueModel& model) {
  const TetMesh& mesh = in.mesh;
  if (Eigen::Index(in.tetLabel.size()) != mesh.numTets())
    return Status::Error("the mesher returned " + std::to_string(in.tetLabel.size()) +
                         " labels for " + std::to_string(mesh.numTets()) + " tetrahedra");
  FaceMap faces;
  if (Status s = CollectFaces(mesh, faces); !s)
    return s;

  std::vector<int> newIndex(std::size_t(mesh.numPoints()), -1);
  std::vector<Eigen::Index> kept;
  for (Eigen::Index e = 0; e < mesh.numTets(); ++e)
    if (in.tetLabel[std::size_t(e)] == kSoftTissue)
      kept.push_back(e);
  if (kept.empty())
    return Status::Error(
        "the mesh has no soft-tissue cell (the tissue label is too thin for CellSize)");
  int next = 0;
  model.tissue.tets.resize(Eigen::Index(kept.size()), 4);
  for (std::size_t c = 0; c < kept.size(); ++c)
    for (int k = 0; k < 4; ++k) {
      int& id = newIndex[std::size_t(mesh.tets(kept[c], k))];
      if (id < 0)
        id = next++;
      model.tissue.tets(Eigen::Index(c), k) = id;
    }
  model.tissue.points.resize(next, 3);
  for (Eigen::Index i = 0; i < mesh.numPoints(); ++i)
    if (newIndex[std::size_t(i)] >= 0)
      model.tissue.points.row(newIndex[std::size_t(i)]) = mesh.points.row(i);
  model.tissueLabel.assign(kept.size(), kSoftTissue);

  std::vector<std::array<int, 3>> bone, skin;
  model.boneLabel.clear();
  for (const auto& entry : faces) {
    const FaceUse& use = entry.second;
    for (int side = 0; side < 2; ++side) {
      if (use.cell[side] < 0 || in.tetLabel[std::size_t(use.cell[side])] != kSoftTissue)
        continue;
      const long long other = use.cell[1 - side];
      const int otherLabel = other < 0 ? kAir : in.tetLabel[std::size_t(other)];
      if (otherLabel == kSoftTissue)
        continue;
      // Face opposite corner f of a positive tet: (f+1, f+2, f+3) is outward for even f, inward for
      // odd f; orient it outward from the tissue.
      const long long e = use.cell[side];
      const int f = use.slot[side];
      std::array<int, 3> tri{mesh.tets(e, (f + 1) % 4), mesh.tets(e, (f + 2) % 4),
                             mesh.tets(e, (f + 3) % 4)};
      if (f % 2 == 1)
        std::swap(tri[1], tri[2]);
      for (int& v : tri)
        v = newIndex[std::size_t(v)];
      if (otherLabel == kAir) {
        skin.push_back(tri);
      } else {
        std::swap(tri[1], tri[2]); // bone normals point into the tissue, out of the bone
        bone.push_back(tri);
        model.boneLabel.push_back(otherLabel);
      }
    }
  }
  auto toFacets = [](const std::vector<std::array<int, 3>>& tris) {
    Facets out(Eigen::Index(tris.size()), 3);
    for (std::size_t t = 0; t < tris.size(); ++t)
      for (int k = 0; k < 3; ++k)
        out(Eigen::Index(t), k) = tris[t][std::size_t(k)];
    return out;
  };
  model.boneFacets = toFacets(bone);
  model.skinFacets = toFacets(skin);
  if (bone.empty())
    return Status::Error("the soft tissue touches no bone in the mesh");
  return Status::Ok();
}

namespace {

// Bounds a model misses: any non-positive cell counts for all of them.
int MissedBounds(const TissueModel& m, double surfaceDistance) {
  if (m.quality.nonPositive > 0)
    return 3;
  return int(m.quality.belowDihedralBound > 0) + int(m.boundaryDistance.largest > surfaceDistance);
}

bool Better(const TissueModel& a, const TissueModel& b, double surfaceDistance) {
  const int ma = MissedBounds(a, surfaceDistance), mb = MissedBounds(b, surfaceDistance);
  if (ma != mb)
    return ma < mb;
  return a.boundaryDistance.largest < b.boundaryDistance.largest;
}

} // namespace

Status BuildTissueModelFromLabels(const LabelImage& labels, const TissueModelParameters& parameters,
                                  const LabelMesher& mesher, TissueModel& model,
                                  std::atomic<bool>* cancel, const MeshingProgress& progress) {
  if (Status s = ValidateParameters(parameters); !s)
    return s;
  if (!mesher)
    return Status::Error("no mesher given");
  if (labels.labels.size() != labels.grid.numVoxels())
    return Status::Error("label image size mismatch");
  if (model.labelling.voxelVolume == 0.0)
    model.labelling = SummariseLabels(labels);
  if (model.labelling.softTissueVoxels == 0)
    return Status::Error("the soft-tissue label is empty");
  model.estimatedCells = EstimateCellCount(model.labelling, parameters);
  if (model.estimatedCells > double(parameters.maximumCells))
    return Status::Error("the estimated mesh of " +
                         std::to_string((long long)model.estimatedCells) +
                         " tetrahedra exceeds MaximumCells (" +
                         std::to_string(parameters.maximumCells) + "): increase CellSize");

  MeshingParameters meshing = parameters.meshing;
  const double boneSize = meshing.cellSize * parameters.boneCellSizeFactor;
  meshing.labelCellSize = {{kBone, boneSize}, {kMandible, boneSize}};
  // A hard cap well above the estimate: a mesh that grows past it fails instead of exhausting
  // memory.
  if (meshing.maximumVertices == 0)
    meshing.maximumVertices = (long long)(2.0 * double(parameters.maximumCells) / 5.0) + 1000;
  // Perturbation and exudation stop once every cell reaches their target; aiming above the bound
  // leaves the worst cells some room.
  meshing.sliverBound = std::min(parameters.meshing.sliverBound + kSliverTargetMargin, 30.0);

  // Mesh_3 bounds the distance only at facet circumcentres and before smoothing moves the
  // vertices, and its sliver removal is best effort: the mesh is made again (kFacetDistanceMargins,
  // the next seed) until the measured distance and quality meet the bounds.
  const double bound = parameters.meshing.surfaceDistance;
  const double angleBound = parameters.meshing.sliverBound;
  const double radius =
      2.0 * bound + *std::max_element(labels.grid.spacing.begin(), labels.grid.spacing.end());
  TissueModel best;
  bool haveBest = false;
  std::vector<long long> attemptCells;
  for (std::size_t attempt = 0; attempt < kFacetDistanceMargins.size(); ++attempt) {
    meshing.surfaceDistance = bound * kFacetDistanceMargins[attempt];
    meshing.seed = parameters.meshing.seed + unsigned(attempt);
    LabeledTetMesh labelled;
    TissueModel candidate;
    candidate.labelling = model.labelling;
    candidate.estimatedCells = model.estimatedCells;
    Status meshed = mesher(labels, meshing, labelled, cancel, progress);
    if (meshed) {
      candidate.meshedCells = labelled.mesh.numTets();
      candidate.peeledSlivers = PeelBoundarySlivers(labelled, angleBound);
      meshed = ExtractTissueModel(labelled, candidate);
    }
    // A finer attempt that fails (vertex budget, a thin label) leaves the coarser one standing.
    if (!meshed) {
      if (haveBest && !(cancel && cancel->load()))
        break;
      return meshed;
    }
    candidate.quality = MeasureTetQuality(candidate.tissue, angleBound);
    Facets boundary(candidate.boneFacets.rows() + candidate.skinFacets.rows(), 3);
    boundary << candidate.boneFacets, candidate.skinFacets;
    candidate.boundaryDistance = MeasureBoundaryDistance(labels, candidate.tissue.points, boundary,
                                                         radius, kRefineDistanceAbove * bound);
    attemptCells.push_back(candidate.meshedCells);
    if (!haveBest || Better(candidate, best, bound)) {
      best = std::move(candidate);
      haveBest = true;
    }
    if (MissedBounds(best, bound) == 0)
      break;
  }
  model = std::move(best);
  model.attemptCells = attemptCells;
  model.meshingAttempts = int(attemptCells.size());

  Status status;
  if (model.quality.nonPositive > 0)
    return Status::Error(std::to_string(model.quality.nonPositive) +
                         " tetrahedra have no positive volume");
  if (model.quality.belowDihedralBound > 0)
    status.warnings.push_back(std::to_string(model.quality.belowDihedralBound) +
                              " slivers: tetrahedra with a dihedral angle below QualityBound (" +
                              Fmt(angleBound) + " deg); worst " +
                              Fmt(model.quality.worstDihedralAngle) + " deg");
  if (model.boundaryDistance.largest > bound)
    status.warnings.push_back("the boundary lies up to " + Fmt(model.boundaryDistance.largest) +
                              " from the labelled interface, more than SurfaceDistance (" +
                              Fmt(bound) + ")");
  model.warnings = status.warnings;
  if (progress)
    progress(1.0, "done");
  return status;
}

Status BuildTissueModel(const CTImage& ct, const TissueModelParameters& parameters,
                        const LabelMesher& mesher, TissueModel& model, std::atomic<bool>* cancel,
                        const MeshingProgress& progress) {
  if (Status s = ValidateParameters(parameters); !s)
    return s;
  if (progress)
    progress(0.0, "labelling");
  LabelImage labels;
  model = TissueModel();
  if (Status s = LabelTissue(ct, parameters.labelling, labels, model.labelling); !s)
    return s;
  if (parameters.labelling.separateMandible && !model.labelling.mandibleSeparated)
    model.warnings.push_back(
        "SeparateMandible: the bone stays one piece after the opening (teeth in occlusion "
        "or a thick joint join the jaws); the mandible is not labelled");
  std::vector<std::string> early = model.warnings;
  Status status = BuildTissueModelFromLabels(labels, parameters, mesher, model, cancel, progress);
  status.warnings.insert(status.warnings.begin(), early.begin(), early.end());
  model.warnings = status.warnings;
  return status;
}

} // namespace faceplan
