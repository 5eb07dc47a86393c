// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Running a filter once on a whole dataset that ParaView has split into pieces across MPI
// processes (pvbatch or pvserver under mpiexec, RedistributeDataSet, D3, multi-piece files): the
// pieces are gathered on one process, which runs the filter as a serial session would, and every
// process gets the result back at its own points. ROIExtract, BezierCut and CondensedFEMDeform
// all gather: their checks (ROI connectivity, fold and intersection tests, the FEM solve) need the
// whole surface or mesh. Private to FacePlan::Filters.
#include "vtkSmartPointer.h"

#include <functional>
#include <string>
#include <vector>

class vtkDataObject;
class vtkMultiProcessController;
class vtkPointSet;
class vtkUnstructuredGrid;

namespace faceplan {
namespace gather {

// The global controller when it runs more than one process; null in a serial or builtin session
// and on a client (which runs no filters).
vtkMultiProcessController* DistributedController();

// False on the ranks other than 0 of a distributed run: an error that every rank meets alike (a
// wrong input type) is logged once.
bool LogsErrors();

// One dataset split across the processes, whole on the root. Collective: every process builds it
// with its own piece (which may be empty), in the same order as the other gathers.
//
// Ghost cells (vtkGhostType & DUPLICATECELL) are dropped. The seam points that several pieces
// share become one point: by point GlobalIds when every non-empty piece has them (the whole's
// points then follow GlobalIds order), otherwise by exactly coincident coordinates (first piece
// first). Cells follow cell GlobalIds order when every non-empty piece has them, else piece order.
class GatheredPieces {
public:
  GatheredPieces(vtkMultiProcessController* controller, vtkPointSet* piece, int root);

  bool IsRoot() const;
  // On the root: the merged pieces, of the piece's type; null elsewhere.
  vtkPointSet* Whole() const { return this->Whole_; }

  // Collective. `wholeResult` (read on the root only) has Whole()'s points in the same order.
  // `output` becomes this process's piece: its own cells and cell arrays, with the points, point
  // arrays and field data of `wholeResult` at its own points.
  void ScatterTo(vtkPointSet* wholeResult, vtkPointSet* output) const;

  // On the root: the process whose piece holds cell `wholeCell` of Whole().
  int CellOwner(vtkIdType wholeCell) const;

  // Collective. `output` becomes the cells of `wholeResult` (read on the root only) that
  // `owner[c]` gives to this process, with their points and arrays, and its field data.
  void ScatterCells(vtkUnstructuredGrid* wholeResult, const std::vector<int>& owner,
                    vtkUnstructuredGrid* output) const;

private:
  vtkMultiProcessController* Controller;
  int Root;
  vtkPointSet* Piece;
  vtkSmartPointer<vtkPointSet> Whole_;
  // On the root, per process: the whole's point id of each of that piece's points (-1 for a
  // point only ghost cells use, when no other piece owns it).
  std::vector<std::vector<vtkIdType>> PointMap;
  std::vector<vtkSmartPointer<vtkPointSet>> Pieces;
  std::vector<int> CellOwners; // on the root, per cell of Whole()
};

// Collective. The root's message (empty when it succeeded) on every process, so that every
// process fails together while only the root logs the error.
std::string ShareRootMessage(vtkMultiProcessController* controller, int root,
                             const std::string& message);

// Collective. `data` on every other process becomes a copy of the root's.
void BroadcastFromRoot(vtkMultiProcessController* controller, int root, vtkDataObject* data);

// The serial filter on the whole input, for a filter whose output keeps its input's points and
// cells (new point positions, point arrays and field data): false (after logging) on an error.
using RunWhole = std::function<bool(vtkPointSet* whole, vtkPointSet* wholeOutput)>;

// Collective. Gathers `piece` on rank 0, runs `run` there once and gives every process its own
// piece of the result in `output`. False on every process when `run` failed on rank 0; every
// `output` is then empty and only rank 0 has logged the error.
bool RunOnWhole(vtkMultiProcessController* controller, vtkPointSet* piece, vtkPointSet* output,
                const RunWhole& run);

} // namespace gather
} // namespace faceplan
