#pragma once
// From a CT volume to a planning model: a tetrahedral soft-tissue mesh, the bone surface made of
// the tissue's own facets that face bone (so tissue and bone share their points) and the skin
// surface. The mesher is passed in (Core/Copyleft/CGAL provides Mesh_3's).
#include "Common/Status.h"
#include "TissueModelFromCT/BoundaryDistance.h"
#include "TissueModelFromCT/LabeledMesher.h"
#include "TissueModelFromCT/TetQuality.h"
#include "TissueModelFromCT/TissueLabelling.h"

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

// Expected number of tetrahedra Mesh_3 makes for the labelled volumes (tissue at CellSize, bone
// at its coarser size): volume over the volume of a regular tetrahedron of that edge, times the
// factor by which Delaunay meshes exceed that count.
double EstimateCellCount(const LabellingSummary& summary, const TissueModelParameters& parameters);
constexpr double kDelaunayCellExcess = 2.5; // measured 1.7 (smooth shell) to 2.8 (head CT)
// Fraction of SurfaceDistance passed to the mesher as its facet-distance criterion.
constexpr double kFacetDistanceMargin = 0.5;

struct TissueModel {
  TetMesh tissue;               // soft-tissue tetrahedra, positively oriented
  std::vector<int> tissueLabel; // per tetrahedron (kSoftTissue)
  Facets boneFacets;            // tissue facets facing bone, normals pointing into the tissue
  std::vector<int> boneLabel;   // per bone facet: kBone or kMandible
  Facets skinFacets;            // tissue facets facing air, normals pointing out of the tissue
  LabellingSummary labelling;
  double estimatedCells = 0.0;
  long long meshedCells = 0;   // every label, before the bone cells are dropped
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
// Warns when the quality bound or SurfaceDistance is missed.
Status BuildTissueModelFromLabels(const LabelImage& labels, const TissueModelParameters& parameters,
                                  const LabelMesher& mesher, TissueModel& model,
                                  std::atomic<bool>* cancel = nullptr,
                                  const MeshingProgress& progress = {});

// Labels the CT (LabelTissue) and continues as above.
Status BuildTissueModel(const CTImage& ct, const TissueModelParameters& parameters,
                        const LabelMesher& mesher, TissueModel& model,
                        std::atomic<bool>* cancel = nullptr, const MeshingProgress& progress = {});

} // namespace faceplan
