// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// CGAL Mesh_3 mesher of labelled images (GPL-3: this part is built only with FACEPLAN_ENABLE_CGAL).
// Meshes the image from memory, in its physical frame (origin, spacing, direction), then
// optimises (ODT or Lloyd), perturbs and exudes. Matches faceplan::LabelMesher.
#include "TissueModelFromCT/LabeledMesher.h"

namespace faceplan {
namespace cgal {

Status MeshLabeledImage(const LabelImage& image, const MeshingParameters& parameters,
                        LabeledTetMesh& result, std::atomic<bool>* cancel,
                        const MeshingProgress& progress);

// The CGAL version this part was built with, e.g. "5.5.1".
const char* CgalVersion();

} // namespace cgal
} // namespace faceplan
