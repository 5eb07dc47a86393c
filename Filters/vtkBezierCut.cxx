// SPDX-License-Identifier: BSD-3-Clause
#include "vtkBezierCut.h"

#include "BezierCut/BezierCut.h"
#include "BezierCutInputCache.h"
#include "FacePlanArrayRanges.h"
#include "FacePlanGather.h"

#include <vtkAlgorithmOutput.h>
#include <vtkCellArray.h>
#include <vtkDataObject.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkIntArray.h>
#include <vtkMultiProcessController.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkPointSet.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>

#include <algorithm>

vtkStandardNewMacro(vtkBezierCut);

namespace {
void Resize(std::vector<double>& c, vtkIdType n, vtkObject* self) {
  if (n < 0)
    n = 0;
  if (static_cast<vtkIdType>(c.size()) != 3 * n) {
    c.resize(static_cast<std::size_t>(3 * n), 0.0);
    self->Modified();
  }
}
void SetPoint(std::vector<double>& c, vtkIdType i, double x, double y, double z, vtkObject* self) {
  if (i < 0)
    return;
  if (3 * i + 3 > static_cast<vtkIdType>(c.size()))
    c.resize(static_cast<std::size_t>(3 * i + 3), 0.0);
  double* p = c.data() + 3 * i;
  if (p[0] != x || p[1] != y || p[2] != z) {
    p[0] = x;
    p[1] = y;
    p[2] = z;
    self->Modified();
  }
}
void GetPoint(const std::vector<double>& c, vtkIdType i, double p[3]) {
  for (int k = 0; k < 3; ++k)
    p[k] = (i >= 0 && 3 * i + 3 <= static_cast<vtkIdType>(c.size())) ? c[3 * i + k] : 0.0;
}
std::vector<Eigen::Vector3d> ToCurve(const std::vector<double>& c) {
  std::vector<Eigen::Vector3d> out;
  for (std::size_t i = 0; i + 2 < c.size(); i += 3)
    out.emplace_back(c[i], c[i + 1], c[i + 2]);
  return out;
}
} // namespace

class vtkBezierCut::vtkInternals {
public:
  faceplan::bezier_filter::InputCache Input;
};

vtkBezierCut::vtkBezierCut() : Internals(new vtkInternals) {
  this->SetNumberOfInputPorts(1);
  this->SetNumberOfOutputPorts(2);
  // A unit square in z = 0; until the user places the curves RequestData replaces it with a patch
  // over the input's ROI (DefaultCutCurves). The values are Plugin/BezierCut.xml's default_values
  // digit for digit, so that the GUI's initial push of them does not count as placing the curves.
  this->CurveU.assign(this->InitialCurveU, this->InitialCurveU + 12);
  this->CurveV.assign(this->InitialCurveV, this->InitialCurveV + 12);
  std::copy(this->InitialCurveU, this->InitialCurveU + 12, this->DefaultCurveU);
  std::copy(this->InitialCurveV, this->InitialCurveV + 12, this->DefaultCurveV);
}

vtkBezierCut::~vtkBezierCut() {
  delete this->Internals;
}

unsigned long vtkBezierCut::GetInputConversionCount() const {
  return this->Internals->Input.conversions();
}

double* vtkBezierCut::GetDefaultCurveU() {
  this->UpdateDefaultCurves();
  return this->DefaultCurveU;
}

double* vtkBezierCut::GetDefaultCurveV() {
  this->UpdateDefaultCurves();
  return this->DefaultCurveV;
}

// The GUI asks for these while it creates the filter, before any Apply: the upstream pipeline is
// brought up to date here as ParaView's own domains do for data information. Under MPI only rank
// 0 is asked and the upstream update is collective, so the curves then come from what rank 0
// already holds. Without usable input they are the constructor's (= the XML defaults), which the
// GUI then pushes unchanged.
void vtkBezierCut::UpdateDefaultCurves() {
  std::copy(this->InitialCurveU, this->InitialCurveU + 12, this->DefaultCurveU);
  std::copy(this->InitialCurveV, this->InitialCurveV + 12, this->DefaultCurveV);
  if (this->GetNumberOfInputConnections(0) < 1)
    return;
  vtkAlgorithmOutput* connection = this->GetInputConnection(0, 0);
  vtkAlgorithm* upstream = connection ? connection->GetProducer() : nullptr;
  if (!upstream)
    return;
  if (!faceplan::gather::DistributedController())
    upstream->Update(connection->GetIndex());
  auto* input = vtkPointSet::SafeDownCast(upstream->GetOutputDataObject(connection->GetIndex()));
  if (!input || !this->Internals->Input.update(input) || !this->Internals->Input.hasDefaultCurves())
    return;
  const auto& u = this->Internals->Input.defaultCurveU();
  const auto& v = this->Internals->Input.defaultCurveV();
  for (int k = 0; k < 4; ++k)
    for (int c = 0; c < 3; ++c) {
      this->DefaultCurveU[3 * k + c] = u[k][c];
      this->DefaultCurveV[3 * k + c] = v[k][c];
    }
}

