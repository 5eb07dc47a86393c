// SPDX-License-Identifier: BSD-3-Clause
#include "vtkTissueModelFromCT.h"

#include "Copyleft/CGAL/LabeledImageMesher.h"
#include "FacePlanFieldData.h"
#include "FacePlanGather.h"
#include "TissueModelFromCT/TissueModel.h"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkIdTypeArray.h>
#include <vtkImageData.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkIntArray.h>
#include <vtkMatrix3x3.h>
#include <vtkMultiProcessController.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkStreamingDemandDrivenPipeline.h>
#include <vtkUnstructuredGrid.h>

#include <atomic>
#include <cmath>
#include <vector>

vtkStandardNewMacro(vtkTissueModelFromCT);

namespace {

using faceplan::fielddata::AddScalar;

// A triangle surface over the tissue points its facets use, renumbered densely;
// TissuePointId maps back to the tissue.
void BuildSurface(const faceplan::TissueModel& model, const faceplan::Facets& facets,
                  const std::vector<int>* labels, vtkPolyData* out) {
  std::vector<vtkIdType> local(std::size_t(model.tissue.numPoints()), -1);
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  vtkNew<vtkIdTypeArray> tissueId;
  tissueId->SetName("TissuePointId");
  vtkNew<vtkCellArray> polys;
  for (Eigen::Index f = 0; f < facets.rows(); ++f) {
    vtkIdType ids[3];
    for (int k = 0; k < 3; ++k) {
      const int p = facets(f, k);
      vtkIdType& id = local[std::size_t(p)];
      if (id < 0) {
        id = points->InsertNextPoint(model.tissue.points(p, 0), model.tissue.points(p, 1),
                                     model.tissue.points(p, 2));
        tissueId->InsertNextValue(p);
      }
      ids[k] = id;
    }
    polys->InsertNextCell(3, ids);
  }
  out->SetPoints(points);
  out->SetPolys(polys);
  out->GetPointData()->AddArray(tissueId);
  if (labels) {
    vtkNew<vtkIntArray> label;
    label->SetName("Label");
    label->SetNumberOfTuples(vtkIdType(labels->size()));
    for (std::size_t c = 0; c < labels->size(); ++c)
      label->SetValue(vtkIdType(c), (*labels)[c]);
    out->GetCellData()->AddArray(label);
  }
}

} // namespace

vtkTissueModelFromCT::vtkTissueModelFromCT() {
  this->SetNumberOfOutputPorts(3);
}

vtkTissueModelFromCT::~vtkTissueModelFromCT() = default;

int vtkTissueModelFromCT::FillInputPortInformation(int, vtkInformation* info) {
  // Any data object, so that a wrong type gets this filter's own error message.
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkDataObject");
  return 1;
}

int vtkTissueModelFromCT::FillOutputPortInformation(int port, vtkInformation* info) {
  info->Set(vtkDataObject::DATA_TYPE_NAME(), port == 0 ? "vtkUnstructuredGrid" : "vtkPolyData");
  return 1;
}

int vtkTissueModelFromCT::RequestUpdateExtent(vtkInformation* request,
                                              vtkInformationVector** inputVector,
                                              vtkInformationVector* outputVector) {
  // Under MPI the whole CT is meshed once, on rank 0: ask for the whole image, not this rank's
  // slab of it (FacePlanGather.h says how the other filters gather).
  if (faceplan::gather::DistributedController()) {
    vtkInformation* inInfo = inputVector[0]->GetInformationObject(0);
    inInfo->Set(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER(), 0);
    inInfo->Set(vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_PIECES(), 1);
    if (inInfo->Has(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT()))
      inInfo->Set(vtkStreamingDemandDrivenPipeline::UPDATE_EXTENT(),
                  inInfo->Get(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT()), 6);
    return 1;
  }
  return this->Superclass::RequestUpdateExtent(request, inputVector, outputVector);
}

