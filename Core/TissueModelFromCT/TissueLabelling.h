// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Labels the voxels of a CT volume as air, soft tissue or bone (optionally mandible) by thresholds,
// connected components and cavity filling. 6-connectivity throughout.
#include "Common/Status.h"
#include "TissueModelFromCT/LabelImage.h"

namespace faceplan {

struct LabellingOptions {
  double boneThreshold = 200.0;  // HU: voxels at or above are bone
  double skinThreshold = -400.0; // HU: voxels at or above are body (soft tissue or bone)
  // Keep only the largest connected body (drops the table, head rest, noise).
  bool keepLargestComponent = true;
  // Bone pieces smaller than this are soft tissue (noise, calcifications), mm^3.
  double minimumBoneComponentVolume = 50.0;
  // Enclosed non-bone pockets of the bone (marrow, canals) up to this volume become bone, mm^3;
  // the limit keeps the brain inside the skull soft tissue.
  bool fillBoneHoles = true;
  double maximumBoneHoleVolume = 2000.0;
  // Split the bone into mandible (label 3) and the rest (label 2): the second-largest piece after
  // a morphological opening of `openingRadius` voxels, grown back within the bone.
  bool separateMandible = false;
  int openingRadius = 1;
};

struct LabellingSummary {
  long long airVoxels = 0, softTissueVoxels = 0, boneVoxels = 0, mandibleVoxels = 0;
  long long cavityVoxelsFilled = 0; // enclosed air made soft tissue
  long long boneHoleVoxelsFilled = 0;
  int bonePieces = 0; // connected bone pieces kept
  bool mandibleSeparated = false;
  double softTissueVolume() const; // set by LabelTissue together with the voxel volume
  double voxelVolume = 0.0;
  double interfaceArea = 0.0; // voxel faces between labels (air outside the image), area units
};

// Spacing positive and finite, origin finite, direction orthonormal.
Status ValidateImageGrid(const ImageGrid& grid);

// Air-filled cavities fully enclosed by the body (sinuses cut off by the thresholds) always become
// soft tissue, so the skin surface is the outer surface only. Errors: "no voxel at or above
// BoneThreshold", "the soft-tissue label is empty", non-finite values, an invalid grid
// (ValidateImageGrid) and size mismatches.
Status LabelTissue(const CTImage& ct, const LabellingOptions& options, LabelImage& labels,
                   LabellingSummary& summary);

// Counts the voxels of each label and the area of the voxel faces between labels.
LabellingSummary SummariseLabels(const LabelImage& labels);

} // namespace faceplan
