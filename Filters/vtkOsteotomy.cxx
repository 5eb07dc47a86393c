// SPDX-License-Identifier: BSD-3-Clause
#include "vtkOsteotomy.h"

#include "FacePlanArrayRanges.h"
#include "FacePlanDataStamp.h"
#include "FacePlanFieldData.h"
#include "FacePlanGather.h"
#include "FacePlanVTKConvert.h"
#include "Osteotomy/CutPlanes.h"
#include "Osteotomy/OperationPresets.h"
#include "Osteotomy/Osteotomy.h"
#include "OsteotomyClipping.h"
#include "OsteotomyConvert.h"
#include "OsteotomyOutput.h"

#include <vtkCellArray.h>
#include <vtkDataSet.h>
#include <vtkFieldData.h>
#include <vtkImplicitFunction.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkMultiProcessController.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkPointSet.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkUnsignedCharArray.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

vtkStandardNewMacro(vtkOsteotomy);
vtkCxxSetObjectMacro(vtkOsteotomy, CutPlane1, vtkImplicitFunction);
vtkCxxSetObjectMacro(vtkOsteotomy, CutPlane2, vtkImplicitFunction);

// The split bone of the last run and Core's view of it, kept while the input (by its stamp), the
// planes and the sides stay the same.
class vtkOsteotomy::vtkInternals {
public:
  bool valid = false;
  faceplan::DataStamp input;
  std::vector<double> key; // Operation, axes, InsideOut, plane origins and normals
  vtkSmartPointer<vtkPolyData> split;
  std::vector<std::uint8_t> moves;
  std::vector<faceplan::CutPlane> planes;      // the planes the split used
  std::vector<std::uint8_t> released, sliding; // a preset's approach, on the split's points
  faceplan::OsteotomyBone bone;
  unsigned long splits = 0;
};

vtkOsteotomy::vtkOsteotomy() : Internals(new vtkInternals) {
  this->SetNumberOfInputPorts(1);
  this->SetNumberOfOutputPorts(2);
}

vtkOsteotomy::~vtkOsteotomy() {
  this->SetCutPlane1(nullptr);
  this->SetCutPlane2(nullptr);
  delete this->Internals;
}

unsigned long vtkOsteotomy::GetSplitCount() const {
  return this->Internals->splits;
}

vtkMTimeType vtkOsteotomy::GetMTime() {
  vtkMTimeType t = this->Superclass::GetMTime();
  if (this->CutPlane1)
    t = std::max(t, this->CutPlane1->GetMTime());
  if (this->CutPlane2)
    t = std::max(t, this->CutPlane2->GetMTime());
  return t;
}

int vtkOsteotomy::FillInputPortInformation(int, vtkInformation* info) {
  // Any data set, so that a wrong type gets this filter's own message.
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkDataSet");
  return 1;
}

void vtkOsteotomy::Fail(const std::string& message, vtkDataObject* output,
                        vtkDataObject* planesOutput) {
  this->LastError = message;
  output->Initialize();
  planesOutput->Initialize();
  vtkErrorMacro(<< "Osteotomy: " << message);
}

int vtkOsteotomy::RequestData(vtkInformation*, vtkInformationVector** inputVector,
                              vtkInformationVector* outputVector) {
  this->LastError.clear();
  vtkDataSet* data = vtkDataSet::GetData(inputVector[0], 0);
  vtkPolyData* output = vtkPolyData::GetData(outputVector, 0);
  vtkPolyData* planesOutput = vtkPolyData::GetData(outputVector, 1);
  // Under MPI the cut needs the whole bone: it is gathered on rank 0 (FacePlanGather.h), which
  // holds both outputs; the cut makes new cells, so no piece maps back to a rank.
  if (vtkMultiProcessController* controller = faceplan::gather::DistributedController()) {
    const faceplan::gather::GatheredPieces bone(controller, vtkPointSet::SafeDownCast(data), 0);
    output->Initialize();
    planesOutput->Initialize();
    if (bone.IsRoot())
      this->Cut(bone.Whole() ? bone.Whole() : data, output, planesOutput);
    this->LastError = faceplan::gather::ShareRootMessage(controller, 0, this->LastError);
  } else {
    this->Cut(data, output, planesOutput);
  }
  for (vtkDataObject* o :
       {static_cast<vtkDataObject*>(output), static_cast<vtkDataObject*>(planesOutput)})
    faceplan::CacheArrayRanges(o, {data});
  return 1;
}

