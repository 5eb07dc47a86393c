// SPDX-License-Identifier: BSD-3-Clause
#include "CondensedFEMDeformParallel.h"

#include "FacePlanGather.h"

#include "vtkDataArray.h"
#include "vtkIdList.h"
#include "vtkMultiProcessController.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkTable.h"
#include "vtkUnstructuredGrid.h"

namespace faceplan {
namespace fem_filter {

int SolvingRank(vtkMultiProcessController*) {
  return 0;
}

void DeformGathered(vtkMultiProcessController* controller, OutputMode mode,
                    vtkUnstructuredGrid* tissue, vtkPointSet* bone, vtkUnstructuredGrid* output,
                    vtkTable* table, const DeformWhole& deform) {
  const int root = SolvingRank(controller);
  const gather::GatheredPieces tissues(controller, tissue, root);
  const gather::GatheredPieces bones(controller, bone, root);

  vtkNew<vtkUnstructuredGrid> wholeOutput;
  std::string failure;
  if (tissues.IsRoot() && !deform(vtkUnstructuredGrid::SafeDownCast(tissues.Whole()), bones.Whole(),
                                  wholeOutput, table))
    failure = "CondensedFEMDeform failed on the solving rank";
  if (!gather::ShareRootMessage(controller, root, failure).empty()) {
    output->Initialize();
    table->Initialize();
    return;
  }

  gather::BroadcastFromRoot(controller, root, table);
  if (mode == OutputMode::Volume) {
    tissues.ScatterTo(wholeOutput, output);
    return;
  }
  // Surface: each boundary triangle goes to the rank that owns the tetrahedron it bounds.
  std::vector<int> owner;
  if (tissues.IsRoot()) {
    auto* whole = vtkUnstructuredGrid::SafeDownCast(tissues.Whole());
    vtkDataArray* wholeIds = wholeOutput->GetPointData()->GetArray("vtkOriginalPointIds");
    whole->BuildLinks();
    vtkNew<vtkIdList> points, cells;
    owner.assign(static_cast<std::size_t>(wholeOutput->GetNumberOfCells()), root);
    for (vtkIdType c = 0; wholeIds && c < wholeOutput->GetNumberOfCells(); ++c) {
      wholeOutput->GetCellPoints(c, points);
      for (vtkIdType k = 0; k < points->GetNumberOfIds(); ++k)
        points->SetId(k, static_cast<vtkIdType>(wholeIds->GetComponent(points->GetId(k), 0)));
      whole->GetCellNeighbors(-1, points, cells);
      if (cells->GetNumberOfIds() > 0)
        owner[static_cast<std::size_t>(c)] = tissues.CellOwner(cells->GetId(0));
    }
  }
  tissues.ScatterCells(wholeOutput, owner, output);
}

} // namespace fem_filter
} // namespace faceplan
