// SPDX-License-Identifier: BSD-3-Clause
#include "ROIExtract/ROIExtract.h"

#include <cmath>
#include <string>

namespace faceplan {

Status ValidateSurfaceMesh(const SurfaceMesh& mesh) {
  const std::int64_t n = mesh.numPoints();
  if (!mesh.points.allFinite()) {
    for (std::int64_t i = 0; i < n; ++i)
      if (!mesh.points.row(i).allFinite())
        return Status::Error("surface point " + std::to_string(i) + " has a non-finite coordinate");
  }
  if (mesh.offsets.empty()) {
    if (!mesh.connectivity.empty())
      return Status::Error("surface cells: connectivity given without offsets");
    return Status::Ok();
  }
  if (mesh.offsets.front() != 0)
    return Status::Error("surface cells: offsets[0] must be 0");
  if (mesh.offsets.back() != std::int64_t(mesh.connectivity.size()))
    return Status::Error("surface cells: last offset " + std::to_string(mesh.offsets.back()) +
                         " differs from the connectivity size " +
                         std::to_string(mesh.connectivity.size()));
  for (std::size_t c = 0; c + 1 < mesh.offsets.size(); ++c)
    if (mesh.offsets[c + 1] < mesh.offsets[c])
      return Status::Error("surface cells: offsets decrease at cell " + std::to_string(c));
  for (std::size_t k = 0; k < mesh.connectivity.size(); ++k) {
    const std::int64_t id = mesh.connectivity[k];
    if (id < 0 || id >= n)
      return Status::Error("surface cells: point id " + std::to_string(id) + " out of range [0, " +
                           std::to_string(n) + ")");
  }
  return Status::Ok();
}

Status ComputeROI(const SurfaceMesh& mesh, const std::vector<std::uint8_t>& selected,
                  ROIResult& result) {
  result = ROIResult{};
  Status s = ValidateSurfaceMesh(mesh);
  if (!s)
    return s;
  const std::int64_t n = mesh.numPoints();
  if (std::int64_t(selected.size()) != n)
    return Status::Error("ROI selection has " + std::to_string(selected.size()) + " entries for " +
                         std::to_string(n) + " points");

  std::vector<std::uint8_t> mask(n), boundary(n, 0);
  for (std::int64_t i = 0; i < n; ++i)
    mask[i] = selected[i] ? 1 : 0;

  auto edge = [&](std::int64_t a, std::int64_t b) {
    if (mask[a] && !mask[b])
      boundary[a] = 1;
    if (mask[b] && !mask[a])
      boundary[b] = 1;
  };
  for (std::int64_t c = 0; c < mesh.numCells(); ++c) {
    const std::int64_t m = mesh.cellSize(c);
    const std::int64_t* ids = mesh.cell(c);
    if (m == 2) {
      edge(ids[0], ids[1]);
    } else if (m >= 3) {
      for (std::int64_t k = 0; k < m; ++k)
        edge(ids[k], ids[(k + 1) % m]);
    }
  }
  result.mask = std::move(mask);
  result.boundary = std::move(boundary);
  for (std::int64_t i = 0; i < n; ++i) {
    result.numROI += result.mask[i];
    result.numBoundary += result.boundary[i];
  }
  return Status::Ok();
}

Status ComputeROIFromIds(const SurfaceMesh& mesh, const std::vector<std::int64_t>& ids,
                         ROIResult& result) {
  result = ROIResult{};
  const std::int64_t n = mesh.numPoints();
  std::vector<std::uint8_t> selected(n, 0);
  for (std::int64_t id : ids) {
    if (id < 0 || id >= n)
      return Status::Error("ROI point id " + std::to_string(id) + " out of range [0, " +
                           std::to_string(n) + ")");
    selected[id] = 1;
  }
  return ComputeROI(mesh, selected, result);
}

} // namespace faceplan
