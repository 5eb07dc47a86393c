#pragma once
// Step 5 of CondensedFEMDeform: the deformed tissue (every tetrahedron, or the boundary surface
// only), its field data and the stage-timing table. Private to FacePlan::Filters.
#include "CondensedFEMDeformConvert.h"
#include "CondensedFEMDeformSolver.h"

class vtkTable;
class vtkUnstructuredGrid;

namespace faceplan {
namespace fem_filter {

// Volume: the tissue's cells with moved points. Surface: the boundary triangles.
void BuildDeformedTissue(vtkUnstructuredGrid* tissue, const TissueBoundary& boundary,
                         const Points& restPoints, const SolveOutcome& outcome, OutputMode mode,
                         vtkUnstructuredGrid* output);

// RelativeResidual, SolveTimeMs, PrecomputeTimeMs, Method, Backend, diagnostics.
void AddFieldData(const SolveOutcome& outcome, const Settings& settings,
                  vtkUnstructuredGrid* output);

// Stage, TimeMs, Reused, Backend: one row per stage, like the paper's Table 2.
void BuildStageTable(const SolveOutcome& outcome, vtkTable* table);

} // namespace fem_filter
} // namespace faceplan
