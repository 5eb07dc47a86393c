// SPDX-License-Identifier: BSD-3-Clause
#include "vtkFacialLandmarks.h"

#include "FacePlanArrayRanges.h"
#include "Landmarks/ClinicalBands.h"
#include "Landmarks/FacialLandmarks.h"
#include "Landmarks/LandmarkTable.h"
#include "Osteotomy/OperationPresets.h"

#include <vtkCellArray.h>
#include <vtkCellLocator.h>
#include <vtkCutter.h>
#include <vtkDataSet.h>
#include <vtkDataSetSurfaceFilter.h>
#include <vtkDemandDrivenPipeline.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkGenericCell.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkPlane.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkStringArray.h>
#include <vtkTable.h>

#include <array>
#include <cmath>
#include <sstream>

vtkStandardNewMacro(vtkFacialLandmarks);

namespace {

namespace lm = faceplan::landmarks;

// A surface at its pre-operative position, its displacement and a locator over it.
struct Surface {
  vtkSmartPointer<vtkPolyData> pre;
  vtkSmartPointer<vtkDoubleArray> displacement; // per point of `pre`
  vtkSmartPointer<vtkCellLocator> locator;
  double diagonal = 0.0;
};

// The boundary surface of `data` (polygons only), moved back by its Displacement. Sets `why` and
// returns false on bad input.
bool PreOperativeSurface(vtkDataSet* data, const char* what, Surface& out, std::string& why) {
  vtkNew<vtkDataSetSurfaceFilter> surface;
  surface->SetInputData(data);
  surface->Update();
  vtkPolyData* s = surface->GetOutput();
  if (s->GetNumberOfPoints() == 0 || s->GetNumberOfPolys() + s->GetNumberOfStrips() == 0) {
    why = std::string("the ") + what +
          " has no surface (no skin): give the soft tissue's volume or "
          "surface";
    return false;
  }
  out.pre = vtkSmartPointer<vtkPolyData>::New();
  out.pre->ShallowCopy(s);
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  const vtkIdType n = s->GetNumberOfPoints();
  points->SetNumberOfPoints(n);
  out.displacement = vtkSmartPointer<vtkDoubleArray>::New();
  out.displacement->SetNumberOfComponents(3);
  out.displacement->SetNumberOfTuples(n);
  out.displacement->SetName("Displacement");
  vtkDataArray* u = s->GetPointData()->GetArray("Displacement");
  if (u && u->GetNumberOfComponents() != 3) {
    why = std::string("the ") + what + "'s Displacement does not have 3 components";
    return false;
  }
  for (vtkIdType i = 0; i < n; ++i) {
    double x[3], d[3] = {0.0, 0.0, 0.0};
    s->GetPoint(i, x);
    if (u)
      u->GetTuple(i, d);
    for (int c = 0; c < 3; ++c) {
      if (!std::isfinite(x[c])) {
        why = std::string("the ") + what + " has a NaN or infinite coordinate (point " +
              std::to_string(i) + ")";
        return false;
      }
      if (!std::isfinite(d[c])) {
        why = std::string("the ") + what + "'s Displacement has a NaN or infinite value (point " +
              std::to_string(i) + ")";
        return false;
      }
      x[c] -= d[c];
    }
    points->SetPoint(i, x);
    out.displacement->SetTuple(i, d);
  }
  out.pre->SetPoints(points);
  out.pre->GetPointData()->Initialize();
  out.locator = vtkSmartPointer<vtkCellLocator>::New();
  out.locator->SetDataSet(out.pre);
  out.locator->BuildLocator();
  out.diagonal = out.pre->GetLength();
  return true;
}

// The segments where a plane cuts the surface (vtkCutter).
lm::Segments Section(vtkPolyData* surface, const Eigen::Vector3d& origin,
                     const Eigen::Vector3d& normal) {
  vtkNew<vtkPlane> plane;
  plane->SetOrigin(origin.data());
  plane->SetNormal(normal.data());
  vtkNew<vtkCutter> cutter;
  cutter->SetCutFunction(plane);
  cutter->SetInputData(surface);
  cutter->Update();
  vtkPolyData* cut = cutter->GetOutput();
  lm::Segments segments;
  vtkCellArray* lines = cut->GetLines();
  vtkIdType npts = 0;
  const vtkIdType* ids = nullptr;
  for (lines->InitTraversal(); lines->GetNextCell(npts, ids);)
    for (vtkIdType k = 0; k + 1 < npts; ++k) {
      double a[3], b[3];
      cut->GetPoint(ids[k], a);
      cut->GetPoint(ids[k + 1], b);
      segments.emplace_back(a[0], a[1], a[2]);
      segments.emplace_back(b[0], b[1], b[2]);
    }
  return segments;
}

// The surface point nearest to x and the displacement interpolated there.
void Locate(const Surface& s, const Eigen::Vector3d& x, Eigen::Vector3d& nearest,
            Eigen::Vector3d& displacement, double& distance) {
  double closest[3], dist2 = 0.0;
  vtkIdType cellId = -1;
  int subId = 0;
  vtkNew<vtkGenericCell> cell;
  s.locator->FindClosestPoint(x.data(), closest, cell, cellId, subId, dist2);
  nearest = Eigen::Vector3d(closest);
  distance = std::sqrt(dist2);
  displacement.setZero();
  if (cellId < 0)
    return;
  double pcoords[3], weights[64], d2 = 0.0, projected[3];
  if (cell->GetNumberOfPoints() > 64)
    return;
  cell->EvaluatePosition(closest, projected, subId, pcoords, d2, weights);
  for (vtkIdType k = 0; k < cell->GetNumberOfPoints(); ++k) {
    double d[3];
    s.displacement->GetTuple(cell->GetPointId(k), d);
    displacement += weights[k] * Eigen::Vector3d(d);
  }
}

} // namespace

