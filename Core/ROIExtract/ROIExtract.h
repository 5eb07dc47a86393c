// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Region of interest on a surface: which vertices may move, and which of them border the rest.
#include "Common/Status.h"
#include "Mesh/SurfaceMesh.h"

#include <cstdint>
#include <vector>

namespace faceplan {

struct ROIResult {
  std::vector<std::uint8_t> mask;     // ROIMask: 1 for ROI vertices
  std::vector<std::uint8_t> boundary; // ROIBoundary: 1 for ROI vertices sharing an edge with a
                                      // non-ROI vertex (these never move)
  std::int64_t numROI = 0;
  std::int64_t numBoundary = 0;
};

// Checks the mesh: offsets monotone and consistent with connectivity, ids in range,
// coordinates finite. Shared by ROI and cut.
Status ValidateSurfaceMesh(const SurfaceMesh& mesh);

// selected: one entry per point, nonzero = in the ROI. Edges are those of the cells (see
// SurfaceMesh). Fails (with an empty result) on a malformed mesh or a selection of the wrong size.
Status ComputeROI(const SurfaceMesh& mesh, const std::vector<std::uint8_t>& selected,
                  ROIResult& result);

// The same from a list of point ids (out-of-range ids are an error naming the first one).
Status ComputeROIFromIds(const SurfaceMesh& mesh, const std::vector<std::int64_t>& ids,
                         ROIResult& result);

} // namespace faceplan
