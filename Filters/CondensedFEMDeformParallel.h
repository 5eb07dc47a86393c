// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// CondensedFEMDeform under MPI (pvbatch or pvserver with more than one process). The tissue and
// bone pieces are gathered on the solving rank (FacePlanGather), which runs the serial steps on
// the whole and keeps the precompute cached there, so an edit re-solves exactly as in serial.
// Volume output: every rank gets its own piece back (its points and cells, moved, with their
// Displacement). Surface output: every rank gets the boundary triangles of its own tetrahedra.
// Field data and the stage table are the same on every rank. An error is logged once, by the
// solving rank; every rank's outputs are then empty. Private to FacePlan::Filters.
#include "CondensedFEMDeformSettings.h"

#include <functional>

class vtkMultiProcessController;
class vtkPointSet;
class vtkTable;
class vtkUnstructuredGrid;

namespace faceplan {
namespace fem_filter {

// The serial filter on whole inputs: false (after logging the error) when it failed.
using DeformWhole = std::function<bool(vtkUnstructuredGrid* tissue, vtkPointSet* bone,
                                       vtkUnstructuredGrid* output, vtkTable* table)>;

// Rank 0 solves, with every backend: ParaView's rank 0 is also the rank that talks to the client
// and the one a GPU node's launcher gives the first device to (give only rank 0 a GPU, e.g.
// CUDA_VISIBLE_DEVICES per rank, when Backend = CUDA). A fixed rank keeps the cached precompute
// where the next edit runs.
int SolvingRank(vtkMultiProcessController* controller);

// Collective: every rank calls it with its own pieces.
void DeformGathered(vtkMultiProcessController* controller, OutputMode mode,
                    vtkUnstructuredGrid* tissue, vtkPointSet* bone, vtkUnstructuredGrid* output,
                    vtkTable* table, const DeformWhole& deform);

} // namespace fem_filter
} // namespace faceplan