void vtkOsteotomy::Cut(vtkDataSet* data, vtkPolyData* output, vtkPolyData* planesOutput) {
  namespace of = faceplan::osteotomy_filter;
  output->Initialize();
  planesOutput->Initialize();
  auto failed = [&](const faceplan::Status& s) {
    if (!s)
      this->Fail(s.message, output, planesOutput);
    return !s;
  };

  if (this->PivotMode != SEGMENT_CENTROID && this->PivotMode != CUSTOM_PIVOT) {
    this->Fail("PivotMode must be 0 (SegmentCentroid) or 1 (Custom), not " +
                   std::to_string(this->PivotMode),
               output, planesOutput);
    return;
  }
  if (this->Operation < CUSTOM || this->Operation > GENIOPLASTY) {
    this->Fail("Operation must be 0 (Custom), 1 (LeFortI), 2 (BSSO) or 3 (Genioplasty), not " +
                   std::to_string(this->Operation),
               output, planesOutput);
    return;
  }
  const bool preset = this->Operation != CUSTOM;
  const bool insideOut = !preset && this->InsideOut != 0;
  faceplan::AnatomicalAxes axes;
  axes.anterior = Eigen::Vector3d(this->AnteriorDirection);
  axes.superior = Eigen::Vector3d(this->SuperiorDirection);
  std::vector<double> key{static_cast<double>(this->Operation), insideOut ? 1.0 : 0.0};
  key.insert(key.end(), this->AnteriorDirection, this->AnteriorDirection + 3);
  key.insert(key.end(), this->SuperiorDirection, this->SuperiorDirection + 3);
  std::vector<faceplan::CutPlane> planes;
  faceplan::Status planesStatus = faceplan::Status::Ok();
  if (!preset) {
    std::vector<vtkImplicitFunction*> functions{this->CutPlane1};
    if (this->UseSecondPlane)
      functions.push_back(this->CutPlane2);
    planesStatus = of::ToCutPlanes(functions, planes);
    for (const faceplan::CutPlane& p : planes) {
      key.insert(key.end(), p.origin.data(), p.origin.data() + 3);
      key.insert(key.end(), p.normal.data(), p.normal.data() + 3);
    }
  }
  vtkInternals& cache = *this->Internals;
  auto* pointSet = vtkPointSet::SafeDownCast(data);
  faceplan::DataStamp stamp;
  if (pointSet)
    stamp = faceplan::StampOf(pointSet);
  if (!(cache.valid && planesStatus && pointSet && stamp == cache.input && key == cache.key)) {
    // Validate (the input, the planes, and that the cut leaves vertices on both sides) and split:
    // only when the input, the operation, the planes or the sides changed.
    cache.valid = false;
    if (failed(of::ValidateInput(data)) || failed(planesStatus))
      return;
    vtkPolyData* input = vtkPolyData::SafeDownCast(data);
    faceplan::SurfaceMesh inputMesh;
    std::string why;
    if (!faceplan::vtkconvert::ToSurfaceMesh(input, faceplan::vtkconvert::CellPolicy::SurfaceOnly,
                                             inputMesh, why)) {
      this->Fail(why, output, planesOutput);
      return;
    }
    faceplan::OperationGeometry geometry;
    if (preset) {
      // Core: the operation's planes from the bone's geometry.
      const faceplan::Status placed = faceplan::PlaceOperationCut(
          static_cast<faceplan::Operation>(this->Operation), inputMesh.points, axes, geometry);
      if (!placed) {
        this->Fail(faceplan::OperationName(static_cast<faceplan::Operation>(this->Operation)) +
                       " preset: " + placed.message,
                   output, planesOutput);
        return;
      }
      planes = geometry.planes;
    }
    std::vector<std::uint8_t> inputSides;
    if (failed(faceplan::ClassifyCutSides(inputMesh.points, planes, insideOut, inputSides)))
      return;
    // Convert: split the bone with VTK's clipping, both sides capped, the bookkeeping
    // interpolated.
    cache.split = of::ClipIntoPieces(of::BookkeepingBone(input),
                                     faceplan::ConvexPiecesOfCut(planes, insideOut), cache.moves);
    if (failed(of::ToOsteotomyBone(cache.split, cache.moves, input->GetFieldData(), cache.bone)))
      return;
    cache.released.clear();
    cache.sliding.clear();
    if (preset)
      faceplan::MarkOperationApproach(geometry, cache.bone.mesh.points, cache.moves, cache.released,
                                      cache.sliding);
    cache.planes = planes;
    cache.input = std::move(stamp);
    cache.key = std::move(key);
    cache.valid = true;
    ++cache.splits;
  }
  planes = cache.planes;
  vtkPolyData* input = vtkPolyData::SafeDownCast(data);
  const faceplan::OsteotomyBone& bone = cache.bone;
  faceplan::OsteotomyMove move;
  move.move.translation = Eigen::Vector3d(this->Translation);
  move.move.rotationDegrees = Eigen::Vector3d(this->Rotation);
  move.move.pivot = Eigen::Vector3d(this->Pivot);
  move.pivotMode = this->PivotMode == CUSTOM_PIVOT ? faceplan::PivotMode::Custom
                                                   : faceplan::PivotMode::SegmentCentroid;

  // Core: move the segment, keep the bookkeeping.
  faceplan::OsteotomyResult result;
  if (failed(faceplan::MoveSegment(bone, move, result)))
    return;
  std::copy(result.pivot.data(), result.pivot.data() + 3, this->UsedPivot);

  // Outputs.
  of::BuildBoneOutput(result, cache.split, input->GetFieldData(), output);
  if (preset) {
    // The operation's approach replaces the flags the input may carry.
    for (const auto& [name, flags] :
         {std::make_pair("Released", &cache.released), std::make_pair("Sliding", &cache.sliding)}) {
      vtkNew<vtkUnsignedCharArray> array;
      array->SetName(name);
      array->SetNumberOfValues(static_cast<vtkIdType>(flags->size()));
      for (std::size_t i = 0; i < flags->size(); ++i)
        array->SetValue(static_cast<vtkIdType>(i), (*flags)[i]);
      output->GetPointData()->RemoveArray(name);
      output->GetPointData()->AddArray(array);
    }
    faceplan::fielddata::AddString(
        output->GetFieldData(), "Operation",
        faceplan::OperationName(static_cast<faceplan::Operation>(this->Operation)));
  }
  std::array<double, 6> box;
  input->GetBounds(box.data());
  of::BuildCutPlaneOutput(planes, box, planesOutput);
}