// A control point set to a value other than the current one counts as placed by the user; the
// GUI's initial push of the XML defaults (equal to the constructor's) does not.
void vtkBezierCut::SetNumberOfCurveUPoints(vtkIdType n) {
  const auto before = this->GetMTime();
  Resize(this->CurveU, n, this);
  this->CurvesPlaced = this->CurvesPlaced || this->GetMTime() != before;
}
void vtkBezierCut::SetNumberOfCurveVPoints(vtkIdType n) {
  const auto before = this->GetMTime();
  Resize(this->CurveV, n, this);
  this->CurvesPlaced = this->CurvesPlaced || this->GetMTime() != before;
}
void vtkBezierCut::SetCurveUPoint(vtkIdType i, double x, double y, double z) {
  const auto before = this->GetMTime();
  SetPoint(this->CurveU, i, x, y, z, this);
  this->CurvesPlaced = this->CurvesPlaced || this->GetMTime() != before;
}
void vtkBezierCut::SetCurveVPoint(vtkIdType i, double x, double y, double z) {
  const auto before = this->GetMTime();
  SetPoint(this->CurveV, i, x, y, z, this);
  this->CurvesPlaced = this->CurvesPlaced || this->GetMTime() != before;
}
void vtkBezierCut::GetCurveUPoint(vtkIdType i, double p[3]) const {
  GetPoint(this->CurveU, i, p);
}
void vtkBezierCut::GetCurveVPoint(vtkIdType i, double p[3]) const {
  GetPoint(this->CurveV, i, p);
}

int vtkBezierCut::FillOutputPortInformation(int port, vtkInformation* info) {
  info->Set(vtkDataObject::DATA_TYPE_NAME(), port == 0 ? "vtkPointSet" : "vtkPolyData");
  return 1;
}

int vtkBezierCut::RequestDataObject(vtkInformation*, vtkInformationVector** inputVector,
                                    vtkInformationVector* outputVector) {
  vtkPointSet* input = vtkPointSet::GetData(inputVector[0], 0);
  // A wrong input type gets an empty polydata output, so that RequestData names the problem.
  const char* type = input ? input->GetClassName() : "vtkPolyData";
  vtkInformation* info0 = outputVector->GetInformationObject(0);
  vtkDataObject* out0 = info0->Get(vtkDataObject::DATA_OBJECT());
  if (!out0 || !out0->IsA(type)) {
    vtkDataObject* fresh = input ? input->NewInstance() : vtkPolyData::New();
    info0->Set(vtkDataObject::DATA_OBJECT(), fresh);
    fresh->Delete();
  }
  vtkInformation* info1 = outputVector->GetInformationObject(1);
  if (!vtkPolyData::SafeDownCast(info1->Get(vtkDataObject::DATA_OBJECT()))) {
    vtkPolyData* fresh = vtkPolyData::New();
    info1->Set(vtkDataObject::DATA_OBJECT(), fresh);
    fresh->Delete();
  }
  return 1;
}

void vtkBezierCut::Fail(const std::string& message, vtkDataObject* output, vtkDataObject* surface) {
  this->LastError = message;
  for (vtkDataObject* o : {output, surface})
    if (o)
      o->Initialize();
  if (faceplan::gather::LogsErrors())
    vtkErrorMacro(<< "Bezier Cut: " << message);
}

