// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class vtkOsteotomy
 * @brief Splits a bone surface along one or two cut planes and moves the segment rigidly.
 *
 * Input: a bone surface of triangles (polygons and strips are triangulated; lines, vertices and
 * volume cells are an error). The segment is the part on the positive side of CutPlane1 (and of
 * CutPlane2 when UseSecondPlane is on: the slab or wedge between them); InsideOut swaps the sides.
 * Both sides are clipped and capped with vtkClipClosedSurface, so every piece is closed (with two
 * planes the side that is not convex is clipped as two closed pieces that touch on CutPlane1). The
 * segment moves by x -> Rz Ry Rx (x - pivot) + pivot + Translation, angles from Rotation (degrees),
 * pivot = the segment's area-weighted surface centroid (PivotMode 0) or Pivot (PivotMode 1).
 *
 * Output port 0: the split bone (triangles, double points) with point arrays `Displacement`
 * (cumulative from the undeformed bone when the input already carries one), `ROIMask` (uint8,
 * 1 on the segment, OR-ed with the input's), `SegmentId` (int: 0 unmoved, this segment
 * 1 + the input's largest id), and field data `SegmentTransform` (12 doubles per segment id,
 * row-major [R | t] from the undeformed bone; NaN where a segment's motion is not rigid) and
 * `SegmentNote` (one string per segment, empty when rigid, else why not). The input's other
 * one-component point arrays (labels, flags such as CondensedFEMDeform's Released and Sliding) are
 * passed on, interpolated at the points the cut adds; vectors and normals are not, since the move
 * would invalidate them.
 * Operation picks where the cut goes: CUSTOM uses CutPlane1/CutPlane2/UseSecondPlane/InsideOut;
 * LE_FORT_I, BSSO and GENIOPLASTY place the planes from the bone's geometry in the frame given by
 * AnteriorDirection and SuperiorDirection (Core/Osteotomy/OperationPresets.h says how) and mark the
 * operation's standard approach on the output: point arrays `Released` (uint8, 1 = degloved bone)
 * and `Sliding` (uint8, 1 = the teeth), replacing the input's, and field data `Operation` (the
 * preset's name). The proxy (Plugin/Osteotomy.xml) starts with LE_FORT_I, so a new filter cuts
 * where the operation does in the GUI and in pvpython alike.
 * Output port 1: the cut plane(s) clipped to the input's bounds (cell array `CutPlane`: 1 or 2).
 * Errors (vtkErrorMacro, empty outputs): input not a triangle surface, NaN coordinates,
 * non-finite planes or move, a cut with no vertex on one of its sides. The input is not modified.
 * The maths and decisions live in Core/Osteotomy.
 */
#ifndef vtkOsteotomy_h
#define vtkOsteotomy_h

#include "FacePlanFiltersModule.h"
#include "vtkPolyDataAlgorithm.h"

#include <string>

class vtkImplicitFunction;

class FACEPLANFILTERS_EXPORT vtkOsteotomy : public vtkPolyDataAlgorithm {
public:
  static vtkOsteotomy* New();
  vtkTypeMacro(vtkOsteotomy, vtkPolyDataAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  enum PivotModeType { SEGMENT_CENTROID = 0, CUSTOM_PIVOT = 1 };
  enum OperationType { CUSTOM = 0, LE_FORT_I = 1, BSSO = 2, GENIOPLASTY = 3 };

  ///@{
  /// The operation: CUSTOM (the cut planes as set) or a preset that places them from the bone
  /// (Core/Osteotomy/OperationPresets.h). Other values are kept and rejected by RequestData.
  vtkSetMacro(Operation, int);
  vtkGetMacro(Operation, int);
  ///@}

  ///@{
  /// The bone's anatomical frame for the presets: out of the face, and up (the bundled face: -x
  /// and +z).
  vtkSetVector3Macro(AnteriorDirection, double);
  vtkGetVector3Macro(AnteriorDirection, double);
  vtkSetVector3Macro(SuperiorDirection, double);
  vtkGetVector3Macro(SuperiorDirection, double);
  ///@}

  ///@{
  /// The cut planes (vtkPlane or a subclass such as ParaView's vtkPVPlane).
  void SetCutPlane1(vtkImplicitFunction* plane);
  vtkGetObjectMacro(CutPlane1, vtkImplicitFunction);
  void SetCutPlane2(vtkImplicitFunction* plane);
  vtkGetObjectMacro(CutPlane2, vtkImplicitFunction);
  ///@}

  ///@{
  /// Bound the segment by CutPlane2 as well (slab or wedge).
  vtkSetMacro(UseSecondPlane, vtkTypeBool);
  vtkGetMacro(UseSecondPlane, vtkTypeBool);
  vtkBooleanMacro(UseSecondPlane, vtkTypeBool);
  ///@}

  ///@{
  /// Move the other side instead (Operation CUSTOM only: a preset moves its segment).
  vtkSetMacro(InsideOut, vtkTypeBool);
  vtkGetMacro(InsideOut, vtkTypeBool);
  vtkBooleanMacro(InsideOut, vtkTypeBool);
  ///@}

  ///@{
  /// The move: translation (length unit of the bone), rotation angles in degrees about X, Y, Z
  /// applied in that order, and the pivot used with PivotMode CUSTOM_PIVOT.
  vtkSetVector3Macro(Translation, double);
  vtkGetVector3Macro(Translation, double);
  vtkSetVector3Macro(Rotation, double);
  vtkGetVector3Macro(Rotation, double);
  vtkSetVector3Macro(Pivot, double);
  vtkGetVector3Macro(Pivot, double);
  // Other values are kept as set and rejected with an error by RequestData (pvpython bypasses the
  // GUI's domain; a silent clamp would use another pivot).
  vtkSetMacro(PivotMode, int);
  vtkGetMacro(PivotMode, int);
  ///@}

  /// The pivot the last run used (the centroid in SEGMENT_CENTROID mode).
  vtkGetVector3Macro(UsedPivot, double);

  /// How many times the bone was validated, split and converted. The split bone is kept while the
  /// input, the planes and the sides stay the same, so that an edit of the move (Translation,
  /// Rotation, pivot) redoes only the move and the output.
  unsigned long GetSplitCount() const;

  /// The message of the last error ("" after a successful run).
  const char* GetLastErrorMessage() const { return this->LastError.c_str(); }

  vtkMTimeType GetMTime() override;

protected:
  vtkOsteotomy();
  ~vtkOsteotomy() override;
  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  vtkImplicitFunction* CutPlane1 = nullptr;
  vtkImplicitFunction* CutPlane2 = nullptr;
  vtkTypeBool UseSecondPlane = false;
  vtkTypeBool InsideOut = false;
  int Operation = CUSTOM;
  double AnteriorDirection[3] = {-1.0, 0.0, 0.0};
  double SuperiorDirection[3] = {0.0, 0.0, 1.0};
  double Translation[3] = {0.0, 0.0, 0.0};
  double Rotation[3] = {0.0, 0.0, 0.0};
  double Pivot[3] = {0.0, 0.0, 0.0};
  int PivotMode = SEGMENT_CENTROID;
  double UsedPivot[3] = {0.0, 0.0, 0.0};
  std::string LastError;

  class vtkInternals;
  vtkInternals* Internals;

private:
  vtkOsteotomy(const vtkOsteotomy&) = delete;
  void operator=(const vtkOsteotomy&) = delete;
  void Fail(const std::string& message, vtkDataObject* output, vtkDataObject* planesOutput);
  // The serial filter on a whole input (errors through Fail).
  void Cut(vtkDataSet* data, vtkPolyData* output, vtkPolyData* planesOutput);
};

#endif
