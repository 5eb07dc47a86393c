// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Step 5 of CondensedFEMDeform: the deformed tissue (every tetrahedron, or the boundary surface
// only), its field data and the stage-timing table. Private to FacePlan::Filters.
#include "CondensedFEMDeformConvert.h"
#include "CondensedFEMDeformSolver.h"

class vtkTable;
class vtkUnstructuredGrid;

namespace faceplan {
namespace fem_filter {

// Volume: the tissue's cells with moved points. Surface: the boundary triangles. The cells are
// shared with the tissue or the cached boundary; only points and Displacement are new.
void BuildDeformedTissue(vtkUnstructuredGrid* tissue, const TissueBoundary& boundary,
                         const RowVectors3d& restPoints, const SolveOutcome& outcome,
                         OutputMode mode, vtkUnstructuredGrid* output);

// RelativeResidual, SolveTimeMs, PrecomputeTimeMs, Method, Backend, diagnostics.
void AddFieldData(const SolveOutcome& outcome, const Settings& settings,
                  vtkUnstructuredGrid* output);

// Stage, TimeMs, Reused, Backend: one row per stage, like the paper's Table 2. `Total` is this
// update's time (the precompute's stages when this update ran them, and the solve); a last row
// `PrecomputeTotal` is the precompute's total, whether it ran now or was reused.
void BuildStageTable(const SolveOutcome& outcome, vtkTable* table);

} // namespace fem_filter
} // namespace faceplan
