// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class vtkFacialLandmarks
 * @brief Soft-tissue and bony facial landmarks, their movement in a reference frame and the
 * soft:hard ratios against published clinical bands.
 *
 * Input 0: the soft tissue (CondensedFEMDeform's output, volume or surface, or any data set with a
 * surface) with an optional 3-component point array `Displacement` (absent: nothing moved). The
 * skin is its boundary surface, taken back to its pre-operative position by the displacement.
 * Input 1 (optional): the bone (Osteotomy's output, or the skeleton of all bones), with an optional
 * `Displacement` (absent: the bone stays put) and optional field data `Operation`.
 *
 * The landmarks are found on the pre-operative surfaces by their standard definitions
 * (Core/Landmarks/FacialLandmarks.h) on sections cut with vtkCutter: the midsagittal plane for the
 * profile, horizontal planes for the cheilions and the alar bases. Overrides replace a landmark by
 * a point the user gives (snapped to the surface with vtkCellLocator; an error when farther from it
 * than 2 % of the surface's bounding diagonal). Each landmark's movement is the displacement field
 * interpolated at it (the cell found by vtkCellLocator).
 *
 * The frame: ReferenceFrame MODEL_AXES uses the midsagittal plane (MidsagittalOrigin,
 * MidsagittalNormal) and AnteriorDirection/SuperiorDirection projected into it;
 * FRANKFORT_HORIZONTAL uses FrankfortPoints (right porion, left porion, orbitale) for the
 * horizontal plane and the midsagittal plane through the porions' midpoint.
 *
 * Output 0: a vtkTable, one row per landmark (Core/Landmarks/LandmarkTable.h): Landmark, Kind,
 * Found, Note, Pre (3), Post (3), Horizontal and Vertical movement (+ anterior, + up), PairedBone,
 * BoneHorizontal, BoneVertical, Ratio, Band, BandLow, BandHigh, Source, Check.
 * Output 1: the found landmarks as vertices at their post-operative positions, with point arrays
 * Landmark (name), Kind and Displacement.
 * Errors (vtkErrorMacro, empty outputs): no tissue surface, NaN coordinates or displacements, a
 * degenerate frame, an unknown override name or an override outside the mesh (PlacedLandmark's
 * too, or PlacedLandmark out of range). Landmarks that cannot
 * be found are rows with Found 0 and a Note saying why, and a warning naming them.
 */
#ifndef vtkFacialLandmarks_h
#define vtkFacialLandmarks_h

#include "FacePlanFiltersModule.h"
#include "vtkAlgorithm.h"

#include <string>
#include <vector>

class FACEPLANFILTERS_EXPORT vtkFacialLandmarks : public vtkAlgorithm {
public:
  static vtkFacialLandmarks* New();
  vtkTypeMacro(vtkFacialLandmarks, vtkAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  enum ReferenceFrameType { MODEL_AXES = 0, FRANKFORT_HORIZONTAL = 1 };
  enum OperationType { FROM_BONE = 0, LE_FORT_I = 1, BSSO = 2, GENIOPLASTY = 3, NONE = 4 };

  vtkSetVector3Macro(MidsagittalOrigin, double);
  vtkGetVector3Macro(MidsagittalOrigin, double);
  vtkSetVector3Macro(MidsagittalNormal, double);
  vtkGetVector3Macro(MidsagittalNormal, double);
  vtkSetVector3Macro(AnteriorDirection, double);
  vtkGetVector3Macro(AnteriorDirection, double);
  vtkSetVector3Macro(SuperiorDirection, double);
  vtkGetVector3Macro(SuperiorDirection, double);
  vtkSetMacro(ReferenceFrame, int);
  vtkGetMacro(ReferenceFrame, int);
  /// The Frankfort points: 0 right porion, 1 left porion, 2 orbitale.
  void SetFrankfortPoint(int index, double x, double y, double z);
  vtkGetVectorMacro(FrankfortPoints, double, 9);
  /// Which operation's bands to use: FROM_BONE reads the bone's field data Operation.
  vtkSetMacro(Operation, int);
  vtkGetMacro(Operation, int);

  ///@{
  /// Overrides, each "Name x y z" (a landmark name of ARCHITECTURE.md and its pre-operative
  /// position).
  void AddOverride(const char* entry);
  void RemoveAllOverrides();
  ///@}

  ///@{
  /// One landmark placed by a point handle in the GUI: PlacedLandmark (a Landmark index, 0
  /// Pronasale ... 18 Menton; -1, the default, places none) at PlacedLandmarkPosition (its
  /// pre-operative position). Applied as one more override, after Overrides, so it wins for its
  /// landmark.
  vtkSetMacro(PlacedLandmark, int);
  vtkGetMacro(PlacedLandmark, int);
  vtkSetVector3Macro(PlacedLandmarkPosition, double);
  vtkGetVector3Macro(PlacedLandmarkPosition, double);
  ///@}

  /// The bone input (optional).
  void SetBoneConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(1, output); }

  const char* GetLastErrorMessage() const { return this->LastError.c_str(); }

  vtkTypeBool ProcessRequest(vtkInformation*, vtkInformationVector**,
                             vtkInformationVector*) override;

protected:
  vtkFacialLandmarks();
  ~vtkFacialLandmarks() override = default;
  int FillInputPortInformation(int port, vtkInformation* info) override;
  int FillOutputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*);

  double MidsagittalOrigin[3] = {0.0, 0.0, 0.0};
  double MidsagittalNormal[3] = {0.0, 1.0, 0.0};
  double AnteriorDirection[3] = {-1.0, 0.0, 0.0};
  double SuperiorDirection[3] = {0.0, 0.0, 1.0};
  int ReferenceFrame = MODEL_AXES;
  double FrankfortPoints[9] = {};
  int Operation = FROM_BONE;
  std::vector<std::string> Overrides;
  int PlacedLandmark = -1;
  double PlacedLandmarkPosition[3] = {0.0, 0.0, 0.0};
  std::string LastError;

private:
  vtkFacialLandmarks(const vtkFacialLandmarks&) = delete;
  void operator=(const vtkFacialLandmarks&) = delete;
};

#endif