int vtkBezierCut::RequestData(vtkInformation*, vtkInformationVector** inputVector,
                              vtkInformationVector* outputVector) {
  this->LastError.clear();
  vtkPointSet* input = vtkPointSet::GetData(inputVector[0], 0);
  vtkPointSet* output = vtkPointSet::GetData(outputVector, 0);
  vtkPolyData* surface = vtkPolyData::GetData(outputVector, 1);
  if (!input || !output || !surface) {
    vtkDataObject* given = vtkDataObject::GetData(inputVector[0], 0);
    this->Fail(std::string("needs a vtkPointSet input (the output of ROI Extract), not ") +
                   (given ? given->GetClassName() : "nothing"),
               output, surface);
    return 1;
  }
  // Under MPI the fold and intersection checks need the whole ROI: gather it (FacePlanGather.h).
  // Rank 0 holds the operative surface; the other ranks' port 1 is empty.
  if (vtkMultiProcessController* controller = faceplan::gather::DistributedController()) {
    const bool root = controller->GetLocalProcessId() == 0;
    vtkNew<vtkPolyData> unused;
    const bool ok = faceplan::gather::RunOnWhole(
        controller, input, output, [&](vtkPointSet* in, vtkPointSet* out) {
          return this->Cut(in, out, root ? surface : unused.Get());
        });
    if (!root || !ok)
      surface->Initialize();
    // Every rank reports the error; only rank 0 logged it.
    this->LastError = faceplan::gather::ShareRootMessage(controller, 0, this->LastError);
  } else {
    this->Cut(input, output, surface);
  }
  for (vtkDataObject* o :
       {static_cast<vtkDataObject*>(output), static_cast<vtkDataObject*>(surface)})
    faceplan::CacheArrayRanges(o, {input});
  return 1;
}

bool vtkBezierCut::Cut(vtkPointSet* input, vtkPointSet* output, vtkPolyData* surface) {
  this->LastError.clear();
  output->Initialize();
  surface->Initialize();

  // Validate.
  if (this->Operation != CUT && this->Operation != FILL) {
    this->Fail("Operation must be 0 (Cut) or 1 (Fill), not " + std::to_string(this->Operation),
               output, surface);
    return false;
  }
  if (this->SurfaceResolution < 1 || this->SurfaceResolution > 256) {
    this->Fail("SurfaceResolution must lie in [1, 256], not " +
                   std::to_string(this->SurfaceResolution),
               output, surface);
    return false;
  }
  // Validate and convert (kept while the input is unchanged).
  faceplan::bezier_filter::InputCache& cache = this->Internals->Input;
  const faceplan::Status converted = cache.update(input);
  if (!converted) {
    this->Fail(converted.message, output, surface);
    return false;
  }
  const vtkIdType n = input->GetNumberOfPoints();
  if (!this->CurvesPlaced && cache.hasDefaultCurves()) {
    // Kept without Modified(): they follow the input until the user sets control points.
    this->CurveU.clear();
    this->CurveV.clear();
    for (int k = 0; k < 4; ++k)
      for (int c = 0; c < 3; ++c) {
        this->CurveU.push_back(cache.defaultCurveU()[k][c]);
        this->CurveV.push_back(cache.defaultCurveV()[k][c]);
      }
  }
  faceplan::BezierCutOptions options;
  options.operation =
      this->Operation == FILL ? faceplan::CutOperation::Fill : faceplan::CutOperation::Cut;
  options.flipNormal = this->FlipNormal != 0;
  options.displayResolution = this->SurfaceResolution;

  // Core.
  std::vector<double> curveU = this->CurveU, curveV = this->CurveV;
  this->LinkFirstPoints(curveU, curveV);
  faceplan::BezierCutResult result;
  const faceplan::Status status =
      faceplan::BezierCut(cache.mesh(), cache.topology(), cache.mask(), cache.boundary(),
                          ToCurve(curveU), ToCurve(curveV), options, result);
  if (!status) {
    this->Fail(status.message, output, surface);
    return false;
  }
  for (const std::string& w : result.warnings)
    vtkWarningMacro(<< "Bezier Cut: " << w);
  if (cache.skippedCells() > 0)
    vtkWarningMacro(<< "Bezier Cut: " << cache.skippedCells()
                    << " line or vertex cells of the input were ignored (passed through unmoved)");

  // Output 0: same cells and arrays, new points. They are always double precision: rounding the
  // moved points to float could flip the tiny triangles that a valid cut may contain (unmoved
  // points keep their values exactly; float to double is exact).
  output->ShallowCopy(input);
  vtkNew<vtkDoubleArray> coordinates;
  coordinates->DeepCopy(cache.points());
  vtkNew<vtkPoints> points;
  points->SetData(coordinates);
  vtkNew<vtkDoubleArray> displacement;
  displacement->SetName("Displacement");
  displacement->SetNumberOfComponents(3);
  displacement->SetNumberOfTuples(n);
  displacement->FillValue(0.0);
  for (vtkIdType i = 0; i < n; ++i) {
    if (!result.moved[static_cast<std::size_t>(i)])
      continue;
    double before[3], after[3];
    input->GetPoints()->GetPoint(i, before);
    points->SetPoint(i, result.points(i, 0), result.points(i, 1), result.points(i, 2));
    points->GetPoint(i, after);
    displacement->SetTuple3(i, after[0] - before[0], after[1] - before[1], after[2] - before[2]);
  }
  output->SetPoints(points);
  output->GetPointData()->RemoveArray("Displacement");
  output->GetPointData()->AddArray(displacement);
  vtkNew<vtkFieldData> fd;
  fd->ShallowCopy(input->GetFieldData());
  auto addInt = [&](const char* name, long long value) {
    vtkNew<vtkIntArray> a;
    a->SetName(name);
    a->InsertNextValue(static_cast<int>(value));
    fd->RemoveArray(name);
    fd->AddArray(a);
  };
  addInt("NumberOfMovedPoints", result.numMoved);
  addInt("IntermediarySteps", result.intermediarySteps);
  output->SetFieldData(fd);

  // Output 1: the operative surface.
  const faceplan::SurfaceMesh& s = result.operativeSurface;
  vtkNew<vtkPoints> spts;
  spts->SetDataTypeToDouble();
  spts->SetNumberOfPoints(s.numPoints());
  for (vtkIdType i = 0; i < s.numPoints(); ++i)
    spts->SetPoint(i, s.points(i, 0), s.points(i, 1), s.points(i, 2));
  vtkNew<vtkCellArray> tris;
  for (std::int64_t c = 0; c < s.numCells(); ++c) {
    const std::int64_t* ids = s.cell(c);
    const vtkIdType tri[3] = {ids[0], ids[1], ids[2]};
    tris->InsertNextCell(3, tri);
  }
  vtkNew<vtkDoubleArray> normals, uv;
  normals->SetName("Normals");
  normals->SetNumberOfComponents(3);
  normals->SetNumberOfTuples(s.numPoints());
  uv->SetName("UV");
  uv->SetNumberOfComponents(2);
  uv->SetNumberOfTuples(s.numPoints());
  for (vtkIdType i = 0; i < s.numPoints(); ++i) {
    const Eigen::Vector2d& p = result.operativeParameters[static_cast<std::size_t>(i)];
    normals->SetTuple3(i, result.operativeNormals(i, 0), result.operativeNormals(i, 1),
                       result.operativeNormals(i, 2));
    uv->SetTuple2(i, p.x(), p.y());
  }
  surface->SetPoints(spts);
  surface->SetPolys(tris);
  surface->GetPointData()->SetNormals(normals);
  surface->GetPointData()->SetTCoords(uv);
  return true;
}

