// SPDX-License-Identifier: BSD-3-Clause
#include "TissueModelFromCT/TissueLabelling.h"

#include "TissueModelFromCT/VoxelComponents.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <deque>
#include <string>
#include <vector>

namespace faceplan {

double LabellingSummary::softTissueVolume() const {
  return double(softTissueVoxels) * voxelVolume;
}

namespace {

using Mask = std::vector<std::uint8_t>;

// Morphological erosion with the 6-neighbourhood (a voxel stays when it and its face neighbours
// are set; voxels on the image border are eroded).
Mask Erode(const Mask& in, const std::array<int, 3>& d) {
  Mask out(in.size(), 0);
  for (int k = 1; k + 1 < d[2]; ++k)
    for (int j = 1; j + 1 < d[1]; ++j)
      for (int i = 1; i + 1 < d[0]; ++i) {
        const std::size_t v =
            std::size_t(i) + std::size_t(d[0]) * (std::size_t(j) + std::size_t(d[1]) * k);
        const std::size_t sx = 1, sy = std::size_t(d[0]), sz = std::size_t(d[0]) * d[1];
        out[v] = in[v] && in[v - sx] && in[v + sx] && in[v - sy] && in[v + sy] && in[v - sz] &&
                 in[v + sz];
      }
  return out;
}

// Splits `bone` into the two largest pieces of its opening, each grown back over the bone voxels
// nearest to it (breadth-first within the bone). Returns false when the opening leaves fewer than
// two pieces.
bool SplitMandible(const std::array<int, 3>& dims, int radius, std::vector<std::uint8_t>& labels) {
  Mask bone(labels.size());
  for (std::size_t v = 0; v < labels.size(); ++v)
    bone[v] = labels[v] == kBone;
  Mask core = bone;
  for (int r = 0; r < radius; ++r)
    core = Erode(core, dims);
  VoxelComponents pieces = FindComponents(core, dims);
  if (pieces.sizes.size() < 2)
    return false;
  std::vector<int> order(pieces.sizes.size());
  for (std::size_t c = 0; c < order.size(); ++c)
    order[c] = int(c);
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return pieces.sizes[a] > pieces.sizes[b]; });
  const int largest = order[0], second = order[1];
  // Owner 1 = the rest of the bone, 2 = mandible; grown outwards from the two cores together.
  std::vector<std::uint8_t> owner(labels.size(), 0);
  std::deque<std::size_t> queue;
  for (std::size_t v = 0; v < labels.size(); ++v) {
    if (pieces.id[v] == largest)
      owner[v] = 1;
    else if (pieces.id[v] == second)
      owner[v] = 2;
    if (owner[v])
      queue.push_back(v);
  }
  const long long sx = 1, sy = dims[0], sz = (long long)dims[0] * dims[1];
  while (!queue.empty()) {
    const std::size_t v = queue.front();
    queue.pop_front();
    const long long i = (long long)(v % dims[0]), j = (long long)((v / dims[0]) % dims[1]),
                    k = (long long)(v / sz);
    const long long steps[6] = {-sx, sx, -sy, sy, -sz, sz};
    const bool inside[6] = {i > 0, i + 1 < dims[0], j > 0, j + 1 < dims[1], k > 0, k + 1 < dims[2]};
    for (int n = 0; n < 6; ++n) {
      if (!inside[n])
        continue;
      const std::size_t w = std::size_t((long long)v + steps[n]);
      if (bone[w] && !owner[w]) {
        owner[w] = owner[v];
        queue.push_back(w);
      }
    }
  }
  for (std::size_t v = 0; v < labels.size(); ++v)
    if (owner[v] == 2)
      labels[v] = kMandible;
  return true;
}

} // namespace

LabellingSummary SummariseLabels(const LabelImage& image) {
  LabellingSummary s;
  s.voxelVolume = image.grid.voxelVolume();
  for (std::uint8_t l : image.labels) {
    if (l == kAir)
      ++s.airVoxels;
    else if (l == kSoftTissue)
      ++s.softTissueVoxels;
    else if (l == kBone)
      ++s.boneVoxels;
    else if (l == kMandible)
      ++s.mandibleVoxels;
  }
  // Faces between voxels of different labels, and of labelled voxels on the image's border.
  const ImageGrid& g = image.grid;
  const double faceArea[3] = {g.spacing[1] * g.spacing[2], g.spacing[0] * g.spacing[2],
                              g.spacing[0] * g.spacing[1]};
  for (int k = 0; k < g.dims[2]; ++k)
    for (int j = 0; j < g.dims[1]; ++j)
      for (int i = 0; i < g.dims[0]; ++i) {
        const std::uint8_t l = image.labels[g.index(i, j, k)];
        const int at[3] = {i, j, k};
        for (int a = 0; a < 3; ++a) {
          if (at[a] + 1 < g.dims[a]) {
            const std::uint8_t m = image.labels[g.index(i + (a == 0), j + (a == 1), k + (a == 2))];
            s.interfaceArea += l != m ? faceArea[a] : 0.0;
          }
          if (l != kAir && (at[a] == 0 || at[a] + 1 == g.dims[a]))
            s.interfaceArea += faceArea[a];
        }
      }
  return s;
}

