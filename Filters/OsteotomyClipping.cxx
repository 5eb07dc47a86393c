// SPDX-License-Identifier: BSD-3-Clause
#include "OsteotomyClipping.h"

#include <vtkAppendPolyData.h>
#include <vtkClipClosedSurface.h>
#include <vtkNew.h>
#include <vtkPlane.h>
#include <vtkPlaneCollection.h>
#include <vtkPolyData.h>
#include <vtkTriangleFilter.h>

namespace faceplan {
namespace osteotomy_filter {

vtkSmartPointer<vtkPolyData> ClipIntoPieces(vtkPolyData* bone,
                                            const std::vector<ConvexPiece>& pieces,
                                            std::vector<std::uint8_t>& moves) {
  moves.clear();
  vtkNew<vtkAppendPolyData> append;
  append->SetOutputPointsPrecision(vtkAlgorithm::DOUBLE_PRECISION);
  for (const ConvexPiece& piece : pieces) {
    vtkNew<vtkPlaneCollection> planes;
    for (const CutPlane& h : piece.bounds) {
      // vtkClipClosedSurface keeps the side its plane normals point to.
      vtkNew<vtkPlane> plane;
      plane->SetOrigin(h.origin.data());
      plane->SetNormal(h.normal.data());
      planes->AddItem(plane);
    }
    vtkNew<vtkClipClosedSurface> clip;
    clip->SetInputData(bone);
    clip->SetClippingPlanes(planes);
    clip->PassPointDataOn();
    clip->GenerateFacesOn();
    clip->GenerateOutlineOff();
    vtkNew<vtkTriangleFilter> triangles;
    triangles->SetInputConnection(clip->GetOutputPort());
    triangles->PassLinesOff();
    triangles->PassVertsOff();
    triangles->Update();
    vtkPolyData* out = triangles->GetOutput();
    if (out->GetNumberOfPoints() == 0 || out->GetNumberOfPolys() == 0)
      continue;
    vtkNew<vtkPolyData> copy;
    copy->ShallowCopy(out);
    append->AddInputData(copy);
    moves.insert(moves.end(), static_cast<std::size_t>(out->GetNumberOfPoints()),
                 piece.moves ? 1 : 0);
  }
  vtkSmartPointer<vtkPolyData> result = vtkSmartPointer<vtkPolyData>::New();
  if (append->GetNumberOfInputConnections(0) == 0)
    return result;
  append->Update();
  result->ShallowCopy(append->GetOutput());
  return result;
}

} // namespace osteotomy_filter
} // namespace faceplan