int vtkTissueModelFromCT::RequestData(vtkInformation*, vtkInformationVector** inputVector,
                                      vtkInformationVector* outputVector) {
  vtkUnstructuredGrid* tissueOut = vtkUnstructuredGrid::GetData(outputVector, 0);
  vtkPolyData* boneOut = vtkPolyData::GetData(outputVector, 1);
  vtkPolyData* skinOut = vtkPolyData::GetData(outputVector, 2);
  tissueOut->Initialize();
  boneOut->Initialize();
  skinOut->Initialize();
  // Under MPI rank 0 meshes the whole CT and holds the model; the other ranks' outputs are empty.
  if (vtkMultiProcessController* controller = faceplan::gather::DistributedController())
    if (controller->GetLocalProcessId() != 0)
      return 1;

  vtkDataObject* inputObject = vtkDataObject::GetData(inputVector[0], 0);
  vtkImageData* input = vtkImageData::SafeDownCast(inputObject);
  if (!input) {
    vtkErrorMacro(<< "Tissue Model From CT: the input is not an image (vtkImageData) but "
                  << (inputObject ? inputObject->GetClassName() : "nothing"));
    return 1;
  }
  if (input->GetNumberOfPoints() == 0) {
    vtkErrorMacro(<< "Tissue Model From CT: the image is empty (no voxels)");
    return 1;
  }
  vtkDataArray* scalars = this->GetInputArrayToProcess(0, inputVector);
  if (!scalars)
    scalars = input->GetPointData()->GetScalars();
  if (!scalars || scalars->GetNumberOfTuples() != input->GetNumberOfPoints()) {
    vtkErrorMacro(
        << "Tissue Model From CT: the image has no point scalars (the CT in Hounsfield units)");
    return 1;
  }
  if (scalars->GetNumberOfComponents() != 1) {
    vtkErrorMacro(<< "Tissue Model From CT: the CT scalars '"
                  << (scalars->GetName() ? scalars->GetName() : "") << "' have "
                  << scalars->GetNumberOfComponents()
                  << " components; one (Hounsfield units) is needed");
    return 1;
  }
  if (this->Optimiser < NONE || this->Optimiser > LLOYD) {
    vtkErrorMacro(<< "Tissue Model From CT: Optimiser " << this->Optimiser
                  << " is none of 0 (None), 1 (ODT), 2 (Lloyd)");
    return 1;
  }
  if (this->Seed < 0) {
    vtkErrorMacro(<< "Tissue Model From CT: Seed must not be negative (got " << this->Seed << ")");
    return 1;
  }

  faceplan::CTImage ct;
  int dims[3];
  input->GetDimensions(dims);
  double spacing[3];
  input->GetSpacing(spacing);
  // The image's first point (its extent may not start at 0) becomes the grid's origin.
  int extent[6];
  input->GetExtent(extent);
  double first[3];
  input->TransformIndexToPhysicalPoint(extent[0], extent[2], extent[4], first);
  for (int a = 0; a < 3; ++a) {
    ct.grid.dims[a] = dims[a];
    ct.grid.spacing[a] = spacing[a];
    ct.grid.origin[a] = first[a];
  }
  vtkMatrix3x3* direction = input->GetDirectionMatrix();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      ct.grid.direction(r, c) = direction->GetElement(r, c);
  ct.hounsfield.resize(std::size_t(input->GetNumberOfPoints()));
  for (vtkIdType i = 0; i < input->GetNumberOfPoints(); ++i)
    ct.hounsfield[std::size_t(i)] = float(scalars->GetTuple1(i));

  faceplan::TissueModelParameters p;
  p.labelling.boneThreshold = this->BoneThreshold;
  p.labelling.skinThreshold = this->SkinThreshold;
  p.labelling.keepLargestComponent = this->KeepLargestComponent;
  p.labelling.minimumBoneComponentVolume = this->MinimumBoneComponentVolume;
  p.labelling.fillBoneHoles = this->FillBoneHoles;
  p.labelling.maximumBoneHoleVolume = this->MaximumBoneHoleVolume;
  p.labelling.separateMandible = this->SeparateMandible;
  p.meshing.cellSize = this->CellSize;
  p.meshing.surfaceDistance = this->SurfaceDistance;
  p.meshing.sliverBound = this->QualityBound;
  p.meshing.optimiser = this->Optimiser == ODT     ? faceplan::MeshOptimiser::ODT
                        : this->Optimiser == LLOYD ? faceplan::MeshOptimiser::Lloyd
                                                   : faceplan::MeshOptimiser::None;
  p.meshing.seed = static_cast<unsigned int>(this->Seed);
  p.boneCellSizeFactor = this->BoneCellSizeFactor;
  p.maximumCells = this->MaximumCells;

  // Interruption: ParaView's abort flag is read whenever Core reports progress; the mesher also
  // polls `cancel` inside its refinement.
  std::atomic<bool> cancel(false);
  auto progress = [this, &cancel](double fraction, const char* what) {
    this->SetProgressText(what);
    this->UpdateProgress(fraction);
    if (this->CheckAbort())
      cancel = true;
  };
  faceplan::TissueModel model;
  const faceplan::Status status =
      faceplan::BuildTissueModel(ct, p, faceplan::cgal::MeshLabeledImage, model, &cancel, progress);
  this->SetProgressText(nullptr);
  if (!status) {
    vtkErrorMacro(<< "Tissue Model From CT: " << status.message);
    return 1;
  }
  for (const std::string& w : status.warnings)
    vtkWarningMacro(<< "Tissue Model From CT: " << w);

  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(model.tissue.numPoints());
  for (Eigen::Index i = 0; i < model.tissue.numPoints(); ++i)
    points->SetPoint(i, model.tissue.points(i, 0), model.tissue.points(i, 1),
                     model.tissue.points(i, 2));
  tissueOut->SetPoints(points);
  tissueOut->Allocate(model.tissue.numTets());
  vtkNew<vtkIntArray> label;
  label->SetName("Label");
  label->SetNumberOfTuples(model.tissue.numTets());
  for (Eigen::Index e = 0; e < model.tissue.numTets(); ++e) {
    const vtkIdType ids[4] = {model.tissue.tets(e, 0), model.tissue.tets(e, 1),
                              model.tissue.tets(e, 2), model.tissue.tets(e, 3)};
    tissueOut->InsertNextCell(VTK_TETRA, 4, ids);
    label->SetValue(e, model.tissueLabel[std::size_t(e)]);
  }
  tissueOut->GetCellData()->AddArray(label);
  vtkFieldData* fd = tissueOut->GetFieldData();
  AddScalar(fd, "EstimatedCells", model.estimatedCells);
  AddScalar(fd, "MeshedCells", double(model.meshedCells));
  AddScalar(fd, "FirstAttemptCells",
            model.attemptCells.empty() ? 0.0 : double(model.attemptCells.front()));
  AddScalar(fd, "MeshingAttempts", model.meshingAttempts);
  AddScalar(fd, "WorstDihedralAngle", model.quality.worstDihedralAngle);
  AddScalar(fd, "SmallestMeanRatio", model.quality.smallestMeanRatio);
  AddScalar(fd, "LargestBoundaryDistance", model.boundaryDistance.largest);

  BuildSurface(model, model.boneFacets, &model.boneLabel, boneOut);
  BuildSurface(model, model.skinFacets, nullptr, skinOut);
  return 1;
}

