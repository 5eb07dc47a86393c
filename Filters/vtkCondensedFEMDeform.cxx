// SPDX-License-Identifier: BSD-3-Clause
#include "vtkCondensedFEMDeform.h"

#include "Common/BlasKernels.h"
#include "Common/LargeAllocations.h"
#include "CondensedFEMDeformBone.h"
#include "CondensedFEMDeformBoneInput.h"
#include "CondensedFEMDeformContact.h"
#include "CondensedFEMDeformConvert.h"
#include "CondensedFEMDeformInputCache.h"
#include "CondensedFEMDeformOutput.h"
#include "CondensedFEMDeformParallel.h"
#include "CondensedFEMDeformSolver.h"
#include "CondensedFEMDeformValidate.h"
#include "FacePlanArrayRanges.h"
#include "FacePlanFieldData.h"
#include "FacePlanGather.h"

#include "vtkAlgorithmOutput.h"
#include "vtkDataArray.h"
#include "vtkFieldData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkLogger.h"
#include "vtkMultiProcessController.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkPointSet.h"
#include "vtkPolyData.h"
#include "vtkStringArray.h"
#include "vtkTable.h"
#include "vtkUnstructuredGrid.h"

#include <set>
#include <string>

vtkStandardNewMacro(vtkCondensedFEMDeform);

using namespace faceplan::fem_filter;

// What the filter keeps between updates: the validated, converted tissue and its boundary, what
// the bone looked like when the contact was built, the contact map, the precompute request made
// from them, and the solver with its cached precompute.
struct vtkCondensedFEMDeform::Cache {
  TissueCache tissue;
  BoneInput bone;
  ContactCache contact;
  faceplan::PrecomputeRequest request; // mesh, materials and node sets; options set by the solver
  unsigned long requestTissue = 0;     // the tissue generation `request` was made from
  bool requestValid = false;
  int contactBuilds = 0; // updates that (re)built the contact
  Solver solver;
  std::set<std::string> saidNotes; // the warnings of the last update, by NoteState
};

vtkCondensedFEMDeform::vtkCondensedFEMDeform() : State(new Cache) {
  // Each precompute frees tens of MB when the next replaces it: keep that from staying resident.
  faceplan::ReturnLargeAllocationsToSystem();
  // An OpenBLAS that does not know this CPU factors several times slower than it could; only the
  // environment of the next start can change that (Common/BlasKernels.h). Said once per process,
  // in the log at INFO: the results are the same.
  static const bool blasSaid = [] {
    const faceplan::BlasKernels blas = faceplan::DescribeBlasKernels();
    if (!blas.advice.empty())
      vtkLog(INFO, "FacePlan: " << blas.advice);
    return true;
  }();
  (void)blasSaid;
  this->SetNumberOfInputPorts(2);
  this->SetNumberOfOutputPorts(2);
}

vtkCondensedFEMDeform::~vtkCondensedFEMDeform() = default;

int vtkCondensedFEMDeform::GetPrecomputeCount() {
  return this->State->solver.precomputeCount();
}

void vtkCondensedFEMDeform::WaitForBackgroundWork() {
  this->State->solver.waitForBackgroundWork();
}

int vtkCondensedFEMDeform::GetContactBuildCount() {
  return this->State->contactBuilds;
}