bool vtkBezierCut::LinkFirstPoints(std::vector<double>& u, std::vector<double>& v) {
  if (u.size() < 3 || v.size() < 3)
    return false;
  const auto same = [](const double* a, const double* b) {
    return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
  };
  const double* shared = nullptr;
  if (same(u.data(), v.data())) {
    shared = u.data();
  } else if (this->HaveFirstPoints) {
    const bool uMoved = !same(u.data(), this->LastFirstU);
    const bool vMoved = !same(v.data(), this->LastFirstV);
    if (uMoved && !vMoved)
      shared = u.data();
    else if (vMoved && !uMoved)
      shared = v.data();
    else if (!uMoved && !vMoved)
      shared = this->SharedFirst;
  }
  if (!shared)
    return false;
  std::copy(u.data(), u.data() + 3, this->LastFirstU);
  std::copy(v.data(), v.data() + 3, this->LastFirstV);
  const double p0[3] = {shared[0], shared[1], shared[2]};
  std::copy(p0, p0 + 3, this->SharedFirst);
  std::copy(p0, p0 + 3, u.data());
  std::copy(p0, p0 + 3, v.data());
  this->HaveFirstPoints = true;
  return true;
}

void vtkBezierCut::PrintSelf(ostream& os, vtkIndent indent) {
  this->Superclass::PrintSelf(os, indent);
  auto printCurve = [&os, indent](const char* name, const std::vector<double>& values) {
    os << indent << name << ": " << values.size() / 3 << " points";
    for (size_t k = 0; k + 2 < values.size(); k += 3)
      os << " (" << values[k] << ", " << values[k + 1] << ", " << values[k + 2] << ")";
    os << "\n";
  };
  printCurve("CurveU", this->CurveU);
  printCurve("CurveV", this->CurveV);
  os << indent << "Operation: " << (this->Operation == FILL ? "Fill" : "Cut") << "\n";
  os << indent << "FlipNormal: " << this->FlipNormal << "\n";
  os << indent << "SurfaceResolution: " << this->SurfaceResolution << "\n";
}