void vtkTissueModelFromCT::PrintSelf(ostream& os, vtkIndent indent) {
  this->Superclass::PrintSelf(os, indent);
  os << indent << "BoneThreshold: " << this->BoneThreshold << "\n";
  os << indent << "SkinThreshold: " << this->SkinThreshold << "\n";
  os << indent << "CellSize: " << this->CellSize << "\n";
  os << indent << "SurfaceDistance: " << this->SurfaceDistance << "\n";
  os << indent << "QualityBound: " << this->QualityBound << "\n";
  os << indent << "KeepLargestComponent: " << this->KeepLargestComponent << "\n";
  os << indent << "MinimumBoneComponentVolume: " << this->MinimumBoneComponentVolume << "\n";
  os << indent << "FillBoneHoles: " << this->FillBoneHoles << "\n";
  os << indent << "MaximumBoneHoleVolume: " << this->MaximumBoneHoleVolume << "\n";
  os << indent << "SeparateMandible: " << this->SeparateMandible << "\n";
  os << indent << "Optimiser: " << this->Optimiser << "\n";
  os << indent << "BoneCellSizeFactor: " << this->BoneCellSizeFactor << "\n";
  os << indent << "MaximumCells: " << this->MaximumCells << "\n";
  os << indent << "Seed: " << this->Seed << "\n";
}
