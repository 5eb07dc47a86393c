#include "CondensedFEMDeformParallel.h"

#include "FacePlanGather.h"

#include "vtkFieldData.h"
#include "vtkMultiProcessController.h"
#include "vtkNew.h"
#include "vtkPolyData.h"
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
  vtkNew<vtkPolyData> fieldCarrier;
  if (tissues.IsRoot()) {
    output->ShallowCopy(wholeOutput);
    fieldCarrier->GetFieldData()->ShallowCopy(wholeOutput->GetFieldData());
  }
  gather::BroadcastFromRoot(controller, root, fieldCarrier);
  if (!tissues.IsRoot()) {
    output->Initialize();
    output->GetFieldData()->ShallowCopy(fieldCarrier->GetFieldData());
  }
}

} // namespace fem_filter
} // namespace faceplan
