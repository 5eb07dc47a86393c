#include "vtkCondensedFEMDeform.h"

#include "FacePlanContact.h"

#include "CondensedFEM/BackgroundPrecompute.h"
#include "CondensedFEM/CondensedFEM.h"
#ifdef FACEPLAN_HAS_CUDA
#include "CudaBackend.h"
#endif

#include "vtkCellArray.h"
#include "vtkCellData.h"
#include "vtkCellType.h"
#include "vtkIntArray.h"
#include "vtkDataArray.h"
#include "vtkDataSetSurfaceFilter.h"
#include "vtkDoubleArray.h"
#include "vtkFieldData.h"
#include "vtkIdList.h"
#include "vtkIdTypeArray.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkPointSet.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkSmartPointer.h"
#include "vtkStringArray.h"
#include "vtkTable.h"
#include "vtkUnstructuredGrid.h"

#include <atomic>
#include <chrono>
#include <cmath>
#include <thread>

vtkStandardNewMacro(vtkCondensedFEMDeform);

namespace {

using faceplan::Displacements;
using faceplan::PrecomputeRequest;

// The tissue boundary, computed once per tissue mesh.
struct TissueBoundary {
  vtkSmartPointer<vtkPolyData> surface; // boundary triangles, with vtkOriginalPointIds
  std::vector<vtkIdType> nodes;         // tissue point ids on the boundary
};

bool SameRequest(const PrecomputeRequest& a, const PrecomputeRequest& b) {
  return a.mesh.points.rows() == b.mesh.points.rows() && a.mesh.tets.rows() == b.mesh.tets.rows() &&
         a.mesh.points == b.mesh.points && a.mesh.tets == b.mesh.tets &&
         a.materials.youngsModulus.size() == b.materials.youngsModulus.size() &&
         a.materials.youngsModulus == b.materials.youngsModulus &&
         a.materials.poissonRatio.size() == b.materials.poissonRatio.size() &&
         a.materials.poissonRatio == b.materials.poissonRatio &&
         a.materials.density.size() == b.materials.density.size() &&
         a.materials.density == b.materials.density && a.sets.constrained == b.sets.constrained &&
         a.sets.movable == b.sets.movable && a.sets.kept == b.sets.kept &&
         a.options.method == b.options.method && a.options.backend == b.options.backend &&
         a.options.elementOrder == b.options.elementOrder;
}

void AddScalar(vtkFieldData* fd, const char* name, double value) {
  vtkNew<vtkDoubleArray> a;
  a->SetName(name);
  a->InsertNextValue(value);
  fd->AddArray(a);
}

void AddString(vtkFieldData* fd, const char* name, const std::string& value) {
  vtkNew<vtkStringArray> a;
  a->SetName(name);
  a->InsertNextValue(value);
  fd->AddArray(a);
}

} // namespace

struct vtkCondensedFEMDeform::Cache {
  faceplan::BackgroundPrecompute background;
  PrecomputeRequest lastRequest;
  bool haveRequest = false;
  std::shared_ptr<faceplan::ComputeBackend> cudaBackend;
  std::string cudaUnavailable;
  bool cudaProbed = false;

  faceplan::TetMesh boundaryMesh;
  TissueBoundary boundary;

  // Contact map and what it was built from.
  std::vector<double> contactBonePoints, contactMask;
  faceplan::Points contactTissuePoints;
  vtkIdType contactBoneCells = -1;
  double contactDistance = -1.0;
  faceplan::vtkcontact::ContactMap contact;
};

vtkCondensedFEMDeform::vtkCondensedFEMDeform() : State(new Cache) {
  this->SetNumberOfInputPorts(2);
  this->SetNumberOfOutputPorts(2);
}

vtkCondensedFEMDeform::~vtkCondensedFEMDeform() = default;

int vtkCondensedFEMDeform::FillInputPortInformation(int port, vtkInformation* info) {
  if (port == 0) info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkUnstructuredGrid");
  else info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkPointSet");
  return 1;
}

int vtkCondensedFEMDeform::FillOutputPortInformation(int port, vtkInformation* info) {
  if (port == 0) info->Set(vtkDataObject::DATA_TYPE_NAME(), "vtkUnstructuredGrid");
  else info->Set(vtkDataObject::DATA_TYPE_NAME(), "vtkTable");
  return 1;
}