void vtkOsteotomy::PrintSelf(ostream& os, vtkIndent indent) {
  this->Superclass::PrintSelf(os, indent);
  os << indent
     << "Operation: " << faceplan::OperationName(static_cast<faceplan::Operation>(this->Operation))
     << " (" << this->Operation << ")\n";
  os << indent << "AnteriorDirection: " << this->AnteriorDirection[0] << " "
     << this->AnteriorDirection[1] << " " << this->AnteriorDirection[2] << "\n";
  os << indent << "SuperiorDirection: " << this->SuperiorDirection[0] << " "
     << this->SuperiorDirection[1] << " " << this->SuperiorDirection[2] << "\n";
  os << indent << "CutPlane1: " << this->CutPlane1 << "\n";
  os << indent << "CutPlane2: " << this->CutPlane2 << "\n";
  os << indent << "UseSecondPlane: " << this->UseSecondPlane << "\n";
  os << indent << "InsideOut: " << this->InsideOut << "\n";
  os << indent << "Translation: " << this->Translation[0] << " " << this->Translation[1] << " "
     << this->Translation[2] << "\n";
  os << indent << "Rotation: " << this->Rotation[0] << " " << this->Rotation[1] << " "
     << this->Rotation[2] << "\n";
  os << indent << "PivotMode: " << (this->PivotMode == CUSTOM_PIVOT ? "Custom" : "SegmentCentroid")
     << "\n";
  os << indent << "Pivot: " << this->Pivot[0] << " " << this->Pivot[1] << " " << this->Pivot[2]
     << "\n";
}
