// SPDX-License-Identifier: BSD-3-Clause
#include "CondensedFEMDeformValidate.h"

#include "FacePlanUndeformedBone.h"

#include "vtkCellArray.h"
#include "vtkCellData.h"
#include "vtkCellType.h"
#include "vtkDataArray.h"
#include "vtkDoubleArray.h"
#include "vtkIdList.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkPointSet.h"
#include "vtkPoints.h"
#include "vtkUnstructuredGrid.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace faceplan {
namespace fem_filter {

namespace {

template <class... Parts> Status Error(const Parts&... parts) {
  std::ostringstream msg;
  (msg << ... << parts);
  return Status::Error(msg.str());
}

// Coordinates beyond this are refused: VTK's closest-point search multiplies up to four lengths
// (its triangle's 2x2 systems), which overflows for coordinates near 1e77 and aborts on a VTK
// assertion. No mesh in any length unit comes near it.
constexpr double kLargestCoordinate = 1e30;

bool UsableCoordinates(const double p[3]) {
  return std::abs(p[0]) <= kLargestCoordinate && std::abs(p[1]) <= kLargestCoordinate &&
         std::abs(p[2]) <= kLargestCoordinate;
}

// The first point with a non-finite or too large coordinate, or -1.
vtkIdType FirstNonFinitePoint(vtkPointSet* data) {
  for (vtkIdType i = 0; i < data->GetNumberOfPoints(); ++i) {
    double p[3];
    data->GetPoint(i, p);
    if (!UsableCoordinates(p))
      return i;
  }
  return -1;
}

// The contact is made on the undeformed bone, points minus Displacement: none of its coordinates
// may be beyond 1e30 or not finite.
Status CheckUndeformedBone(const std::vector<double>& undeformed) {
  for (size_t k = 0; k < undeformed.size(); k += 3)
    if (!UsableCoordinates(&undeformed[k]))
      return Error("the bone's point ", k / 3, " minus its Displacement (the undeformed bone) has ",
                   "a coordinate beyond 1e30 or not finite");
  return Status::Ok();
}

// An array with one tuple per point (or cell) and the expected components, all finite.
Status CheckArray(vtkDataArray* array, const char* name, const char* owner, vtkIdType tuples,
                  int components) {
  if (array->GetNumberOfComponents() != components)
    return Error("the ", owner, " array ", name, " has ", array->GetNumberOfComponents(),
                 " components; it needs ", components);
  if (array->GetNumberOfTuples() != tuples)
    return Error("the ", owner, " array ", name, " has ", array->GetNumberOfTuples(),
                 " values; it needs one per ", owner == std::string("cell") ? "cell" : "point",
                 " (", tuples, ")");
  for (vtkIdType i = 0; i < tuples; ++i)
    for (int c = 0; c < components; ++c)
      if (!std::isfinite(array->GetComponent(i, c)))
        return Error("the ", owner, " array ", name, " has a NaN or infinite value at ", i);
  return Status::Ok();
}

// The largest length of a 3-component Displacement's tuples (0 without one). A double array, the
// usual edit's, is read in place, without a virtual call per tuple; sqrt is monotonic and
// correctly rounded, so the largest square's root is the largest root.
double LargestDisplacement(vtkDataArray* displacement) {
  if (!displacement)
    return 0.0;
  double largest2 = 0.0;
  auto* moves = vtkDoubleArray::FastDownCast(displacement);
  if (moves && moves->GetNumberOfComponents() == 3) {
    const double* d = moves->GetPointer(0);
    for (vtkIdType i = 0; i < moves->GetNumberOfTuples(); ++i, d += 3)
      largest2 = std::max(largest2, d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  } else {
    for (vtkIdType i = 0; i < displacement->GetNumberOfTuples(); ++i) {
      double d[3];
      displacement->GetTuple(i, d);
      largest2 = std::max(largest2, d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    }
  }
  return std::sqrt(largest2);
}

} // namespace

Status ValidateProperties(const Settings& s) {
  if (!(s.youngsModulus > 0.0) || !std::isfinite(s.youngsModulus))
    return Error("YoungsModulus must be a positive number of pascals (got ", s.youngsModulus, ")");
  if (!(s.poissonRatio > -1.0 && s.poissonRatio < 0.5))
    return Error("PoissonRatio must lie in (-1, 0.5) (got ", s.poissonRatio, ")");
  if (!(s.lengthUnit > 0.0) || !std::isfinite(s.lengthUnit))
    return Error("LengthUnit must be a positive number of metres per mesh unit (got ", s.lengthUnit,
                 ")");
  if (!(s.contactDistance >= 0.0) || !std::isfinite(s.contactDistance))
    return Error("ContactDistance must be zero or positive and finite (got ", s.contactDistance,
                 ")");
  if (s.contactModel < 0 || s.contactModel > 3)
    return Error("ContactModel must be 0 (Tied), 1 (Sliding), 2 (ByArray) or 3 (Auto), not ",
                 s.contactModel);
  if (!(s.releaseDistance >= 0.0) || !std::isfinite(s.releaseDistance))
    return Error("ReleaseDistance must be zero or positive and finite (got ", s.releaseDistance,
                 ")");
  if (s.lipSeal != Settings::kLipSealAuto && (!(s.lipSeal >= 0.0) || !std::isfinite(s.lipSeal)))
    return Error("LipSeal must be -1 (Auto), zero or a positive, finite gap in mesh units (got ",
                 s.lipSeal, ")");
  if (s.useGravity) {
    if (!(s.density >= 0.0) || !std::isfinite(s.density))
      return Error("Density must be zero or positive and finite with UseGravity on (got ",
                   s.density, ")");
    for (double g : s.gravity)
      if (!std::isfinite(g))
        return Error("Gravity has a NaN or infinite component");
  }
  if (s.outputMode < 0 || s.outputMode > 1)
    return Error("OutputMode must be 0 (Volume) or 1 (Surface), not ", s.outputMode);
  if (s.backend < 0 || s.backend > 2)
    return Error("Backend must be 0 (Auto), 1 (CPU) or 2 (CUDA), not ", s.backend);
  if (s.method < 0 || s.method > 3)
    return Error(
        "Method must be 0 (Auto), 1 (DenseResponse), 2 (CachedFactor) or 3 (FullReference), not ",
        s.method);
  if (s.elementOrder < 0 || s.elementOrder > 2)
    return Error(
        "ElementOrder must be 0 (Linear), 1 (Quadratic) or 2 (QuadraticNodalPressure), not ",
        s.elementOrder);
  if (s.model < 0 || s.model > 2)
    return Error("Model must be 0 (LinearElastic), 1 (NeoHookean) or 2 (Auto), not ", s.model);
  if (s.largeDeformationSolver < 0 || s.largeDeformationSolver > 1)
    return Error("LargeDeformationSolver must be 0 (Precomputed) or 1 (Newton), not ",
                 s.largeDeformationSolver);
  if (s.iterationLimit < 0)
    return Error("QuasiNewtonIterationLimit must be 0 (no limit) or positive, not ",
                 s.iterationLimit);
  if (s.largeDeformation() && s.elementOrder != 0)
    return Error("Model NeoHookean supports ElementOrder Linear only");
  if (s.largeDeformation() && s.verify)
    return Error("Verify compares with the linear reference solve: it does not apply to Model "
                 "NeoHookean");
  return Status::Ok();
}

Status ValidateTissue(vtkUnstructuredGrid* tissue, const Settings& settings) {
  if (!tissue || tissue->GetNumberOfCells() == 0 || tissue->GetNumberOfPoints() == 0)
    return Error("the Input (soft tissue) is empty");
  const vtkIdType n = tissue->GetNumberOfPoints(), m = tissue->GetNumberOfCells();
  vtkNew<vtkIdList> ids;
  for (vtkIdType c = 0; c < m; ++c) {
    if (tissue->GetCellType(c) != VTK_TETRA)
      return Error("cell ", c, " of the tissue is not a linear tetrahedron (VTK type ",
                   tissue->GetCellType(c),
                   "); apply ParaView's Tetrahedralize filter to the tissue first");
    tissue->GetCellPoints(c, ids);
    if (ids->GetNumberOfIds() != 4)
      return Error("tetrahedron ", c, " has ", ids->GetNumberOfIds(), " point ids, not 4");
    for (vtkIdType k = 0; k < 4; ++k) {
      const vtkIdType id = ids->GetId(k);
      if (id < 0 || id >= n)
        return Error("tetrahedron ", c, " uses point id ", id, ", outside the tissue's ", n,
                     " points");
      for (vtkIdType j = 0; j < k; ++j)
        if (ids->GetId(j) == id)
          return Error("tetrahedron ", c, " uses point ", id, " twice");
    }
  }
  const vtkIdType bad = FirstNonFinitePoint(tissue);
  if (bad >= 0)
    return Error("the tissue's point ", bad,
                 " has a NaN or infinite coordinate (or one beyond 1e30)");
  if (settings.useCellMaterials) {
    for (const char* name : {"YoungsModulus", "PoissonRatio"})
      if (vtkDataArray* a = tissue->GetCellData()->GetArray(name)) {
        const Status s = CheckArray(a, name, "cell", m, 1);
        if (!s)
          return s;
      }
  }
  return Status::Ok();
}

Status ValidateBone(vtkPointSet* bone) {
  std::vector<double> undeformed;
  return ValidateBone(bone, undeformed);
}

Status ValidateBone(vtkPointSet* bone, std::vector<double>& undeformed) {
  if (!bone)
    return Error("no Bone input: connect the operated bone (the output of BezierCut or "
                 "Osteotomy) and the bones that stay put (any bone surface: without a "
                 "Displacement array a bone is fixed)");
  if (bone->GetNumberOfPoints() == 0 || bone->GetNumberOfCells() == 0)
    return Error("the Bone input has no cells to make contact with");
  const vtkIdType n = bone->GetNumberOfPoints();
  bool hasSurfaceCell = false;
  vtkNew<vtkIdList> ids;
  for (vtkIdType c = 0; c < bone->GetNumberOfCells(); ++c) {
    const int type = bone->GetCellType(c);
    if (type == VTK_TRIANGLE || type == VTK_QUAD || type == VTK_POLYGON || type == VTK_PIXEL)
      hasSurfaceCell = true;
    bone->GetCellPoints(c, ids);
    for (vtkIdType k = 0; k < ids->GetNumberOfIds(); ++k)
      if (ids->GetId(k) < 0 || ids->GetId(k) >= n)
        return Error("bone cell ", c, " uses point id ", ids->GetId(k), ", outside the bone's ", n,
                     " points");
    // VTK's closest-point search writes out of bounds on a triangle strip none of whose triangles
    // has a non-zero area (vtkTriangleStrip::EvaluatePosition then indexes its weights with an
    // unset sub-id); strips are refused rather than judged triangle by triangle.
    if (type == VTK_TRIANGLE_STRIP)
      return Error("bone cell ", c,
                   " is a triangle strip, which the contact search does not take; apply "
                   "ParaView's Triangulate filter to the bone first");
  }
  if (!hasSurfaceCell)
    return Error(
        "the Bone input has no surface cells (triangles or polygons) to make contact with");
  Status s = ValidateBoneValues(bone, undeformed); // coordinates and Displacement, as an edit does
  if (!s)
    return s;
  for (const char* name : {"ROIMask", "SegmentId", "Sliding", "Released"})
    if (vtkDataArray* array = bone->GetPointData()->GetArray(name)) {
      s = CheckArray(array, name, "point", n, 1);
      if (!s)
        return s;
    }
  // A flag, not a measure: a float array here is more likely a resampled or interpolated field
  // than a choice of where the tissue was detached.
  if (vtkDataArray* released = bone->GetPointData()->GetArray("Released"))
    if (released->GetDataType() != VTK_UNSIGNED_CHAR)
      return Error("the point array Released is of type ", released->GetDataTypeAsString(),
                   "; it needs uint8 (unsigned char): 1 where the tissue is detached from the "
                   "bone, 0 where it stays tied");
  return Status::Ok();
}

// The usual edit's check in one pass: points and Displacement both double arrays (BezierCut's
// and Osteotomy's outputs), the undeformed points written as they are checked. False when the
// arrays are of another kind or a value is not usable; the caller then checks step by step, which
// names the first problem.
bool UsableBoneValuesInOnePass(vtkPointSet* bone, vtkDataArray* displacement,
                               std::vector<double>& undeformed) {
  const vtkIdType n = bone->GetNumberOfPoints();
  auto* points =
      bone->GetPoints() ? vtkDoubleArray::FastDownCast(bone->GetPoints()->GetData()) : nullptr;
  auto* moves = vtkDoubleArray::FastDownCast(displacement);
  if (!points || !moves || points->GetNumberOfComponents() != 3 ||
      moves->GetNumberOfComponents() != 3 || moves->GetNumberOfTuples() != n ||
      points->GetNumberOfTuples() != n)
    return false;
  undeformed.resize(static_cast<size_t>(3 * n));
  const double* x = points->GetPointer(0);
  const double* u = moves->GetPointer(0);
  double* out = undeformed.data();
  bool usable = true;
  for (vtkIdType k = 0; k < 3 * n; ++k) {
    const double rest = x[k] - u[k];
    out[k] = rest;
    // Not finite fails every comparison; a finite Displacement with usable points and a usable
    // difference is what the step-by-step checks accept.
    usable &= std::abs(x[k]) <= kLargestCoordinate && std::isfinite(u[k]) &&
              std::abs(rest) <= kLargestCoordinate;
  }
  return usable;
}

Status ValidateBoneValues(vtkPointSet* bone, std::vector<double>& undeformed) {
  if (UsableBoneValuesInOnePass(bone, bone->GetPointData()->GetArray("Displacement"), undeformed))
    return Status::Ok();
  const vtkIdType bad = FirstNonFinitePoint(bone);
  if (bad >= 0)
    return Error("the bone's point ", bad,
                 " has a NaN or infinite coordinate (or one beyond 1e30)");
  vtkDataArray* displacement = bone->GetPointData()->GetArray("Displacement");
  if (!displacement)
    return Error("the Bone input needs a 3-component point array named Displacement "
                 "(connect the output of BezierCut or Osteotomy)");
  const Status s = CheckArray(displacement, "Displacement", "point", bone->GetNumberOfPoints(), 3);
  if (!s)
    return s;
  UndeformedPoints(bone, displacement, undeformed);
  return CheckUndeformedBone(undeformed);
}

std::string UnfollowedBoneMotion(const std::vector<char>& tiedMovable,
                                 vtkDataArray* boneDisplacement) {
  for (char movable : tiedMovable)
    if (movable)
      return std::string();
  const double largest = LargestDisplacement(boneDisplacement);
  if (largest == 0.0)
    return std::string();
  std::ostringstream msg;
  msg << "the bone moves (largest Displacement " << largest
      << ") but its ROIMask is 0 at every point where the tissue is tied to it, so the tissue does "
         "not move: check the ROI (ROI Extract) or the bone's ROIMask";
  return msg.str();
}

std::string LooseTissueNote(double tissueLargest, vtkDataArray* boneDisplacement, double tissueSize,
                            double lengthUnit) {
  const double boneLargest = LargestDisplacement(boneDisplacement);
  // A move below the floor (0.03 mm for a head whose bounds span 300 mm) is no move: round-off or
  // a solver's tolerance (a warm-started solve back at zero leaves about 1e-13 mm), far below
  // anything a surgeon plans or sees. Without gravity the bones are the only load, so when none
  // moves beyond the floor the tissue has nothing to swing from and there is nothing to say.
  const double floor = kLooseTissueFloor * tissueSize;
  if (!(boneLargest > floor) || !(tissueLargest > kLooseTissueRatio * boneLargest))
    return std::string();
  const char* unit = lengthUnit == 0.001 ? " mm" : lengthUnit == 1.0 ? " m" : " (mesh units)";
  std::ostringstream msg;
  msg.precision(3);
  msg << "the tissue moves " << tissueLargest << unit << " where no bone moves more than "
      << boneLargest << unit
      << ": is every bone connected? Connect the bones that stay put (the mandible, the cranium) "
         "to the Bone port as well; a connection without a Displacement array is a fixed bone. If "
         "every bone is connected, the tissue is held loosely: Sliding, Released and lifted-off "
         "tissue follows the bone only along its normal or not at all";
  return msg.str();
}

} // namespace fem_filter
} // namespace faceplan
