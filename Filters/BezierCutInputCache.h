// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// BezierCut's input validated and converted, with everything that depends on the bone and its ROI
// alone: the surface mesh, ROIMask/ROIBoundary as flags, Core's cut topology (edge neighbours,
// fan triangles), the default curves and the points in double precision. It is rebuilt only when
// the input's stamp (FacePlanDataStamp.h) changes, so that an edit of the control points redoes
// only the cut itself. Private to FacePlan::Filters.
#include "FacePlanDataStamp.h"

#include "BezierCut/BezierCut.h"
#include "Common/Status.h"
#include "Mesh/SurfaceMesh.h"

#include "vtkSmartPointer.h"
#include "vtkType.h"

#include <Eigen/Core>

#include <cstdint>
#include <vector>

class vtkDoubleArray;
class vtkPointSet;

namespace faceplan {
namespace bezier_filter {

class InputCache {
public:
  // Validates and converts `input` unless it carries the stamp of the last successful call; an
  // error leaves the cache empty, so the next call validates again.
  Status update(vtkPointSet* input);

  const SurfaceMesh& mesh() const { return mesh_; }
  const CutMeshTopology& topology() const { return topology_; }
  const std::vector<std::uint8_t>& mask() const { return mask_; }
  const std::vector<std::uint8_t>& boundary() const { return boundary_; }
  // Line and vertex cells, which the cut ignores.
  vtkIdType skippedCells() const { return skipped_; }
  // The curves the filter uses until the user places its own (false: the ROI has no extent).
  bool hasDefaultCurves() const { return hasDefaults_; }
  const std::vector<Eigen::Vector3d>& defaultCurveU() const { return defaultU_; }
  const std::vector<Eigen::Vector3d>& defaultCurveV() const { return defaultV_; }
  // The input's points as doubles (n x 3), copied into each output.
  vtkDoubleArray* points() const { return points_; }
  // How many times the input was converted (tests check that an edit of the curves does not).
  unsigned long conversions() const { return conversions_; }

private:
  Status convert(vtkPointSet* input);

  bool valid_ = false;
  DataStamp stamp_;
  SurfaceMesh mesh_;
  CutMeshTopology topology_;
  std::vector<std::uint8_t> mask_, boundary_;
  vtkIdType skipped_ = 0;
  bool hasDefaults_ = false;
  std::vector<Eigen::Vector3d> defaultU_, defaultV_;
  vtkSmartPointer<vtkDoubleArray> points_;
  unsigned long conversions_ = 0;
};

} // namespace bezier_filter
} // namespace faceplan