vtkFacialLandmarks::vtkFacialLandmarks() {
  this->SetNumberOfInputPorts(2);
  this->SetNumberOfOutputPorts(2);
}

void vtkFacialLandmarks::SetFrankfortPoint(int index, double x, double y, double z) {
  if (index < 0 || index > 2) {
    vtkErrorMacro(<< "FacialLandmarks: Frankfort point " << index << " out of range [0, 2]");
    return;
  }
  double* p = this->FrankfortPoints + 3 * index;
  if (p[0] != x || p[1] != y || p[2] != z) {
    p[0] = x;
    p[1] = y;
    p[2] = z;
    this->Modified();
  }
}

void vtkFacialLandmarks::AddOverride(const char* entry) {
  this->Overrides.emplace_back(entry ? entry : "");
  this->Modified();
}

void vtkFacialLandmarks::RemoveAllOverrides() {
  if (!this->Overrides.empty()) {
    this->Overrides.clear();
    this->Modified();
  }
}

int vtkFacialLandmarks::FillInputPortInformation(int port, vtkInformation* info) {
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkDataSet");
  if (port == 1)
    info->Set(vtkAlgorithm::INPUT_IS_OPTIONAL(), 1);
  return 1;
}

int vtkFacialLandmarks::FillOutputPortInformation(int port, vtkInformation* info) {
  info->Set(vtkDataObject::DATA_TYPE_NAME(), port == 0 ? "vtkTable" : "vtkPolyData");
  return 1;
}

vtkTypeBool vtkFacialLandmarks::ProcessRequest(vtkInformation* request,
                                               vtkInformationVector** inputVector,
                                               vtkInformationVector* outputVector) {
  if (request->Has(vtkDemandDrivenPipeline::REQUEST_DATA()))
    return this->RequestData(request, inputVector, outputVector);
  return this->Superclass::ProcessRequest(request, inputVector, outputVector);
}

