// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Runs CalculiX (ccx, C3D4, *STATIC) on the same mesh and boundary conditions as a FacePlan
// solve, as an outside peer, and reads back the kept nodes' displacements (global axes). Sliding
// nodes get a local system with the normal as its x axis (*TRANSFORM) and only that DOF prescribed;
// the system is fixed, as the FacePlan models keep the undeformed normal. One *MATERIAL per
// distinct (E, nu).
#include "CondensedFEM/CondensedFEM.h"

#include <string>

namespace faceplan::bench {

enum class CalculixModel {
  LinearElastic, // *ELASTIC, linear geometry: the peer of Solve
  // *HYPERELASTIC, NEO HOOKE (C10 = mu / 2, D1 = 2 / kappa for the small-strain limit E, nu) with
  // NLGEOM: the peer of SolveLargeDeformation. ccx ramps the prescribed values over the step.
  NeoHookean,
};

struct CalculixOptions {
  CalculixModel model = CalculixModel::LinearElastic;
  int threads = 1;
  // NeoHookean: the step's increments as fractions of it (*STATIC: initial, minimum, maximum).
  double initialIncrement = 0.1;
  double minimumIncrement = 1e-5;
  double maximumIncrement = 0.25;
  // NeoHookean: converged when the largest residual force is at most this fraction of the average
  // element nodal force (*CONTROLS, PARAMETERS=FIELD: R_alpha_n and R_alpha_p; ccx's defaults,
  // 0.005 and 0.02, leave errors far above the printed 7 digits).
  double residualTolerance = 1e-9;
};

struct CalculixResult {
  bool ok = false;
  std::string error;
  double wallMs = 0.0;           // ccx run alone (input already written)
  RowVectors3d keptDisplacement; // NodeSets::kept order, at the end of the step
};

// Writes <workDir>/job.inp, runs `ccx -i job` there and parses job.dat. The .dat prints 7
// significant digits (e13.6), so a displacement is known to 5e-7 of its size at best.
CalculixResult RunCalculix(const PrecomputeRequest& request, const RowVectors3d& movable,
                           const std::string& workDir, const CalculixOptions& options);

// The linear model with `threads` threads.
CalculixResult RunCalculix(const PrecomputeRequest& request, const RowVectors3d& movable,
                           const std::string& workDir, int threads);

} // namespace faceplan::bench
