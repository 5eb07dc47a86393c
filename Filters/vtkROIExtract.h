// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class vtkROIExtract
 * @brief Marks a region of interest on a surface: point arrays ROIMask and ROIBoundary.
 *
 * Input: any vtkPointSet (typically a triangulated bone surface). The ROI is the list of point ids
 * `PointIds` when it is not empty, otherwise the points where the implicit function `Region` is
 * negative (inside a sphere or box; behind a plane, i.e. against its normal). `InsideOut` takes the
 * complement. Output: a shallow copy of the input (same points, cells and arrays) plus uint8 point
 * arrays `ROIMask` (1 for ROI points) and `ROIBoundary` (1 for ROI points sharing a cell edge with
 * a non-ROI point; these never move in vtkBezierCut). The input is never modified.
 * Errors (no ROI given, id out of range, ...) are reported with vtkErrorMacro and give an empty
 * output.
 */
#ifndef vtkROIExtract_h
#define vtkROIExtract_h

#include "FacePlanFiltersModule.h"
#include "vtkPointSetAlgorithm.h"

#include <vector>

class vtkImplicitFunction;

class FACEPLANFILTERS_EXPORT vtkROIExtract : public vtkPointSetAlgorithm {
public:
  static vtkROIExtract* New();
  vtkTypeMacro(vtkROIExtract, vtkPointSetAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /// Implicit function whose negative side is the ROI (used when PointIds is empty).
  virtual void SetRegion(vtkImplicitFunction*);
  vtkGetObjectMacro(Region, vtkImplicitFunction);
  ///@}

  ///@{
  /// Explicit list of ROI point ids; takes precedence over Region when not empty.
  void SetNumberOfPointIds(vtkIdType n);
  void SetPointId(vtkIdType index, vtkIdType pointId);
  void AddPointId(vtkIdType pointId);
  void RemoveAllPointIds();
  vtkIdType GetNumberOfPointIds() const { return static_cast<vtkIdType>(this->PointIds.size()); }
  vtkIdType GetPointId(vtkIdType index) const;
  ///@}

  ///@{
  /// Take the complement of the selection.
  vtkSetMacro(InsideOut, vtkTypeBool);
  vtkGetMacro(InsideOut, vtkTypeBool);
  vtkBooleanMacro(InsideOut, vtkTypeBool);
  ///@}

  /// Where a new sphere Region starts, as centre x, y, z and radius: on the input where an
  /// operation would be planned (Core's DefaultROISphere: the bone's most anterior point in the
  /// face frame, a fifth of its extent), not over the whole bone; radius -1 without usable input.
  /// Brings the upstream pipeline up to date, as ParaView's domains do for data information.
  /// vtkROIExtractInitializationHelper places a new proxy's sphere here (GUI and pvpython).
  double* GetDefaultSphere() VTK_SIZEHINT(4);

  /// Includes the Region's modification time.
  vtkMTimeType GetMTime() override;

protected:
  vtkROIExtract();
  ~vtkROIExtract() override;
  int RequestDataObject(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  vtkImplicitFunction* Region = nullptr;
  std::vector<vtkIdType> PointIds;
  vtkTypeBool InsideOut = false;
  double DefaultSphere[4] = {0.0, 0.0, 0.0, -1.0};

private:
  vtkROIExtract(const vtkROIExtract&) = delete;
  void operator=(const vtkROIExtract&) = delete;
  // The serial filter on a whole input; false (after logging the error) when it failed.
  bool Extract(vtkPointSet* input, vtkPointSet* output);
};

#endif