namespace {

// The newest modification time of everything upstream of `algorithm` (its inputs' producers and
// their parameters, e.g. a cut's control points or an ROI's region).
vtkMTimeType UpstreamMTime(vtkAlgorithm* algorithm) {
  vtkMTimeType newest = 0;
  for (int port = 0; port < algorithm->GetNumberOfInputPorts(); ++port)
    for (int c = 0; c < algorithm->GetNumberOfInputConnections(port); ++c)
      if (vtkAlgorithm* up = algorithm->GetInputAlgorithm(port, c))
        newest = std::max({newest, up->GetMTime(), UpstreamMTime(up)});
  return newest;
}

// Marks the filter outdated when its inputs changed while RequestData ran (on every return path).
class UpstreamEditWatch {
public:
  UpstreamEditWatch(vtkAlgorithm* algorithm, bool& changed)
      : algorithm_(algorithm), changed_(changed) {
    changed_ = false;
    started_.Modified();
  }
  ~UpstreamEditWatch() { changed_ = UpstreamMTime(algorithm_) > started_.GetMTime(); }

private:
  vtkAlgorithm* algorithm_;
  bool& changed_;
  vtkTimeStamp started_;
};

// A warning's state: its words without the figures, so that an edit of the same situation (the
// same strain warning with another percentage) is not said again.
std::string NoteState(const std::string& note) {
  std::string state;
  for (char c : note)
    if (!(c >= '0' && c <= '9') && c != '.' && c != '-')
      state += c;
  return state;
}

// Says each warning or note once per state: one whose state the last update also had is not
// repeated (the Output Messages window would otherwise open at every edit of one plan, and the log
// would grow by a line per edit). What this update had becomes the next update's record, on every
// return path.
class NoteLog {
public:
  explicit NoteLog(std::set<std::string>& said) : said_(said) {}
  ~NoteLog() { said_.swap(now_); }
  bool sayNow(const std::string& note) {
    const std::string state = NoteState(note);
    now_.insert(state);
    return !said_.count(state);
  }

private:
  std::set<std::string>& said_;
  std::set<std::string> now_;
};

} // namespace

vtkMTimeType vtkCondensedFEMDeform::GetMTime() {
  if (this->InputsChangedWhileRunning)
    this->OutdatedTime.Modified();
  return std::max(this->Superclass::GetMTime(),
                  this->InputsChangedWhileRunning ? this->OutdatedTime.GetMTime() : 0);
}

int vtkCondensedFEMDeform::FillInputPortInformation(int port, vtkInformation* info) {
  if (port == 0)
    info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkUnstructuredGrid");
  else {
    info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkPointSet");
    info->Set(vtkAlgorithm::INPUT_IS_REPEATABLE(), 1);
  }
  return 1;
}

int vtkCondensedFEMDeform::FillOutputPortInformation(int port, vtkInformation* info) {
  if (port == 0)
    info->Set(vtkDataObject::DATA_TYPE_NAME(), "vtkUnstructuredGrid");
  else
    info->Set(vtkDataObject::DATA_TYPE_NAME(), "vtkTable");
  return 1;
}

// The property's Auto value is the one the settings resolve (Settings::sealGap).
static_assert(vtkCondensedFEMDeform::LIP_SEAL_AUTO == Settings::kLipSealAuto,
              "LipSeal's Auto value must be the settings' own");
static_assert(vtkCondensedFEMDeform::CONTACT_AUTO == static_cast<int>(ContactModelChoice::Auto),
              "ContactModel's Auto value must be the contact step's own");

int vtkCondensedFEMDeform::RequestData(vtkInformation*, vtkInformationVector** inputVector,
                                       vtkInformationVector* outputVector) {
  vtkUnstructuredGrid* tissue = vtkUnstructuredGrid::GetData(inputVector[0], 0);
  std::vector<vtkPointSet*> bones;
  for (int c = 0; c < inputVector[1]->GetNumberOfInformationObjects(); ++c)
    bones.push_back(vtkPointSet::GetData(inputVector[1], c));
  if (bones.empty())
    bones.push_back(nullptr);
  vtkUnstructuredGrid* output = vtkUnstructuredGrid::GetData(outputVector, 0);
  vtkTable* table = vtkTable::GetData(outputVector, 1);
  // A connection without Displacement is a fixed bone (ARCHITECTURE.md, "Fixed bone"): it gets a
  // zero Displacement on a shallow copy, so every later step sees one kind of bone.
  std::vector<vtkSmartPointer<vtkPointSet>> fixedBones;
  for (vtkPointSet*& bone : bones)
    if (bone && !bone->GetPointData()->GetArray("Displacement")) {
      fixedBones.push_back(WithZeroDisplacement(bone));
      bone = fixedBones.back();
    }
  // An operation preset's bone (Osteotomy's field data Operation) sets LipSeal Auto's gap; the
  // merge keeps only the segments' field data, so it is read from the connections.
  this->BoneOperation.clear();
  for (vtkPointSet* bone : bones)
    if (bone)
      if (auto* operation =
              vtkStringArray::SafeDownCast(bone->GetFieldData()->GetAbstractArray("Operation")))
        if (operation->GetNumberOfValues() > 0 && this->BoneOperation.empty())
          this->BoneOperation = operation->GetValue(0);
  // Several connections (a bimaxillary plan) become one bone, each checked first.
  for (size_t c = 0; bones.size() > 1 && c < bones.size(); ++c) {
    const faceplan::Status status = ValidateBone(bones[c]);
    if (!status) {
      vtkErrorMacro(<< "Bone connection " << c << ": " << status.message);
      return 1;
    }
  }
  const vtkSmartPointer<vtkPointSet> mergedBone = MergeBones(bones);
  vtkPointSet* bone = mergedBone;
  // Under MPI the pieces are gathered and solved once (CondensedFEMDeformParallel.h).
  if (vtkMultiProcessController* controller = faceplan::gather::DistributedController()) {
    DeformGathered(controller, this->CurrentSettings().output(), tissue, bone, output, table,
                   [this](vtkUnstructuredGrid* t, vtkPointSet* b, vtkUnstructuredGrid* o,
                          vtkTable* tab) { return this->Deform(t, b, o, tab); });
  } else
    this->Deform(tissue, bone, output, table);
  // The field data are the solve's figures (Backend, Method, SolveTimeMs, ...), all made here:
  // the colour-by list offers the point arrays (Displacement) only.
  faceplan::fielddata::HideFromArrayLists(output->GetFieldData());
  std::vector<vtkDataObject*> inputs{tissue};
  for (int c = 0; c < inputVector[1]->GetNumberOfInformationObjects(); ++c)
    inputs.push_back(vtkDataObject::GetData(inputVector[1], c));
  for (vtkDataObject* o : {static_cast<vtkDataObject*>(output), static_cast<vtkDataObject*>(table)})
    faceplan::CacheArrayRanges(o, inputs);
  return 1;
}