Status ValidateImageGrid(const ImageGrid& g) {
  if (!g.direction.allFinite() ||
      !(g.direction.transpose() * g.direction).isApprox(Eigen::Matrix3d::Identity(), 1e-6))
    return Status::Error(
        "the image's direction matrix must be orthonormal (a rotation, possibly mirrored)");
  for (int a = 0; a < 3; ++a)
    if (!(g.spacing[a] > 0.0) || !std::isfinite(g.spacing[a]))
      return Status::Error("the image spacing must be positive and finite (axis " +
                           std::to_string(a) + ": " + std::to_string(g.spacing[a]) + ")");
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(g.origin[a]))
      return Status::Error("the image origin must be finite");
  return Status::Ok();
}

Status LabelTissue(const CTImage& ct, const LabellingOptions& options, LabelImage& out,
                   LabellingSummary& summary) {
  const auto& d = ct.grid.dims;
  if (d[0] < 2 || d[1] < 2 || d[2] < 2)
    return Status::Error("the image must have at least 2 voxels along each axis");
  const std::size_t n = ct.grid.numVoxels();
  if (ct.hounsfield.size() != n)
    return Status::Error("the image has " + std::to_string(ct.hounsfield.size()) + " values for " +
                         std::to_string(n) + " voxels");
  if (Status s = ValidateImageGrid(ct.grid); !s)
    return s;
  std::size_t nonFinite = 0, firstNonFinite = 0;
  for (std::size_t v = 0; v < n; ++v)
    if (!std::isfinite(ct.hounsfield[v]) && nonFinite++ == 0)
      firstNonFinite = v;
  if (nonFinite > 0)
    return Status::Error("the CT holds " + std::to_string(nonFinite) +
                         " non-finite values (NaN or inf), the first at voxel " +
                         std::to_string(firstNonFinite));
  if (!(options.skinThreshold < options.boneThreshold))
    return Status::Error(
        "thresholds in the wrong order: SkinThreshold must be below BoneThreshold");

  const double voxel = ct.grid.voxelVolume();
  long long aboveBone = 0;
  Mask body(n);
  for (std::size_t v = 0; v < n; ++v) {
    body[v] = ct.hounsfield[v] >= options.skinThreshold;
    aboveBone += ct.hounsfield[v] >= options.boneThreshold;
  }
  if (aboveBone == 0)
    return Status::Error("no voxel at or above BoneThreshold");

  summary = LabellingSummary();
  summary.voxelVolume = voxel;
  if (options.keepLargestComponent)
    KeepLargestComponent(body, d);
  // Enclosed air pockets become body.
  {
    Mask air(n);
    for (std::size_t v = 0; v < n; ++v)
      air[v] = !body[v];
    const VoxelComponents pockets = FindComponents(air, d);
    for (std::size_t v = 0; v < n; ++v)
      if (pockets.id[v] >= 0 && !pockets.touchesBorder[pockets.id[v]]) {
        body[v] = 1;
        ++summary.cavityVoxelsFilled;
      }
  }

  Mask bone(n);
  for (std::size_t v = 0; v < n; ++v)
    bone[v] = body[v] && ct.hounsfield[v] >= options.boneThreshold;
  {
    const VoxelComponents pieces = FindComponents(bone, d);
    std::vector<std::uint8_t> keep(pieces.sizes.size());
    for (std::size_t c = 0; c < keep.size(); ++c) {
      keep[c] = double(pieces.sizes[c]) * voxel >= options.minimumBoneComponentVolume;
      summary.bonePieces += keep[c];
    }
    for (std::size_t v = 0; v < n; ++v)
      if (bone[v] && !keep[pieces.id[v]])
        bone[v] = 0;
  }
  if (options.fillBoneHoles) {
    Mask notBone(n);
    for (std::size_t v = 0; v < n; ++v)
      notBone[v] = !bone[v];
    const VoxelComponents holes = FindComponents(notBone, d);
    for (std::size_t v = 0; v < n; ++v) {
      const int c = holes.id[v];
      if (c >= 0 && !holes.touchesBorder[c] &&
          double(holes.sizes[c]) * voxel <= options.maximumBoneHoleVolume) {
        bone[v] = 1;
        body[v] = 1;
        ++summary.boneHoleVoxelsFilled;
      }
    }
  }

  out.grid = ct.grid;
  out.labels.assign(n, kAir);
  for (std::size_t v = 0; v < n; ++v)
    out.labels[v] = bone[v] ? kBone : (body[v] ? kSoftTissue : kAir);
  if (options.separateMandible)
    summary.mandibleSeparated = SplitMandible(d, std::max(1, options.openingRadius), out.labels);

  const LabellingSummary counts = SummariseLabels(out);
  summary.airVoxels = counts.airVoxels;
  summary.softTissueVoxels = counts.softTissueVoxels;
  summary.interfaceArea = counts.interfaceArea;
  summary.boneVoxels = counts.boneVoxels;
  summary.mandibleVoxels = counts.mandibleVoxels;
  if (summary.boneVoxels + summary.mandibleVoxels == 0)
    return Status::Error(
        "no voxel at or above BoneThreshold is left after removing bone pieces smaller than " +
        std::to_string(options.minimumBoneComponentVolume) + " mm^3");
  if (summary.softTissueVoxels == 0)
    return Status::Error(
        "the soft-tissue label is empty (no voxel between SkinThreshold and BoneThreshold)");
  return Status::Ok();
}

} // namespace faceplan