int vtkCondensedFEMDeform::RequestData(vtkInformation*, vtkInformationVector** inputVector,
                                       vtkInformationVector* outputVector) {
  vtkUnstructuredGrid* tissue = vtkUnstructuredGrid::GetData(inputVector[0], 0);
  vtkPointSet* bone = vtkPointSet::GetData(inputVector[1], 0);
  vtkUnstructuredGrid* output = vtkUnstructuredGrid::GetData(outputVector, 0);
  vtkTable* table = vtkTable::GetData(outputVector, 1);
  Cache& cache = *this->State;

  // ---- validate -------------------------------------------------------------------------------
  if (!tissue || tissue->GetNumberOfCells() == 0) {
    vtkErrorMacro("the Input (soft tissue) is empty");
    return 1;
  }
  if (!bone) {
    vtkErrorMacro("no Bone input: connect the output of BezierCut (a surface with a Displacement array)");
    return 1;
  }
  for (vtkIdType c = 0; c < tissue->GetNumberOfCells(); ++c) {
    if (tissue->GetCellType(c) != VTK_TETRA) {
      vtkErrorMacro("cell " << c << " of the tissue is not a linear tetrahedron (VTK type "
                            << tissue->GetCellType(c)
                            << "); apply ParaView's Tetrahedralize filter to the tissue first");
      return 1;
    }
  }
  vtkDataArray* boneDisplacement = bone->GetPointData()->GetArray("Displacement");
  if (!boneDisplacement || boneDisplacement->GetNumberOfComponents() != 3) {
    vtkErrorMacro("the Bone input needs a 3-component point array named Displacement "
                  "(connect the output of BezierCut)");
    return 1;
  }
  for (vtkIdType i = 0; i < boneDisplacement->GetNumberOfTuples(); ++i)
    for (int c = 0; c < 3; ++c)
      if (!std::isfinite(boneDisplacement->GetComponent(i, c))) {
        vtkErrorMacro("the bone's Displacement has a NaN or infinite value at point " << i);
        return 1;
      }
  vtkDataArray* roiMask = bone->GetPointData()->GetArray("ROIMask");
  if (!(this->LengthUnit > 0.0) || !(this->ContactDistance >= 0.0)) {
    vtkErrorMacro("LengthUnit must be positive and ContactDistance non-negative");
    return 1;
  }

  // ---- convert --------------------------------------------------------------------------------
  PrecomputeRequest request;
  const vtkIdType n = tissue->GetNumberOfPoints(), m = tissue->GetNumberOfCells();
  request.mesh.points.resize(n, 3);
  for (vtkIdType i = 0; i < n; ++i) tissue->GetPoint(i, &request.mesh.points(i, 0));
  request.mesh.tets.resize(m, 4);
  {
    vtkNew<vtkIdList> ids;
    for (vtkIdType c = 0; c < m; ++c) {
      tissue->GetCellPoints(c, ids);
      for (int k = 0; k < 4; ++k) request.mesh.tets(c, k) = static_cast<int>(ids->GetId(k));
    }
  }
  const double s = this->LengthUnit;
  request.materials = faceplan::Materials::Uniform(this->YoungsModulus * s * s, this->PoissonRatio,
                                                   this->Density * s * s * s);
  if (this->UseCellMaterials) {
    if (vtkDataArray* e = tissue->GetCellData()->GetArray("YoungsModulus")) {
      request.materials.youngsModulus.resize(m);
      for (vtkIdType c = 0; c < m; ++c) request.materials.youngsModulus[c] = e->GetComponent(c, 0) * s * s;
    }
    if (vtkDataArray* nu = tissue->GetCellData()->GetArray("PoissonRatio")) {
      request.materials.poissonRatio.resize(m);
      for (vtkIdType c = 0; c < m; ++c) request.materials.poissonRatio[c] = nu->GetComponent(c, 0);
    }
  }

  if (!cache.boundary.surface || cache.boundaryMesh.points.rows() != n ||
      cache.boundaryMesh.tets.rows() != m || cache.boundaryMesh.points != request.mesh.points ||
      cache.boundaryMesh.tets != request.mesh.tets) {
    vtkNew<vtkDataSetSurfaceFilter> surface;
    surface->SetInputData(tissue);
    surface->PassThroughPointIdsOn();
    surface->Update();
    cache.boundary.surface = surface->GetOutput();
    cache.boundary.nodes.clear();
    vtkIdTypeArray* original = vtkIdTypeArray::SafeDownCast(
        cache.boundary.surface->GetPointData()->GetArray(surface->GetOriginalPointIdsName()));
    for (vtkIdType k = 0; original && k < original->GetNumberOfTuples(); ++k)
      cache.boundary.nodes.push_back(original->GetValue(k));
    cache.boundaryMesh = request.mesh;
  }
  this->UpdateProgress(0.05);

  // Contact: rebuilt only when the undeformed bone, its ROI or the tissue changed.
  {
    std::vector<double> undeformed(3 * bone->GetNumberOfPoints());
    for (vtkIdType i = 0; i < bone->GetNumberOfPoints(); ++i) {
      double p[3], d[3];
      bone->GetPoint(i, p);
      boneDisplacement->GetTuple(i, d);
      for (int c = 0; c < 3; ++c) undeformed[3 * i + c] = p[c] - d[c];
    }
    std::vector<double> mask;
    if (roiMask)
      for (vtkIdType i = 0; i < roiMask->GetNumberOfTuples(); ++i) mask.push_back(roiMask->GetComponent(i, 0));
    double bounds[6];
    bone->GetBounds(bounds);
    const double tolerance = 1e-9 * std::sqrt((bounds[1] - bounds[0]) * (bounds[1] - bounds[0]) +
                                              (bounds[3] - bounds[2]) * (bounds[3] - bounds[2]) +
                                              (bounds[5] - bounds[4]) * (bounds[5] - bounds[4]));
    bool same = cache.contactBonePoints.size() == undeformed.size() && cache.contactMask == mask &&
                cache.contactBoneCells == bone->GetNumberOfCells() &&
                cache.contactDistance == this->ContactDistance &&
                cache.contactTissuePoints.rows() == n && cache.contactTissuePoints == request.mesh.points;
    for (size_t k = 0; same && k < undeformed.size(); ++k)
      same = std::abs(undeformed[k] - cache.contactBonePoints[k]) <= tolerance;
    if (!same) {
      std::string why;
      if (!faceplan::vtkcontact::BuildContactMap(tissue, cache.boundary.nodes, bone, boneDisplacement, roiMask,
                                                 this->ContactDistance, cache.contact, why)) {
        vtkErrorMacro(<< why);
        cache.contactBonePoints.clear();
        return 1;
      }
      cache.contactBonePoints = undeformed;
      cache.contactMask = mask;
      cache.contactBoneCells = bone->GetNumberOfCells();
      cache.contactDistance = this->ContactDistance;
      cache.contactTissuePoints = request.mesh.points;
    }
  }
  const auto& contact = cache.contact;
  if (contact.tiedNodes.empty()) {
    vtkErrorMacro("no tissue boundary node lies within ContactDistance = "
                  << this->ContactDistance
                  << " of the undeformed bone: increase ContactDistance or check that tissue and "
                     "bone share one frame and unit");
    return 1;
  }
  for (size_t t = 0; t < contact.tiedNodes.size(); ++t) {
    request.sets.constrained.push_back(contact.tiedNodes[t]);
    if (contact.movable[t]) request.sets.movable.push_back(contact.tiedNodes[t]);
  }
  for (vtkIdType node : cache.boundary.nodes) request.sets.kept.push_back(static_cast<int>(node));

  // Auto lets Core pick the cheapest exact cached path; Condensed forces the explicit condensed
  // (dense kept-by-ROI) response, the paper's method.
  if (this->Method == METHOD_CONDENSED) request.options.method = faceplan::SolveMethod::DenseResponse;
  const bool quadratic =
      this->ElementOrder == QUADRATIC_ELEMENTS || this->ElementOrder == QUADRATIC_NODAL_PRESSURE;
  if (this->ElementOrder == QUADRATIC_ELEMENTS) request.options.elementOrder = faceplan::ElementOrder::Quadratic;
  if (this->ElementOrder == QUADRATIC_NODAL_PRESSURE)
    request.options.elementOrder = faceplan::ElementOrder::QuadraticNodalPressure;

  // ---- backend --------------------------------------------------------------------------------
  std::vector<std::string> notes;
  if (quadratic && this->Method == METHOD_FULL_REFERENCE)
    notes.push_back("the FullReference method supports linear elements only: solved with linear elements");
  if (this->Backend != BACKEND_CPU) {
    if (!cache.cudaProbed) {
      cache.cudaProbed = true;
#ifdef FACEPLAN_HAS_CUDA
      std::string error;
      cache.cudaBackend = faceplan::cuda::MakeCudaBackend(error);
      if (!cache.cudaBackend) cache.cudaUnavailable = error;
#else
      cache.cudaUnavailable = "this build has no CUDA backend";
#endif
    }
    if (cache.cudaBackend) request.options.backend = cache.cudaBackend;
    else if (this->Backend == BACKEND_CUDA) {
      vtkWarningMacro("Backend CUDA is not available (" << cache.cudaUnavailable << "); using the CPU");
      notes.push_back("CUDA unavailable: " + cache.cudaUnavailable);
    }
  }

  // ---- call Core ------------------------------------------------------------------------------
  // The precompute starts first, on its worker thread; the per-edit values are gathered meanwhile.
  faceplan::SolveResult result;
  faceplan::Status status;
  bool freshPrecompute = false;
  double precomputeMs = 0.0;
  auto progress = std::make_shared<std::atomic<double>>(0.0);
  if (this->Method != METHOD_FULL_REFERENCE &&
      (!cache.haveRequest || !SameRequest(request, cache.lastRequest))) {
    cache.background.start(request, [progress](double f, const char*) { progress->store(f); });
    cache.lastRequest = request;
    cache.haveRequest = true;
    freshPrecompute = true;
    ++this->PrecomputeCount;
  }

  // Per-edit values: the bone's displacement at each movable tied node.
  std::vector<double> tiedDisplacement;
  faceplan::vtkcontact::InterpolateDisplacement(contact, boneDisplacement, tiedDisplacement);
  faceplan::SolveInput input;
  input.movableDisplacement.resize(static_cast<Eigen::Index>(request.sets.movable.size()), 3);
  for (size_t t = 0, k = 0; t < contact.tiedNodes.size(); ++t)
    if (contact.movable[t]) {
      input.movableDisplacement.row(k++) << tiedDisplacement[3 * t], tiedDisplacement[3 * t + 1],
          tiedDisplacement[3 * t + 2];
    }
  if (this->UseGravity) input.gravity = Eigen::Vector3d(this->Gravity[0], this->Gravity[1], this->Gravity[2]);
  input.recoverInterior = this->OutputMode == VOLUME;

  if (this->Method == METHOD_FULL_REFERENCE) {
    status = faceplan::SolveFullReference(request, input, result);
  } else {
    // Report the worker's progress to ParaView from this (the pipeline's) thread.
    while (!cache.background.ready()) {
      this->UpdateProgress(0.1 + 0.8 * progress->load());
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    std::shared_ptr<const faceplan::CondensedSystem> system;
    status = cache.background.wait(system);
    if (!status) cache.haveRequest = false; // a failed precompute is retried next time
    else {
      // The precompute's findings (slivers, fallbacks) are reported once, not again on every edit.
      if (freshPrecompute)
        for (const auto& w : status.warnings) notes.push_back(w);
      status = faceplan::Solve(*system, input, result);
      const faceplan::SystemInfo info = faceplan::Describe(*system);
      precomputeMs = info.precomputeTimings[faceplan::Stage::Total].ms;
      if (freshPrecompute)
        for (int k = 0; k < faceplan::kNumStages; ++k)
          if (info.precomputeTimings.stages[k].ms > 0.0) result.timings.stages[k].reused = false;
      result.timings[faceplan::Stage::Total].reused = false;
    }
  }
  if (!status) {
    vtkErrorMacro(<< status.message);
    return 1;
  }
  for (const auto& w : status.warnings) notes.push_back(w); // the solve's (large strain, inversion)
  for (const auto& w : notes) vtkWarningMacro(<< w);
  this->UpdateProgress(0.95);

  double verifyError = -1.0;
  if (this->Verify) {
    faceplan::SolveResult reference;
    faceplan::SolveInput verifyInput = input;
    faceplan::Status vs;
    if (quadratic && this->Method != METHOD_FULL_REFERENCE) {
      // The reference solve is linear: verify a quadratic result against a fresh, uncached
      // quadratic cached-factor solve instead.
      PrecomputeRequest fresh = request;
      fresh.options.method = faceplan::SolveMethod::CachedFactor;
      std::shared_ptr<const faceplan::CondensedSystem> freshSystem;
      vs = faceplan::Precompute(fresh, freshSystem);
      if (vs) vs = faceplan::Solve(*freshSystem, verifyInput, reference);
    } else {
      vs = faceplan::SolveFullReference(request, verifyInput, reference);
    }
    if (!vs) {
      vtkErrorMacro("verification solve failed: " << vs.message);
      return 1;
    }
    const double scale = std::max(reference.keptDisplacement.cwiseAbs().maxCoeff(), 1e-300);
    verifyError = (result.keptDisplacement - reference.keptDisplacement).cwiseAbs().maxCoeff() / scale;
    if (input.recoverInterior)
      verifyError = std::max(verifyError, (result.allDisplacement - reference.allDisplacement).cwiseAbs().maxCoeff() / scale);
  }

  // ---- build output ---------------------------------------------------------------------------
  vtkNew<vtkDoubleArray> displacement;
  displacement->SetName("Displacement");
  displacement->SetNumberOfComponents(3);
  vtkNew<vtkPoints> moved;
  moved->SetDataTypeToDouble();
  if (this->OutputMode == VOLUME) {
    output->ShallowCopy(tissue);
    displacement->SetNumberOfTuples(n);
    moved->SetNumberOfPoints(n);
    for (vtkIdType i = 0; i < n; ++i) {
      const Eigen::RowVector3d u = result.allDisplacement.row(i);
      displacement->SetTuple3(i, u(0), u(1), u(2));
      const Eigen::RowVector3d p = request.mesh.points.row(i) + u;
      moved->SetPoint(i, p(0), p(1), p(2));
    }
  } else {
    vtkPolyData* surface = cache.boundary.surface;
    const vtkIdType ns = surface->GetNumberOfPoints();
    displacement->SetNumberOfTuples(ns);
    moved->SetNumberOfPoints(ns);
    for (vtkIdType k = 0; k < ns; ++k) { // kept == boundary nodes, in the surface's point order
      const Eigen::RowVector3d u = result.keptDisplacement.row(k);
      displacement->SetTuple3(k, u(0), u(1), u(2));
      const Eigen::RowVector3d p = request.mesh.points.row(cache.boundary.nodes[k]) + u;
      moved->SetPoint(k, p(0), p(1), p(2));
    }
    output->Initialize();
    output->GetPointData()->ShallowCopy(surface->GetPointData());
    vtkNew<vtkIdList> ids;
    output->Allocate(surface->GetNumberOfCells());
    for (vtkIdType c = 0; c < surface->GetNumberOfCells(); ++c) {
      surface->GetCellPoints(c, ids);
      output->InsertNextCell(surface->GetCellType(c), ids);
    }
  }
  output->SetPoints(moved);
  output->GetPointData()->AddArray(displacement);
  output->GetPointData()->SetActiveVectors("Displacement");

  const double solveMs = result.timings[faceplan::Stage::Total].ms;
  vtkNew<vtkFieldData> fd;
  AddScalar(fd, "RelativeResidual", result.relativeResidual);
  AddScalar(fd, "ResidualFromPrecompute", result.residualFromPrecompute ? 1.0 : 0.0);
  AddScalar(fd, "SolveTimeMs", solveMs);
  AddScalar(fd, "PrecomputeTimeMs", precomputeMs);
  AddScalar(fd, "PrecomputeReused", freshPrecompute || this->Method == METHOD_FULL_REFERENCE ? 0.0 : 1.0);
  AddString(fd, "Method", faceplan::MethodName(result.method));
  AddString(fd, "Backend", result.backend);
  if (this->Verify) AddScalar(fd, "VerifyMaxRelativeError", verifyError);
  AddScalar(fd, "ConditionEstimate", result.conditionEstimate);
  AddScalar(fd, "LargestStrain", result.largestStrain);
  AddScalar(fd, "InvertedCells", static_cast<double>(result.invertedCells));
  AddString(fd, "ElementOrder", faceplan::ElementOrderName(
                                    this->Method == METHOD_FULL_REFERENCE ? faceplan::ElementOrder::Linear
                                                                          : request.options.elementOrder));
  output->SetFieldData(fd);

  // Stage table, like the paper's Table 2.
  vtkNew<vtkStringArray> stage, backendColumn;
  stage->SetName("Stage");
  backendColumn->SetName("Backend");
  vtkNew<vtkDoubleArray> timeMs;
  timeMs->SetName("TimeMs");
  vtkNew<vtkIntArray> reused;
  reused->SetName("Reused");
  for (int k = 0; k < faceplan::kNumStages; ++k) {
    stage->InsertNextValue(faceplan::StageName(static_cast<faceplan::Stage>(k)));
    timeMs->InsertNextValue(result.timings.stages[k].ms);
    reused->InsertNextValue(result.timings.stages[k].reused ? 1 : 0);
    backendColumn->InsertNextValue(result.backend);
  }
  table->AddColumn(stage);
  table->AddColumn(timeMs);
  table->AddColumn(reused);
  table->AddColumn(backendColumn);
  this->UpdateProgress(1.0);
  return 1;
}

void vtkCondensedFEMDeform::PrintSelf(ostream& os, vtkIndent indent) {
  this->Superclass::PrintSelf(os, indent);
  os << indent << "YoungsModulus: " << this->YoungsModulus << "\n"
     << indent << "PoissonRatio: " << this->PoissonRatio << "\n"
     << indent << "ContactDistance: " << this->ContactDistance << "\n"
     << indent << "OutputMode: " << this->OutputMode << "\n"
     << indent << "Backend: " << this->Backend << "\n"
     << indent << "Method: " << this->Method << "\n"
     << indent << "ElementOrder: " << this->ElementOrder << "\n";
}