bool vtkCondensedFEMDeform::Deform(vtkUnstructuredGrid* tissue, vtkPointSet* bone,
                                   vtkUnstructuredGrid* output, vtkTable* table) {
  Cache& cache = *this->State;
  const Settings settings = this->CurrentSettings();
  const UpstreamEditWatch watch(this, this->InputsChangedWhileRunning);
  NoteLog notes(cache.saidNotes);
  auto warn = [this, &notes](const std::string& note) {
    if (notes.sayNow(note))
      vtkWarningMacro(<< note);
  };
  auto inform = [this, &notes](const std::string& note) {
    if (notes.sayNow(note))
      vtkLog(INFO, << this->GetObjectDescription() << ": " << note);
  };

  // 1. validate and 2. convert: nothing below runs on malformed input. The tissue is validated and
  // converted again only when it or the material properties changed; the bone is taken in one
  // pass (BoneInput: validated once, its cells in full only when they changed, the undeformed
  // bone computed once, and whether the contact still holds).
  faceplan::Status status = ValidateProperties(settings);
  if (status)
    status = cache.tissue.update(tissue, settings);
  const unsigned long tissueGeneration = cache.tissue.generation();
  if (status)
    status = cache.bone.update(bone, tissueGeneration, settings.contactDistance,
                               settings.releaseDistance);
  if (!status) {
    cache.requestValid = false;
    vtkErrorMacro(<< status.message);
    return false;
  }
  const TissueBoundary& boundary = cache.tissue.boundary();
  // A gap set by hand that ties nothing is a mistake; Auto's 3 mm tying nothing is a face whose
  // lips are further apart at rest (lip incompetence), which the model then leaves open.
  if (settings.sealGap() > 0.0 && cache.tissue.lipSeal().bridges == 0) {
    const std::string none = "LipSeal: no facing tissue surfaces within " +
                             std::to_string(settings.sealGap()) + " mesh units, so nothing is tied";
    if (settings.lipSeal == Settings::kLipSealAuto) {
      inform(none + " (Auto: the lips stay open)");
    } else {
      warn(none);
    }
  }
  this->UpdateProgress(0.05);

  // 3. contact, rebuilt when the tissue, the distance, the release distance or the undeformed
  // bone (its cells, ROIMask, SegmentId, Released and points minus Displacement) changed: a move of
  // a cut or an osteotomy keeps it.
  const bool contactBuilt = cache.bone.contactChanged();
  if (contactBuilt) {
    status = cache.contact.build(tissue, boundary.nodes, bone, cache.bone.undeformed(),
                                 settings.contactDistance, settings.releaseDistance);
    if (!status) {
      cache.bone.contactLost();
      vtkErrorMacro(<< status.message);
      return false;
    }
    cache.bone.contactBuilt();
    ++cache.contactBuilds;
  }
  const ContactMap& contact = cache.contact.map();
  if (contact.tiedNodes.empty()) {
    vtkErrorMacro("no tissue boundary node lies within ContactDistance = "
                  << settings.contactDistance
                  << " of the undeformed bone: increase ContactDistance or check that tissue and "
                     "bone share one frame and unit");
    return false;
  }
  const std::string unfollowed =
      UnfollowedBoneMotion(contact.movable, bone->GetPointData()->GetArray("Displacement"));
  if (!unfollowed.empty())
    warn(unfollowed);
  if (static_cast<ContactModelChoice>(settings.contactModel) == ContactModelChoice::ByArray &&
      !bone->GetPointData()->GetArray("Sliding")) {
    vtkErrorMacro("ContactModel ByArray needs a bone point array named Sliding (uint8, 1 = slide)");
    return false;
  }
  // Rigid segments: the bone's SegmentId and SegmentTransform, used when its Displacement follows
  // them; a node tied to a segment then moves with it as one body.
  const BoneSegments segments = ReadBoneSegments(bone, cache.bone.undeformed());
  if (!segments.usable && bone->GetPointData()->GetArray("SegmentId"))
    warn("rigid-segment path not used: " + segments.whyNot);
  // Released tissue is what the surgeon asked for: information (field data ReleasedNodes and the
  // log at INFO, when the contact is built: an edit that keeps it releases the same nodes), not a
  // warning.
  const bool releasedArray = bone->GetPointData()->GetArray("Released") != nullptr;
  if (contactBuilt && (settings.releaseDistance > 0.0 || releasedArray))
    vtkLog(INFO, << this->GetObjectDescription() << ": " << ReleasedCount(contact)
                 << " tied nodes released "
                 << (settings.releaseDistance > 0.0
                         ? (releasedArray ? "within ReleaseDistance of a cut or the ROI's "
                                            "boundary, or on bone points marked Released"
                                          : "within ReleaseDistance of a cut or the ROI's "
                                            "boundary")
                         : "on bone points marked Released"));
  if (!cache.requestValid || cache.requestTissue != tissueGeneration) {
    cache.request = faceplan::PrecomputeRequest();
    cache.request.mesh = cache.tissue.mesh();
    cache.request.materials = cache.tissue.materials();
    cache.requestTissue = tissueGeneration;
    cache.requestValid = true;
  }
  // The node sets also follow the contact model, the Sliding flags and the segments (cheap to
  // rebuild; the solver reuses its precompute while the whole request is equal).
  const ContactModelChoice contactModel =
      ResolveContactModel(static_cast<ContactModelChoice>(settings.contactModel),
                          bone->GetPointData()->GetArray("Sliding") != nullptr);
  cache.request.sets =
      MakeNodeSets(contact, boundary.nodes, contactModel, bone->GetPointData()->GetArray("Sliding"),
                   segments.usable ? segments.segmentOfPoint : std::vector<int>());
  const faceplan::PrecomputeRequest& request = cache.request;
  faceplan::SolveInput input;
  input.movableDisplacement =
      MovableDisplacements(contact, bone->GetPointData()->GetArray("Displacement"));
  if (segments.usable) {
    input.segmentTransforms = segments.transforms;
    input.movableDisplacement = faceplan::FollowSegments(
        request.mesh.points, request.sets, segments.transforms, input.movableDisplacement);
  }
  if (settings.useGravity)
    input.gravity = Eigen::Vector3d(settings.gravity[0], settings.gravity[1], settings.gravity[2]);
  input.recoverInterior = settings.output() == OutputMode::Volume;

  // 4. solve (the precompute runs on a worker thread and is reused while the request is the same)
  SolveOutcome outcome;
  status = cache.solver.run(
      request, input, settings,
      [this](double fraction) { this->UpdateProgress(0.1 + 0.8 * fraction); }, outcome);
  for (const auto& note : outcome.notes)
    warn(note);
  if (!status) {
    vtkErrorMacro(<< status.message);
    return false;
  }
  // A tissue that moves far beyond every bone is held by too few bones (a fixed bone left out).
  // Under gravity the tissue sags even where every bone holds it, by an amount its density and
  // stiffness set rather than any bone's move, so the comparison would say nothing true: telling a
  // sag from a missing bone would take a second solve without gravity. The check is skipped.
  if (!settings.useGravity) {
    const faceplan::RowVectors3d& tissueMoves = outcome.result.keptDisplacement;
    const double tissueLargest = tissueMoves.rows() ? tissueMoves.rowwise().norm().maxCoeff() : 0.0;
    const std::string loose =
        LooseTissueNote(tissueLargest, bone->GetPointData()->GetArray("Displacement"),
                        tissue->GetLength(), settings.lengthUnit);
    if (!loose.empty())
      warn(loose);
  }
  this->UpdateProgress(0.95);

  // 5. build output
  BuildDeformedTissue(tissue, boundary, request.mesh.points, outcome, settings.output(), output);
  AddFieldData(outcome, settings, output);
  faceplan::fielddata::AddScalar(output->GetFieldData(), "ReleasedNodes",
                                 static_cast<double>(ReleasedCount(contact)));
  faceplan::fielddata::AddScalar(output->GetFieldData(), "LipSealBridges",
                                 static_cast<double>(cache.tissue.lipSeal().bridges));
  faceplan::fielddata::AddScalar(output->GetFieldData(), "LipSealGap", settings.sealGap());
  faceplan::fielddata::AddString(output->GetFieldData(), "ContactModel",
                                 ContactModelName(contactModel));
  BuildStageTable(outcome, table);
  this->UpdateProgress(1.0);
  return true;
}

