// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The report's scenes: the face-like shell, the refined hollow sphere with its analytic solution,
// and the meshes of Data/ (organs, face), each with its precompute request and a surgical edit.
#include "CondensedFEM/CondensedFEM.h"
#include "Report/Statistics.h"
#include "Support/AnalyticHollowSphere.h"

#include <string>

namespace faceplan::report {

struct Scene {
  std::string name, family, description;
  PrecomputeRequest request;
  RowVectors3d edit;
  bool analytic = false;
  HollowSphere exact;
  double h = kNaN; // mesh size (analytic family)
  bool large = false;
};

// shell<N>k: the face-like shell with the given subdivisions and layers.
Scene FaceLikeShell(const std::string& name, int subdivisions, int layers);
// sphere<level>: the hollow sphere at refinement `level`.
Scene Sphere(int level);
// A mesh of Data/ (face: the face tissue with its bone contact; otherwise an organ).
bool DataScene(const std::string& name, const std::string& path, bool face, Scene& s,
               std::string& error);

} // namespace faceplan::report
