// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// From a CT volume to a planning model: a tetrahedral soft-tissue mesh, the bone surface made of
// the tissue's own facets that face bone (so tissue and bone share their points) and the skin
// surface. The mesher is passed in (Core/Copyleft/CGAL provides Mesh_3's).
#include "Common/Status.h"
#include "TissueModelFromCT/BoundaryDistance.h"
#include "TissueModelFromCT/LabeledMesher.h"
#include "TissueModelFromCT/TetQuality.h"
#include "TissueModelFromCT/TissueLabelling.h"

#include <array>
#include <atomic>
#include <string>
#include <vector>

namespace faceplan {

struct TissueModelParameters {
  LabellingOptions labelling;
  MeshingParameters meshing; // meshing.sliverBound is the quality bound (smallest dihedral angle)
  double boneCellSizeFactor = 2.0;  // bone is meshed this much coarser (its cells are dropped)
  long long maximumCells = 1000000; // refuse runs whose estimated tetrahedron count is larger
};

// Parameter errors name the property: "CellSize must be positive", ...
Status ValidateParameters(const TissueModelParameters& parameters);

// Expected number of tetrahedra (every label) of the first meshing attempt: the labelled volumes
// over the volume of a regular tetrahedron of their edge (tissue at CellSize, bone coarser), plus
// the cells along the boundary, whose facets the facet distance keeps shorter than CellSize on a
// voxelised interface. Calibrated on the head CT and the synthetic shell so as not to undercount
// (TestTissueModelMeshing.CellEstimateCoversMeshedCells, the CT test).
double EstimateCellCount(const LabellingSummary& summary, const TissueModelParameters& parameters);
constexpr double kCellsPerVolumeCell = 2.2;
constexpr double kCellsPerBoundaryFacet = 1.4;
constexpr double kFacetEdgePerDistance = 4.0; // boundary facet edge over the facet distance
// Fractions of SurfaceDistance passed to the mesher as its facet-distance criterion, one per
// attempt: a mesh whose measured distance or quality misses its bound is made again with the next
// fraction and the next seed (Seed + attempt). The misses are a few facets across voxel-sized
// features, different for every seed; smaller fractions add facets and so chances to miss.
constexpr std::array<double, 5> kFacetDistanceMargins{{0.5, 0.4, 0.4, 0.4, 0.4}};
// Degrees above the quality bound that sliver perturbation and exudation aim for.
constexpr double kSliverTargetMargin = 3.0;
// Boundary samples farther than this fraction of SurfaceDistance get the fine direction search.
constexpr double kRefineDistanceAbove = 0.75;

struct TissueModel {
  TetMesh tissue;               // soft-tissue tetrahedra, positively oriented
  std::vector<int> tissueLabel; // per tetrahedron (kSoftTissue)
  Facets boneFacets;            // tissue facets facing bone, normals pointing into the tissue
  std::vector<int> boneLabel;   // per bone facet: kBone or kMandible
  Facets skinFacets;            // tissue facets facing air, normals pointing out of the tissue
  LabellingSummary labelling;
  double estimatedCells = 0.0;
  long long meshedCells = 0; // every label, before the bone cells are dropped
  int meshingAttempts = 0;   // meshes made until the bounds were met (kFacetDistanceMargins)
  std::vector<long long> attemptCells; // every label, per attempt (the estimate is of the first)
  long long peeledSlivers = 0; // boundary slivers given to air or bone (PeelBoundarySlivers)
  TetQualitySummary quality;
  BoundaryDistanceResult boundaryDistance;
  std::vector<std::string> warnings;
};

// Boundary slivers: soft-tissue cells below the quality bound (smallest dihedral angle, degrees)
// with a face on the tissue's boundary take the label across that face (air or bone). Such cells
// are nearly flat and lie along the interface, where perturbation and exudation cannot move
// their corners, so peeling them changes the volume negligibly. Repeats while any is found (at
// most `rounds` times); returns the number of cells relabelled.
long long PeelBoundarySlivers(LabeledTetMesh& labelled, double boundDegrees, int rounds = 3);

// Splits a labelled mesh into the tissue model: keeps the kSoftTissue cells and their points, and
// classifies their boundary facets by the label on the other side (none = air).
Status ExtractTissueModel(const LabeledTetMesh& labelled, TissueModel& model);

// The whole path from labels: budget check, meshing, extraction, quality and boundary distance.
// Meshes again with a smaller facet distance while the quality bound or SurfaceDistance is missed
// (kFacetDistanceMargins); warns when the last attempt still misses one, keeping the best mesh.
Status BuildTissueModelFromLabels(const LabelImage& labels, const TissueModelParameters& parameters,
                                  const LabelMesher& mesher, TissueModel& model,
                                  std::atomic<bool>* cancel = nullptr,
                                  const MeshingProgress& progress = {});

// Labels the CT (LabelTissue) and continues as above.
Status BuildTissueModel(const CTImage& ct, const TissueModelParameters& parameters,
                        const LabelMesher& mesher, TissueModel& model,
                        std::atomic<bool>* cancel = nullptr, const MeshingProgress& progress = {});

} // namespace faceplan
