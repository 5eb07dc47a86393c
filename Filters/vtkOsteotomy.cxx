#include "vtkOsteotomy.h"

#include "FacePlanVTKConvert.h"
#include "Osteotomy/CutPlanes.h"
#include "Osteotomy/Osteotomy.h"
#include "OsteotomyClipping.h"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkImplicitFunction.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkIntArray.h>
#include <vtkObjectFactory.h>
#include <vtkPlane.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkStringArray.h>
#include <vtkTriangleFilter.h>
#include <vtkUnsignedCharArray.h>

#include <array>
#include <cmath>

vtkStandardNewMacro(vtkOsteotomy);
vtkCxxSetObjectMacro(vtkOsteotomy, CutPlane1, vtkImplicitFunction);
vtkCxxSetObjectMacro(vtkOsteotomy, CutPlane2, vtkImplicitFunction);

namespace {

// The plane an implicit function describes: its gradient is the normal, and the origin is moved
// onto its zero set (ParaView's plane adds an offset along the normal).
bool ToCutPlane(vtkImplicitFunction* function, faceplan::CutPlane& out) {
  vtkPlane* plane = vtkPlane::SafeDownCast(function);
  if (!plane)
    return false;
  double o[3], g[3];
  plane->GetOrigin(o);
  function->FunctionGradient(o, g);
  const double value = function->FunctionValue(o);
  const Eigen::Vector3d n(g[0], g[1], g[2]);
  out.normal = n;
  out.origin = Eigen::Vector3d(o[0], o[1], o[2]);
  if (value != 0.0)
    out.origin -= (value / n.squaredNorm()) * n;
  return true;
}

vtkSmartPointer<vtkDoubleArray> DoubleArray(const char* name, int components, vtkIdType n) {
  auto a = vtkSmartPointer<vtkDoubleArray>::New();
  a->SetName(name);
  a->SetNumberOfComponents(components);
  a->SetNumberOfTuples(n);
  a->FillValue(0.0);
  return a;
}

} // namespace

vtkOsteotomy::vtkOsteotomy() {
  this->SetNumberOfInputPorts(1);
  this->SetNumberOfOutputPorts(2);
}

