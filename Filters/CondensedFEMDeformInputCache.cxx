// SPDX-License-Identifier: BSD-3-Clause
#include "CondensedFEMDeformInputCache.h"

#include "CondensedFEMDeformValidate.h"

#include "vtkCellArray.h"
#include "vtkDataArray.h"
#include "vtkDoubleArray.h"
#include "vtkIdList.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkPointSet.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"

#include <cmath>

namespace faceplan {
namespace fem_filter {

namespace {

template <class Matrix> bool SameMatrix(const Matrix& a, const Matrix& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() && a == b;
}

bool SameMaterials(const Materials& a, const Materials& b) {
  return SameMatrix(a.youngsModulus, b.youngsModulus) &&
         SameMatrix(a.poissonRatio, b.poissonRatio) && SameMatrix(a.density, b.density);
}

} // namespace

Status TissueCache::update(vtkUnstructuredGrid* tissue, const Settings& settings) {
  DataStamp stamp = StampOf(tissue);
  const MaterialSettings materialSettings{settings.youngsModulus,    settings.poissonRatio,
                                          settings.density,          settings.lengthUnit,
                                          settings.useCellMaterials, settings.sealGap()};
  if (valid_ && stamp == stamp_ && materialSettings == materialSettings_)
    return Status::Ok();

  Status status = ValidateTissue(tissue, settings);
  TetMesh mesh;
  Materials materials;
  if (status) {
    ToTetMesh(tissue, mesh);
    status = ToMaterials(tissue, settings, materials);
  }
  // LipSeal: the facing surfaces within the gap tied by bridging cells, which the solvers take as
  // tissue; the output keeps the input's cells.
  LipSealInfo lipSeal;
  if (status && settings.sealGap() > 0.0) {
    LipSealOptions options;
    options.gap = settings.sealGap();
    TetMesh sealed;
    Materials sealedMaterials;
    status = AddLipSeal(mesh, materials, options, sealed, sealedMaterials, lipSeal);
    mesh = std::move(sealed);
    materials = std::move(sealedMaterials);
  }
  if (!status) {
    valid_ = false;
    return status;
  }
  // A new stamp with the content of the last one (an upstream filter re-executed, a copied data
  // set) keeps the generation, and with it the contact and the precompute.
  const bool sameMesh = valid_ && SameMatrix(mesh.points, mesh_.points) &&
                        SameMatrix(mesh.tets, mesh_.tets) && !boundary_.nodes.empty();
  const bool sameMaterials = valid_ && SameMaterials(materials, materials_);
  if (!sameMesh) {
    boundary_ = ExtractBoundary(tissue);
    mesh_ = std::move(mesh);
  }
  if (!sameMesh || !sameMaterials) {
    materials_ = std::move(materials);
    ++generation_;
  }
  lipSeal_ = lipSeal;
  stamp_ = std::move(stamp);
  materialSettings_ = materialSettings;
  valid_ = true;
  return Status::Ok();
}

} // namespace fem_filter
} // namespace faceplan
