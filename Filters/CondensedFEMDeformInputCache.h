// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What changed in CondensedFEMDeform's tissue input since the last update, so that an edit (a new
// bone Displacement on the same tissue, bone surface and ROI) redoes only the per-edit work; the
// bone's side is BoneInput (CondensedFEMDeformBoneInput.h).
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
#include "Mesh/LipSeal.h"
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
  // With LipSeal, mesh() and materials() carry the bridges after the tissue's own cells.
  const LipSealInfo& lipSeal() const { return lipSeal_; }
  unsigned long generation() const { return generation_; }

private:
  struct MaterialSettings {
    double youngsModulus, poissonRatio, density, lengthUnit;
    bool useCellMaterials;
    double lipSeal;
    bool operator==(const MaterialSettings& o) const {
      return youngsModulus == o.youngsModulus && poissonRatio == o.poissonRatio &&
             density == o.density && lengthUnit == o.lengthUnit &&
             useCellMaterials == o.useCellMaterials && lipSeal == o.lipSeal;
    }
  };
  bool valid_ = false;
  DataStamp stamp_;
  MaterialSettings materialSettings_{};
  TetMesh mesh_;
  Materials materials_;
  TissueBoundary boundary_;
  LipSealInfo lipSeal_;
  unsigned long generation_ = 0;
};

} // namespace fem_filter
} // namespace faceplan
