#pragma once
// Runs CalculiX (ccx, C3D4, *STATIC) on the same mesh and boundary conditions as a FacePlan
// solve, as an outside peer, and reads back the kept nodes' displacements (global axes). Sliding
// nodes get a local system with the normal as its x axis (*TRANSFORM) and only that DOF prescribed.
#include "CondensedFEM/CondensedFEM.h"

#include <string>

namespace faceplan::bench {

struct CalculixResult {
  bool ok = false;
  std::string error;
  double wallMs = 0.0;         // ccx run alone (input already written)
  RowVectors3d keptDisplacement; // NodeSets::kept order
};

// Writes <workDir>/job.inp, runs `ccx -i job` there and parses job.dat.
CalculixResult RunCalculix(const PrecomputeRequest& request, const RowVectors3d& movable,
                           const std::string& workDir, int threads);

} // namespace faceplan::bench
