// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The ICAT 2008 paper's "traditional" route, as a historical baseline: no condensation and no
// cache; the free nodes are renumbered by reverse Cuthill-McKee, the whole free stiffness is
// assembled into symmetric band storage and factored by LAPACK's band Cholesky (dpbtrf/dpbtrs)
// on one thread. Every stage runs on one thread and is timed like the paper's Table 2.
//
// LAPACK is looked up at run time (dlsym, then dlopen of liblapack.so.3), so FacePlanCore needs no
// extra link dependency; CHOLMOD already loads the system LAPACK (OpenBLAS on Debian). A machine
// without LAPACK gets an error status, never a crash.
#include "CondensedFEM/CondensedFEM.h"

namespace faceplan {

struct TraditionalBandOptions {
  double maxBandBytes = 4.0e9;    // refuse larger band matrices
  double maxFactorFlops = 1.0e12; // refuse factorizations estimated above this (n * kd^2)
  bool recoverAll = false;        // also return every node's displacement
};

struct TraditionalBandResult {
  RowVectors3d keptDisplacement; // NodeSets::kept order
  RowVectors3d allDisplacement;  // n x 3 when recoverAll
  double reorderingMs = 0, elementStiffnessMs = 0, assemblyMs = 0, boundaryConditionMs = 0,
         factorizationMs = 0, solveMs = 0, totalMs = 0;
  long long freeDofs = 0;
  int semiBandwidth = 0;       // in DOFs, after reordering
  int semiBandwidthBefore = 0; // in DOFs, in the mesh's own numbering
  double bandBytes = 0.0;
  double relativeResidual = 0.0; // of the band system, in double
};

// True when LAPACK's dpbtrf/dpbtrs can be found in this process.
bool BandLapackAvailable(std::string* why = nullptr);

Status SolveTraditionalBand(const PrecomputeRequest& request, const RowVectors3d& movable,
                            TraditionalBandResult& result,
                            const TraditionalBandOptions& options = {});

} // namespace faceplan