int vtkFacialLandmarks::RequestData(vtkInformation*, vtkInformationVector** inputVector,
                                    vtkInformationVector* outputVector) {
  this->LastError.clear();
  vtkDataSet* tissue = vtkDataSet::GetData(inputVector[0], 0);
  vtkDataSet* bone =
      this->GetNumberOfInputConnections(1) > 0 ? vtkDataSet::GetData(inputVector[1], 0) : nullptr;
  vtkTable* table = vtkTable::GetData(outputVector, 0);
  vtkPolyData* points = vtkPolyData::GetData(outputVector, 1);
  table->Initialize();
  points->Initialize();
  auto fail = [&](const std::string& message) {
    this->LastError = message;
    table->Initialize();
    points->Initialize();
    vtkErrorMacro(<< "FacialLandmarks: " << message);
    return 1;
  };

  // Validate and convert.
  if (!tissue || tissue->GetNumberOfPoints() == 0)
    return fail("the soft tissue input is empty (no skin)");
  if (this->Operation < FROM_BONE || this->Operation > NONE)
    return fail("Operation must be 0 (FromBone), 1 (LeFortI), 2 (BSSO), 3 (Genioplasty) or 4 "
                "(None), not " +
                std::to_string(this->Operation));
  if (this->PlacedLandmark < -1 || this->PlacedLandmark >= lm::kLandmarkCount)
    return fail("PlacedLandmark must be -1 (none) or a landmark from 0 (Pronasale) to " +
                std::to_string(lm::kLandmarkCount - 1) + " (Menton), not " +
                std::to_string(this->PlacedLandmark));
  if (this->ReferenceFrame != MODEL_AXES && this->ReferenceFrame != FRANKFORT_HORIZONTAL)
    return fail("ReferenceFrame must be 0 (ModelAxes) or 1 (FrankfortHorizontal), not " +
                std::to_string(this->ReferenceFrame));
  Surface skin, boneSurface;
  std::string why;
  if (!PreOperativeSurface(tissue, "soft tissue", skin, why))
    return fail(why);
  const bool haveBone = bone && bone->GetNumberOfPoints() > 0;
  if (haveBone && !PreOperativeSurface(bone, "bone", boneSurface, why))
    return fail(why);

  lm::Frame frame;
  faceplan::Status framed =
      this->ReferenceFrame == MODEL_AXES
          ? lm::ModelAxesFrame(Eigen::Vector3d(this->MidsagittalOrigin),
                               Eigen::Vector3d(this->MidsagittalNormal),
                               Eigen::Vector3d(this->AnteriorDirection),
                               Eigen::Vector3d(this->SuperiorDirection), frame)
          : lm::FrankfortFrame(Eigen::Vector3d(this->FrankfortPoints),
                               Eigen::Vector3d(this->FrankfortPoints + 3),
                               Eigen::Vector3d(this->FrankfortPoints + 6),
                               Eigen::Vector3d(this->SuperiorDirection), frame);
  if (!framed)
    return fail(framed.message);

  faceplan::Operation operation = faceplan::Operation::Custom;
  if (this->Operation == FROM_BONE) {
    auto* names =
        haveBone ? vtkStringArray::SafeDownCast(bone->GetFieldData()->GetAbstractArray("Operation"))
                 : nullptr;
    if (names && names->GetNumberOfValues() > 0)
      for (int o = 1; o <= 3; ++o)
        if (names->GetValue(0) == faceplan::OperationName(static_cast<faceplan::Operation>(o)))
          operation = static_cast<faceplan::Operation>(o);
  } else if (this->Operation != NONE) {
    operation = static_cast<faceplan::Operation>(this->Operation);
  }

  // Sections (VTK's cutter) and the definitions (Core).
  lm::Placement placement;
  const lm::Segments skinMidline = Section(skin.pre, frame.origin, frame.lateral);
  lm::PlaceMidlineSkin(skinMidline, frame, placement);
  if (haveBone) {
    lm::PlaceMidlineBone(Section(boneSurface.pre, frame.origin, frame.lateral), frame, placement);
    lm::PlaceSkinMenton(skinMidline, frame, placement);
  } else {
    for (int i = static_cast<int>(lm::Landmark::ANS); i < lm::kLandmarkCount; ++i)
      placement.miss(static_cast<lm::Landmark>(i), "no bone input");
    placement.miss(lm::Landmark::SoftTissueMenton, "needs Menton on the bone (no bone input)");
  }
  if (placement.has(lm::Landmark::Stomion)) {
    const Eigen::Vector3d level = placement.at(lm::Landmark::Stomion);
    lm::PlaceLateralPair(Section(skin.pre, level, frame.superior), frame, level,
                         lm::Landmark::CheilionRight, lm::Landmark::CheilionLeft, true, placement);
  } else {
    placement.miss(lm::Landmark::CheilionRight, "needs Stomion");
    placement.miss(lm::Landmark::CheilionLeft, "needs Stomion");
  }
  if (placement.has(lm::Landmark::Subnasale) && placement.has(lm::Landmark::Pronasale)) {
    const Eigen::Vector3d level = lm::AlarLevel(placement);
    lm::PlaceLateralPair(Section(skin.pre, level, frame.superior), frame, level,
                         lm::Landmark::AlarBaseRight, lm::Landmark::AlarBaseLeft, false, placement);
  } else {
    placement.miss(lm::Landmark::AlarBaseRight, "needs Subnasale and Pronasale");
    placement.miss(lm::Landmark::AlarBaseLeft, "needs Subnasale and Pronasale");
  }

  // Overrides: the user's point, snapped to its surface. The handle's landmark comes last, so it
  // wins over a list entry for the same landmark.
  auto placeOverride = [&](const std::string& what, int which, const double x[3],
                           const char* howToFix) {
    if (!std::isfinite(x[0]) || !std::isfinite(x[1]) || !std::isfinite(x[2]))
      return "override " + what + " has a non-finite coordinate";
    const bool isSkin = lm::IsSkinLandmark(static_cast<lm::Landmark>(which));
    if (!isSkin && !haveBone)
      return "override " + what + " is a bony landmark but there is no bone input";
    const Surface& s = isSkin ? skin : boneSurface;
    Eigen::Vector3d nearest, u;
    double distance = 0.0;
    Locate(s, Eigen::Vector3d(x), nearest, u, distance);
    if (!(distance <= 0.02 * s.diagonal))
      return "override " + what + " lies " + std::to_string(distance) + " from the " +
             (isSkin ? "skin" : "bone") + " (outside the mesh; at most 2 % of its size, " +
             std::to_string(0.02 * s.diagonal) + ", is allowed)" + howToFix;
    placement.set(static_cast<lm::Landmark>(which), nearest);
    return std::string();
  };
  for (const std::string& entry : this->Overrides) {
    std::istringstream in(entry);
    std::string name;
    double x[3] = {0.0, 0.0, 0.0};
    if (!(in >> name >> x[0] >> x[1] >> x[2]))
      return fail("override '" + entry + "' is not 'Name x y z'");
    int which = -1;
    for (int i = 0; i < lm::kLandmarkCount; ++i)
      if (lm::LandmarkName(static_cast<lm::Landmark>(i)) == name)
        which = i;
    if (which < 0)
      return fail("override '" + entry + "' names no landmark (Pronasale, ..., Menton)");
    const std::string problem = placeOverride("'" + entry + "'", which, x, "");
    if (!problem.empty())
      return fail(problem);
  }
  if (this->PlacedLandmark >= 0) {
    const std::string problem = placeOverride(
        "PlacedLandmark " + lm::LandmarkName(static_cast<lm::Landmark>(this->PlacedLandmark)) +
            " (the point handle)",
        this->PlacedLandmark, this->PlacedLandmarkPosition,
        ": drag the handle onto the surface, or hover over the surface in the 3D view and press P");
    if (!problem.empty())
      return fail(problem);
  }

  // The displacement field at each landmark (the cell vtkCellLocator finds), then Core's table.
  std::array<Eigen::Vector3d, lm::kLandmarkCount> displacement;
  for (int i = 0; i < lm::kLandmarkCount; ++i) {
    displacement[i].setZero();
    if (!placement.found[i])
      continue;
    const Surface& s = lm::IsSkinLandmark(static_cast<lm::Landmark>(i)) ? skin : boneSurface;
    Eigen::Vector3d nearest;
    double distance = 0.0;
    Locate(s, placement.position[i], nearest, displacement[i], distance);
  }
  std::vector<lm::LandmarkRow> rows;
  const double still = 1e-3 * std::max(placement.profileHeight, 1e-300);
  if (faceplan::Status s = lm::LandmarkRows(placement, displacement, frame, operation, still, rows);
      !s)
    return fail(s.message);

  // Output 0: the table.
  auto column = [&](auto array, const char* name, int components = 1) {
    array->SetName(name);
    array->SetNumberOfComponents(components);
    array->SetNumberOfTuples(static_cast<vtkIdType>(rows.size()));
    table->AddColumn(array);
    return array;
  };
  auto* name = column(vtkStringArray::New(), "Landmark");
  auto* kind = column(vtkStringArray::New(), "Kind");
  auto* found = column(vtkIntArray::New(), "Found");
  auto* pre = column(vtkDoubleArray::New(), "Pre", 3);
  auto* post = column(vtkDoubleArray::New(), "Post", 3);
  auto* horizontal = column(vtkDoubleArray::New(), "Horizontal");
  auto* vertical = column(vtkDoubleArray::New(), "Vertical");
  auto* paired = column(vtkStringArray::New(), "PairedBone");
  auto* boneH = column(vtkDoubleArray::New(), "BoneHorizontal");
  auto* boneV = column(vtkDoubleArray::New(), "BoneVertical");
  auto* ratio = column(vtkDoubleArray::New(), "Ratio");
  auto* band = column(vtkStringArray::New(), "Band");
  auto* low = column(vtkDoubleArray::New(), "BandLow");
  auto* high = column(vtkDoubleArray::New(), "BandHigh");
  auto* source = column(vtkStringArray::New(), "Source");
  auto* check = column(vtkStringArray::New(), "Check");
  auto* note = column(vtkStringArray::New(), "Note");
  std::string missing;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const lm::LandmarkRow& row = rows[r];
    const vtkIdType i = static_cast<vtkIdType>(r);
    const bool isSkin = lm::IsSkinLandmark(row.landmark);
    name->SetValue(i, lm::LandmarkName(row.landmark));
    kind->SetValue(i, isSkin ? "skin" : "bone");
    found->SetValue(i, row.found ? 1 : 0);
    pre->SetTuple(i, row.pre.data());
    post->SetTuple(i, row.post.data());
    horizontal->SetValue(i, row.horizontal);
    vertical->SetValue(i, row.vertical);
    paired->SetValue(i, isSkin ? lm::LandmarkName(row.paired) : "");
    boneH->SetValue(i, row.boneHorizontal);
    boneV->SetValue(i, row.boneVertical);
    ratio->SetValue(i, row.ratioDefined ? row.ratio : 0.0);
    if (row.band) {
      std::ostringstream b;
      b << lm::MovementName(row.band->movement) << " "
        << (row.band->component == lm::Component::Horizontal ? "horizontal" : "vertical") << " "
        << row.band->low << "-" << row.band->high;
      band->SetValue(i, b.str());
      low->SetValue(i, row.band->low);
      high->SetValue(i, row.band->high);
      source->SetValue(i, row.band->source);
    } else {
      band->SetValue(i, "");
      low->SetValue(i, 0.0);
      high->SetValue(i, 0.0);
      source->SetValue(i, "");
    }
    check->SetValue(i, row.check);
    note->SetValue(i, row.note);
    if (!row.found)
      missing +=
          (missing.empty() ? "" : ", ") + lm::LandmarkName(row.landmark) + " (" + row.note + ")";
  }
  for (vtkIdType c = 0; c < table->GetNumberOfColumns(); ++c)
    table->GetColumn(c)->UnRegister(this);

  // Output 1: the found landmarks at their post-operative positions.
  vtkNew<vtkPoints> out;
  out->SetDataTypeToDouble();
  vtkNew<vtkCellArray> verts;
  vtkNew<vtkStringArray> names;
  names->SetName("Landmark");
  vtkNew<vtkStringArray> kinds;
  kinds->SetName("Kind");
  vtkNew<vtkDoubleArray> moved;
  moved->SetName("Displacement");
  moved->SetNumberOfComponents(3);
  for (const lm::LandmarkRow& row : rows) {
    if (!row.found)
      continue;
    const vtkIdType id = out->InsertNextPoint(row.post.data());
    verts->InsertNextCell(1, &id);
    names->InsertNextValue(lm::LandmarkName(row.landmark));
    kinds->InsertNextValue(lm::IsSkinLandmark(row.landmark) ? "skin" : "bone");
    const Eigen::Vector3d u = row.post - row.pre;
    moved->InsertNextTuple(u.data());
  }
  points->SetPoints(out);
  points->SetVerts(verts);
  points->GetPointData()->AddArray(names);
  points->GetPointData()->AddArray(kinds);
  points->GetPointData()->AddArray(moved);
  if (!missing.empty() && haveBone)
    vtkWarningMacro(<< "FacialLandmarks: not found: " << missing);
  for (vtkDataObject* o : {static_cast<vtkDataObject*>(table), static_cast<vtkDataObject*>(points)})
    faceplan::CacheArrayRanges(o, {tissue, bone});
  return 1;
}

void vtkFacialLandmarks::PrintSelf(ostream& os, vtkIndent indent) {
  this->Superclass::PrintSelf(os, indent);
  auto v3 = [&](const char* label, const double* v) {
    os << indent << label << ": " << v[0] << " " << v[1] << " " << v[2] << "\n";
  };
  v3("MidsagittalOrigin", this->MidsagittalOrigin);
  v3("MidsagittalNormal", this->MidsagittalNormal);
  v3("AnteriorDirection", this->AnteriorDirection);
  v3("SuperiorDirection", this->SuperiorDirection);
  os << indent << "ReferenceFrame: " << this->ReferenceFrame << "\n";
  v3("FrankfortPoints[0]", this->FrankfortPoints);
  v3("FrankfortPoints[1]", this->FrankfortPoints + 3);
  v3("FrankfortPoints[2]", this->FrankfortPoints + 6);
  os << indent << "Operation: " << this->Operation << "\n";
  os << indent << "Overrides: " << this->Overrides.size() << "\n";
  for (const std::string& o : this->Overrides)
    os << indent << "  " << o << "\n";
  os << indent << "PlacedLandmark: " << this->PlacedLandmark << "\n";
  v3("PlacedLandmarkPosition", this->PlacedLandmarkPosition);
}
