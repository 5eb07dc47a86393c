#pragma once
// What changed in CondensedFEMDeform's inputs since the last update, so that an edit (a new bone
// Displacement on the same tissue, bone surface and ROI) redoes only the per-edit work.
//
// Each input is first identified by VTK modification times: the data object's (which covers its
// points and point/cell arrays) and those of its cell arrays and their storage (which
// vtkDataObject::GetMTime leaves out). While they are unchanged the last validation and conversion
// stand. When they change (a re-executed upstream filter, a copied or gathered data set) the
// content is validated, converted and compared with the cached one before anything downstream is
// rebuilt: an unchanged tissue keeps its precompute, a changed mesh or material always gets a new
// one. Private to FacePlan::Filters.
#include "CondensedFEMDeformConvert.h"
#include "CondensedFEMDeformSettings.h"
#include "FacePlanDataStamp.h"

#include "Common/Status.h"
#include "Mesh/TetMesh.h"

#include "vtkType.h"

#include <vector>

class vtkPointSet;
class vtkUnstructuredGrid;

namespace faceplan {
namespace fem_filter {

// The tissue validated and converted (mesh, materials, boundary), redone only when it or the
// material properties changed. `generation` counts content changes: it stays the same when a new
// stamp carries the same mesh and materials.
class TissueCache {
public:
  Status update(vtkUnstructuredGrid* tissue, const Settings& settings);
  const TetMesh& mesh() const { return mesh_; }
  const Materials& materials() const { return materials_; }
  const TissueBoundary& boundary() const { return boundary_; }
  unsigned long generation() const { return generation_; }

private:
  struct MaterialSettings {
    double youngsModulus, poissonRatio, density, lengthUnit;
    bool useCellMaterials;
    bool operator==(const MaterialSettings& o) const {
      return youngsModulus == o.youngsModulus && poissonRatio == o.poissonRatio &&
             density == o.density && lengthUnit == o.lengthUnit &&
             useCellMaterials == o.useCellMaterials;
    }
  };
  bool valid_ = false;
  DataStamp stamp_;
  MaterialSettings materialSettings_{};
  TetMesh mesh_;
  Materials materials_;
  TissueBoundary boundary_;
  unsigned long generation_ = 0;
};

// The bone's per-edit check: its structure (cells, ROIMask, SegmentId, Sliding, Released; by stamp,
// and by their bytes when the stamp differs, since an edit through Osteotomy, Append Geometry or
// several Bone connections hands over new arrays with the same values) and its undeformed points
// (points minus Displacement, compared by value because an edit makes a new bone whose points and
// Displacement both move). Validation runs in full when the structure changed, else only on the
// values an edit changes.
class BoneCache {
public:
  Status validate(vtkPointSet* bone);
  // Whether the contact built for this bone still holds: same tissue content, distance, bone
  // structure and undeformed points as at the last call of `contactBuilt`, so a move never
  // rebuilds the contact.
  bool contactStillValid(vtkPointSet* bone, unsigned long tissueGeneration, double contactDistance);
  void contactBuilt(vtkPointSet* bone, unsigned long tissueGeneration, double contactDistance);

private:
  static constexpr const char* kStructureArrays[] = {"ROIMask", "SegmentId", "Sliding", "Released"};
  static DataStamp StructureStampOf(vtkPointSet* bone);
  // The structure's bytes: point count, cells (a polydata's raw offsets and connectivity, else the
  // cells one by one) and the structure arrays with their type and shape.
  static void StructureSignature(vtkPointSet* bone, std::vector<unsigned char>& out);
  static void UndeformedPoints(vtkPointSet* bone, std::vector<double>& points);
  // The signature of the bone with this stamp, computed once per stamp.
  const std::vector<unsigned char>& signatureOf(vtkPointSet* bone, const DataStamp& stamp);

  bool haveSignature_ = false;
  DataStamp signatureStamp_;
  std::vector<unsigned char> signature_;

  bool validated_ = false;
  DataStamp validatedStructure_;
  std::vector<unsigned char> validatedSignature_;

  bool haveContact_ = false;
  DataStamp contactStamp_;
  std::vector<unsigned char> contactSignature_;
  unsigned long contactTissue_ = 0;
  double contactDistance_ = -1.0;
  std::vector<double> contactUndeformed_, scratch_;
};

} // namespace fem_filter
} // namespace faceplan