Settings vtkCondensedFEMDeform::CurrentSettings() const {
  Settings s;
  s.youngsModulus = this->YoungsModulus;
  s.poissonRatio = this->PoissonRatio;
  s.useCellMaterials = this->UseCellMaterials;
  s.lengthUnit = this->LengthUnit;
  s.contactDistance = this->ContactDistance;
  s.contactModel = this->ContactModel;
  s.releaseDistance = this->ReleaseDistance;
  s.useGravity = this->UseGravity;
  s.density = this->Density;
  for (int c = 0; c < 3; ++c)
    s.gravity[c] = this->Gravity[c];
  s.outputMode = this->OutputMode;
  s.backend = this->Backend;
  s.method = this->Method;
  s.elementOrder = this->ElementOrder;
  s.model = this->Model;
  s.largeDeformationSolver = this->LargeDeformationSolver;
  s.iterationLimit = this->QuasiNewtonIterationLimit;
  s.liftOff = this->LiftOff;
  s.lipSeal = this->LipSeal;
  s.boneOperation = this->BoneOperation;
  s.verify = this->Verify;
  return s;
}

void vtkCondensedFEMDeform::PrintSelf(ostream& os, vtkIndent indent) {
  this->Superclass::PrintSelf(os, indent);
  os << indent << "YoungsModulus: " << this->YoungsModulus << "\n"
     << indent << "PoissonRatio: " << this->PoissonRatio << "\n"
     << indent << "UseCellMaterials: " << this->UseCellMaterials << "\n"
     << indent << "LengthUnit: " << this->LengthUnit << "\n"
     << indent << "ContactDistance: " << this->ContactDistance << "\n"
     << indent << "ContactModel: " << this->ContactModel << "\n"
     << indent << "ReleaseDistance: " << this->ReleaseDistance << "\n"
     << indent << "UseGravity: " << this->UseGravity << "\n"
     << indent << "Density: " << this->Density << "\n"
     << indent << "Gravity: (" << this->Gravity[0] << ", " << this->Gravity[1] << ", "
     << this->Gravity[2] << ")\n"
     << indent << "OutputMode: " << this->OutputMode << "\n"
     << indent << "Backend: " << this->Backend << "\n"
     << indent << "Method: " << this->Method << "\n"
     << indent << "ElementOrder: " << this->ElementOrder << "\n"
     << indent << "Model: " << this->Model << "\n"
     << indent << "LargeDeformationSolver: " << this->LargeDeformationSolver << "\n"
     << indent << "QuasiNewtonIterationLimit: " << this->QuasiNewtonIterationLimit << "\n"
     << indent << "LiftOff: " << this->LiftOff << "\n"
     << indent << "LipSeal: " << this->LipSeal << "\n"
     << indent << "Verify: " << this->Verify << "\n";
}