vtkOsteotomy::~vtkOsteotomy() {
  this->SetCutPlane1(nullptr);
  this->SetCutPlane2(nullptr);
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

void vtkOsteotomy::Fail(const std::string& message, vtkInformationVector* outputVector) {
  this->LastError = message;
  for (int port = 0; port < 2; ++port)
    if (vtkDataObject* o =
            outputVector->GetInformationObject(port)->Get(vtkDataObject::DATA_OBJECT()))
      o->Initialize();
  vtkErrorMacro(<< "Osteotomy: " << message);
}

int vtkOsteotomy::RequestData(vtkInformation*, vtkInformationVector** inputVector,
                              vtkInformationVector* outputVector) {
  this->LastError.clear();
  vtkDataSet* data = vtkDataSet::GetData(inputVector[0], 0);
  vtkPolyData* output = vtkPolyData::GetData(outputVector, 0);
  vtkPolyData* planesOut = vtkPolyData::GetData(outputVector, 1);
  output->Initialize();
  planesOut->Initialize();

  // ---- validate -------------------------------------------------------------------------------
  vtkPolyData* input = vtkPolyData::SafeDownCast(data);
  if (!input) {
    this->Fail(std::string("the input is a ") + (data ? data->GetClassName() : "null data set") +
                   "; Osteotomy needs a bone surface of triangles (apply Extract Surface first)",
               outputVector);
    return 1;
  }
  if (input->GetNumberOfPoints() == 0 ||
      input->GetNumberOfPolys() + input->GetNumberOfStrips() == 0) {
    this->Fail("the input has no triangles; Osteotomy needs a bone surface of triangles",
               outputVector);
    return 1;
  }
  if (input->GetNumberOfLines() + input->GetNumberOfVerts() > 0) {
    this->Fail("the input has " +
                   std::to_string(input->GetNumberOfLines() + input->GetNumberOfVerts()) +
                   " line or vertex cells; Osteotomy needs a bone surface of triangles only",
               outputVector);
    return 1;
  }
  std::vector<faceplan::CutPlane> planes(this->UseSecondPlane ? 2 : 1);
  vtkImplicitFunction* functions[2] = {this->CutPlane1, this->CutPlane2};
  for (std::size_t k = 0; k < planes.size(); ++k)
    if (!ToCutPlane(functions[k], planes[k])) {
      this->Fail("CutPlane" + std::to_string(k + 1) + " is not set or not a plane", outputVector);
      return 1;
    }
  if (faceplan::Status s = faceplan::NormalizeCutPlanes(planes); !s) {
    this->Fail(s.message, outputVector);
    return 1;
  }
  faceplan::SurfaceMesh inputMesh;
  std::string why;
  if (!faceplan::vtkconvert::ToSurfaceMesh(input, faceplan::vtkconvert::CellPolicy::SurfaceOnly,
                                           inputMesh, why)) {
    this->Fail(why, outputVector);
    return 1;
  }
  std::vector<std::uint8_t> inputSides;
  if (faceplan::Status s =
          faceplan::ClassifyCutSides(inputMesh.points, planes, this->InsideOut != 0, inputSides);
      !s) {
    this->Fail(s.message, outputVector);
    return 1;
  }
  vtkDataArray* inDisplacement = input->GetPointData()->GetArray("Displacement");
  if (inDisplacement && inDisplacement->GetNumberOfComponents() != 3) {
    this->Fail("the input's Displacement array does not have 3 components", outputVector);
    return 1;
  }

  // ---- convert: the bookkeeping arrays as doubles, then split with VTK's clipping --------------
  const vtkIdType n = input->GetNumberOfPoints();
  vtkNew<vtkPolyData> bone;
  {
    vtkNew<vtkTriangleFilter> triangulate;
    triangulate->SetInputData(input);
    triangulate->Update();
    bone->CopyStructure(triangulate->GetOutput());
  }
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(n);
  for (vtkIdType i = 0; i < n; ++i)
    points->SetPoint(i, input->GetPoint(i));
  bone->SetPoints(points);
  auto displacement = DoubleArray("Displacement", 3, n);
  auto mask = DoubleArray("ROIMask", 1, n);
  auto segment = DoubleArray("SegmentId", 1, n);
  vtkDataArray* inMask = input->GetPointData()->GetArray("ROIMask");
  vtkDataArray* inSegment = input->GetPointData()->GetArray("SegmentId");
  for (vtkIdType i = 0; i < n; ++i) {
    if (inDisplacement)
      for (int c = 0; c < 3; ++c)
        displacement->SetComponent(i, c, inDisplacement->GetComponent(i, c));
    if (inMask)
      mask->SetValue(i, inMask->GetComponent(i, 0) != 0.0 ? 1.0 : 0.0);
    if (inSegment)
      segment->SetValue(i, inSegment->GetComponent(i, 0));
  }
  bone->GetPointData()->AddArray(displacement);
  bone->GetPointData()->AddArray(mask);
  bone->GetPointData()->AddArray(segment);

  std::vector<std::uint8_t> moves;
  vtkSmartPointer<vtkPolyData> split = faceplan::vtkosteotomy::ClipIntoPieces(
      bone, faceplan::ConvexPiecesOfCut(planes, this->InsideOut != 0), moves);

  faceplan::OsteotomyBone cut;
  if (!faceplan::vtkconvert::ToSurfaceMesh(split, faceplan::vtkconvert::CellPolicy::SurfaceOnly,
                                           cut.mesh, why)) {
    this->Fail(why, outputVector);
    return 1;
  }
  const vtkIdType m = split->GetNumberOfPoints();
  cut.displacement.resize(m, 3);
  cut.segmentId.resize(static_cast<std::size_t>(m));
  cut.roiMask.resize(static_cast<std::size_t>(m));
  cut.moves = moves;
  if (m > 0) {
    vtkDataArray* d = split->GetPointData()->GetArray("Displacement");
    vtkDataArray* r = split->GetPointData()->GetArray("ROIMask");
    vtkDataArray* s = split->GetPointData()->GetArray("SegmentId");
    for (vtkIdType i = 0; i < m; ++i) {
      for (int c = 0; c < 3; ++c)
        cut.displacement(i, c) = d->GetComponent(i, c);
      // New points lie on edges within one piece of the input, whose ends share a segment id.
      cut.segmentId[static_cast<std::size_t>(i)] =
          static_cast<int>(std::lround(s->GetComponent(i, 0)));
      cut.roiMask[static_cast<std::size_t>(i)] = r->GetComponent(i, 0) >= 0.5 ? 1 : 0;
    }
  }
  vtkFieldData* inField = input->GetFieldData();
  if (vtkDataArray* t = inField->GetArray("SegmentTransform"))
    for (vtkIdType k = 0; k < t->GetNumberOfTuples() * t->GetNumberOfComponents(); ++k)
      cut.segmentTransforms.push_back(
          t->GetComponent(k / t->GetNumberOfComponents(), k % t->GetNumberOfComponents()));
  if (auto* notes = vtkStringArray::SafeDownCast(inField->GetAbstractArray("SegmentNote")))
    for (vtkIdType k = 0; k < notes->GetNumberOfValues(); ++k)
      cut.segmentNotes.push_back(notes->GetValue(k));

  faceplan::OsteotomyMove move;
  move.move.translation =
      Eigen::Vector3d(this->Translation[0], this->Translation[1], this->Translation[2]);
  move.move.rotationDegrees =
      Eigen::Vector3d(this->Rotation[0], this->Rotation[1], this->Rotation[2]);
  move.move.pivot = Eigen::Vector3d(this->Pivot[0], this->Pivot[1], this->Pivot[2]);
  move.pivotMode = this->PivotMode == CUSTOM_PIVOT ? faceplan::PivotMode::Custom
                                                   : faceplan::PivotMode::SegmentCentroid;

  // ---- Core -----------------------------------------------------------------------------------
  faceplan::OsteotomyResult result;
  if (faceplan::Status s = faceplan::MoveSegment(cut, move, result); !s) {
    this->Fail(s.message, outputVector);
    return 1;
  }
  for (int k = 0; k < 3; ++k)
    this->UsedPivot[k] = result.pivot[k];

  // ---- output 0: the split bone, segment moved ----------------------------------------------
  vtkNew<vtkPoints> moved;
  moved->SetDataTypeToDouble();
  moved->SetNumberOfPoints(m);
  auto outDisplacement = DoubleArray("Displacement", 3, m);
  vtkNew<vtkUnsignedCharArray> outMask;
  outMask->SetName("ROIMask");
  outMask->SetNumberOfTuples(m);
  vtkNew<vtkIntArray> outSegment;
  outSegment->SetName("SegmentId");
  outSegment->SetNumberOfTuples(m);
  for (vtkIdType i = 0; i < m; ++i) {
    moved->SetPoint(i, result.points(i, 0), result.points(i, 1), result.points(i, 2));
    outDisplacement->SetTuple3(i, result.displacement(i, 0), result.displacement(i, 1),
                               result.displacement(i, 2));
    outMask->SetValue(i, result.roiMask[static_cast<std::size_t>(i)]);
    outSegment->SetValue(i, result.segmentId[static_cast<std::size_t>(i)]);
  }
  output->SetPoints(moved);
  output->SetPolys(split->GetPolys());
  output->GetPointData()->AddArray(outDisplacement);
  output->GetPointData()->SetActiveVectors("Displacement");
  output->GetPointData()->AddArray(outMask);
  output->GetPointData()->AddArray(outSegment);
  vtkNew<vtkFieldData> field;
  field->ShallowCopy(inField);
  vtkNew<vtkDoubleArray> transforms;
  transforms->SetName("SegmentTransform");
  for (double v : result.segmentTransforms)
    transforms->InsertNextValue(v);
  vtkNew<vtkStringArray> notes;
  notes->SetName("SegmentNote");
  for (const std::string& note : result.segmentNotes)
    notes->InsertNextValue(note);
  field->RemoveArray("SegmentTransform");
  field->RemoveArray("SegmentNote");
  field->AddArray(transforms);
  field->AddArray(notes);
  output->SetFieldData(field);

  // ---- output 1: the cut plane(s) within the input's bounds ---------------------------------
  std::array<double, 6> box;
  input->GetBounds(box.data());
  vtkNew<vtkPoints> planePoints;
  planePoints->SetDataTypeToDouble();
  vtkNew<vtkCellArray> polygons;
  vtkNew<vtkIntArray> planeIds;
  planeIds->SetName("CutPlane");
  for (std::size_t k = 0; k < planes.size(); ++k) {
    const auto corners = faceplan::PlaneBoxSection(planes[k], box);
    if (corners.empty())
      continue;
    polygons->InsertNextCell(static_cast<vtkIdType>(corners.size()));
    for (const auto& c : corners)
      polygons->InsertCellPoint(planePoints->InsertNextPoint(c.data()));
    planeIds->InsertNextValue(static_cast<int>(k + 1));
  }
  planesOut->SetPoints(planePoints);
  planesOut->SetPolys(polygons);
  planesOut->GetCellData()->AddArray(planeIds);
  return 1;
}

void vtkOsteotomy::PrintSelf(ostream& os, vtkIndent indent) {
  this->Superclass::PrintSelf(os, indent);
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
