// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class vtkBezierCut
 * @brief Cuts (or fills) a bone surface with a translational Bezier surface.
 *
 * Input: the output of vtkROIExtract (a vtkPointSet of surface cells with uint8 point arrays
 * `ROIMask` and `ROIBoundary`). `CurveU` and `CurveV` are composite cubic Bezier curves (3k+1 and
 * 3m+1 control points, k, m >= 1) sharing their first point P0; the operative surface is
 * S(u,v) = U(u) + V(v) - P0 with normal dS/du x dS/dv (negated by `FlipNormal`).
 * `Operation` Cut (0): ROI points (not ROIBoundary) on the side the normal points to, whose closest
 * surface point is an orthogonal foot inside the patch, move onto S. Fill (1): the same for the
 * other side. See Core/BezierCut.h for the exact rules and guarantees (no flipped, degenerate or
 * newly intersecting triangles; intermediary surfaces when direct projection would fold).
 *
 * Output port 0: the input's cells and point order with the new coordinates (double precision), a
 * point vector array `Displacement` (exactly zero where unmoved), the input's arrays (ROIMask,
 * ROIBoundary, ...) passed through, and field data `NumberOfMovedPoints`, `IntermediarySteps`.
 * Output port 1: the operative surface as triangles (point arrays `Normals`, `UV`).
 * Errors (ill-defined control points, missing ROI arrays, a cut that cannot be mapped without
 * folding) are reported with vtkErrorMacro and give empty outputs. The input is never modified.
 */
#ifndef vtkBezierCut_h
#define vtkBezierCut_h

#include "FacePlanFiltersModule.h"
#include "vtkPointSetAlgorithm.h"

#include <string>
#include <vector>

class FACEPLANFILTERS_EXPORT vtkBezierCut : public vtkPointSetAlgorithm {
public:
  static vtkBezierCut* New();
  vtkTypeMacro(vtkBezierCut, vtkPointSetAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  enum OperationType { CUT = 0, FILL = 1 };

  ///@{
  /// Control points of CurveU (3k+1 points). Until a control point of either curve is set to a new
  /// value, the filter places both curves itself: a flat patch over the bounding box of the input's
  /// ROI (ROIMask != 0; the whole input when it selects nothing), normal to the box's shortest axis
  /// and three quarters of the way along it, so that a new cut meets the bone. The Get methods
  /// report the curves of the last run.
  void SetNumberOfCurveUPoints(vtkIdType n);
  vtkIdType GetNumberOfCurveUPoints() const {
    return static_cast<vtkIdType>(this->CurveU.size() / 3);
  }
  void SetCurveUPoint(vtkIdType i, double x, double y, double z);
  void GetCurveUPoint(vtkIdType i, double p[3]) const;
  ///@}

  ///@{
  /// Control points of CurveV (3m+1 points); point 0 must equal CurveU's point 0.
  void SetNumberOfCurveVPoints(vtkIdType n);
  vtkIdType GetNumberOfCurveVPoints() const {
    return static_cast<vtkIdType>(this->CurveV.size() / 3);
  }
  void SetCurveVPoint(vtkIdType i, double x, double y, double z);
  void GetCurveVPoint(vtkIdType i, double p[3]) const;
  ///@}

  ///@{
  /// CUT (0) or FILL (1). Other values are kept as set and rejected with an error by RequestData
  /// (pvpython bypasses the GUI's domains; a silent clamp would run another operation).
  vtkSetMacro(Operation, int);
  vtkGetMacro(Operation, int);
  ///@}

  ///@{
  /// Negate the surface normal (choose which side is cut).
  vtkSetMacro(FlipNormal, vtkTypeBool);
  vtkGetMacro(FlipNormal, vtkTypeBool);
  vtkBooleanMacro(FlipNormal, vtkTypeBool);
  ///@}

  ///@{
  /// Tessellation intervals per Bezier segment of the displayed surface (output port 1), 1 to 256;
  /// other values are rejected with an error by RequestData.
  vtkSetMacro(SurfaceResolution, int);
  vtkGetMacro(SurfaceResolution, int);
  ///@}

  /// The message of the last error ("" after a successful run).
  const char* GetLastErrorMessage() const { return this->LastError.c_str(); }

  /// How many times the input was validated and converted. What depends only on the input (the
  /// converted surface, ROI flags, edge neighbours, fan triangles, default curves) is kept while
  /// the input is unchanged, so that an edit of the control points redoes only the cut.
  unsigned long GetInputConversionCount() const;

  ///@{
  /// The curves the filter places itself over the current input (see SetCurveUPoint), 4 control
  /// points each, for the GUI's initial widget positions; all zero while the input is missing or
  /// unusable. They read the input's data, bringing the upstream pipeline up to date first.
  double* GetDefaultCurveU() VTK_SIZEHINT(12);
  double* GetDefaultCurveV() VTK_SIZEHINT(12);
  ///@}

protected:
  vtkBezierCut();
  ~vtkBezierCut() override;
  int FillOutputPortInformation(int port, vtkInformation* info) override;
  int RequestDataObject(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  std::vector<double> CurveU, CurveV;
  int Operation = CUT;
  vtkTypeBool FlipNormal = false;
  int SurfaceResolution = 16;
  std::string LastError;
  bool CurvesPlaced = false; // by the user; until then RequestData places them over the ROI
  // The shared first point P0 as the curves were last received and as last used: a GUI drag moves
  // one curve's first handle only, and P0 follows the one that moved (LinkFirstPoints).
  bool HaveFirstPoints = false;
  double LastFirstU[3] = {0, 0, 0}, LastFirstV[3] = {0, 0, 0}, SharedFirst[3] = {0, 0, 0};
  // The curves to cut with: `u` and `v` start at one P0. When their first points differ, the one
  // that changed since the last update moves P0 (the other follows); with neither changed the
  // last P0 stays. False (curves as given) when both changed to different points or there is no
  // earlier update to tell which moved: Core then names the unshared points.
  bool LinkFirstPoints(std::vector<double>& u, std::vector<double>& v);
  // A unit square in z = 0, Plugin/BezierCut.xml's default_values digit for digit.
  static constexpr double InitialCurveU[12] = {-0.5,      -0.5, 0, -0.1666667, -0.5, 0,
                                               0.1666667, -0.5, 0, 0.5,        -0.5, 0};
  static constexpr double InitialCurveV[12] = {-0.5, -0.5,      0, -0.5, -0.1666667, 0,
                                               -0.5, 0.1666667, 0, -0.5, 0.5,        0};
  double DefaultCurveU[12] = {};
  double DefaultCurveV[12] = {};

private:
  vtkBezierCut(const vtkBezierCut&) = delete;
  void operator=(const vtkBezierCut&) = delete;
  void Fail(const std::string& message, vtkDataObject* output, vtkDataObject* surface);
  void UpdateDefaultCurves();
  class vtkInternals;
  vtkInternals* Internals;
  // The serial filter on a whole input; false (after logging the error) when it failed.
  bool Cut(vtkPointSet* input, vtkPointSet* output, vtkPolyData* surface);
};

#endif
