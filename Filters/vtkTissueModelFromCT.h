// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class vtkTissueModelFromCT
 * @brief From a CT volume (Hounsfield units) to a planning model: tetrahedral soft tissue, bone
 * surface and skin surface.
 *
 * Input: vtkImageData with the CT in Hounsfield units as its point scalars (or the array chosen
 * with SetInputArrayToProcess); origin, spacing and direction matrix are honoured. The voxels are
 * labelled air, soft tissue or bone (thresholds, largest component, cavity and hole filling,
 * optionally mandible), the labels meshed with CGAL Mesh_3 and optimised.
 * Output port 0: the soft tissue (vtkUnstructuredGrid, VTK_TETRA only, cell data `Label`).
 * Port 1: the bone surface, the tissue's own facets that face bone (triangles, cell data `Label`:
 * 2 bone, 3 mandible; point data `TissuePointId`), so its points coincide with tissue points.
 * Port 2: the skin surface (triangles, `TissuePointId`). All in the image's frame and unit.
 * Field data of port 0: `EstimatedCells` (of the first attempt), `FirstAttemptCells` and
 * `MeshedCells` (all labels), `MeshingAttempts`, `WorstDihedralAngle`, `SmallestMeanRatio`,
 * `LargestBoundaryDistance`.
 * Errors (not an image, an empty, flat or non-finite image, spacing not positive, a direction
 * matrix that is not orthonormal, no voxel above BoneThreshold, empty tissue, thresholds in the
 * wrong order, a property out of range, estimated cells over MaximumCells) give vtkErrorMacro and
 * empty outputs.
 */
#ifndef vtkTissueModelFromCT_h
#define vtkTissueModelFromCT_h

#include "FacePlanFiltersModule.h"
#include "vtkUnstructuredGridAlgorithm.h"

class FACEPLANFILTERS_EXPORT vtkTissueModelFromCT : public vtkUnstructuredGridAlgorithm {
public:
  static vtkTissueModelFromCT* New();
  vtkTypeMacro(vtkTissueModelFromCT, vtkUnstructuredGridAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  enum Optimisers { NONE = 0, ODT = 1, LLOYD = 2 };

  ///@{
  /// Hounsfield thresholds: at or above SkinThreshold is body, at or above BoneThreshold is bone.
  vtkSetMacro(BoneThreshold, double);
  vtkGetMacro(BoneThreshold, double);
  vtkSetMacro(SkinThreshold, double);
  vtkGetMacro(SkinThreshold, double);
  ///@}

  ///@{
  /// Target tetrahedron edge length and largest boundary-to-interface distance, image units.
  vtkSetMacro(CellSize, double);
  vtkGetMacro(CellSize, double);
  vtkSetMacro(SurfaceDistance, double);
  vtkGetMacro(SurfaceDistance, double);
  ///@}

  ///@{
  /// Smallest dihedral angle (degrees) the optimisation aims for; cells below it give a warning.
  vtkSetMacro(QualityBound, double);
  vtkGetMacro(QualityBound, double);
  ///@}

  ///@{
  /// Keep only the largest connected body; bone pieces below MinimumBoneComponentVolume dropped.
  vtkSetMacro(KeepLargestComponent, bool);
  vtkGetMacro(KeepLargestComponent, bool);
  vtkBooleanMacro(KeepLargestComponent, bool);
  vtkSetMacro(MinimumBoneComponentVolume, double);
  vtkGetMacro(MinimumBoneComponentVolume, double);
  ///@}

  ///@{
  /// Fill enclosed pockets of the bone up to MaximumBoneHoleVolume (image units cubed).
  vtkSetMacro(FillBoneHoles, bool);
  vtkGetMacro(FillBoneHoles, bool);
  vtkBooleanMacro(FillBoneHoles, bool);
  vtkSetMacro(MaximumBoneHoleVolume, double);
  vtkGetMacro(MaximumBoneHoleVolume, double);
  ///@}

  ///@{
  /// Label the mandible (3) apart from the rest of the bone (2).
  vtkSetMacro(SeparateMandible, bool);
  vtkGetMacro(SeparateMandible, bool);
  vtkBooleanMacro(SeparateMandible, bool);
  ///@}

  ///@{
  /// ODT, Lloyd or no smoothing before perturbation and exudation (other values are an error).
  vtkSetMacro(Optimiser, int);
  vtkGetMacro(Optimiser, int);
  ///@}

  ///@{
  /// Bone is meshed this much coarser than CellSize (its cells are dropped).
  vtkSetMacro(BoneCellSizeFactor, double);
  vtkGetMacro(BoneCellSizeFactor, double);
  ///@}

  ///@{
  /// Refuse runs whose estimated tetrahedron count is larger.
  vtkSetMacro(MaximumCells, vtkIdType);
  vtkGetMacro(MaximumCells, vtkIdType);
  ///@}

  ///@{
  /// Random seed of the mesher (not negative): equal seeds give equal meshes.
  vtkSetMacro(Seed, int);
  vtkGetMacro(Seed, int);
  ///@}

protected:
  vtkTissueModelFromCT();
  ~vtkTissueModelFromCT() override;
  int FillInputPortInformation(int port, vtkInformation* info) override;
  int FillOutputPortInformation(int port, vtkInformation* info) override;
  int RequestUpdateExtent(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  double BoneThreshold = 200.0;
  double SkinThreshold = -400.0;
  double CellSize = 5.0;
  double SurfaceDistance = 2.0;
  double QualityBound = 5.0;
  bool KeepLargestComponent = true;
  double MinimumBoneComponentVolume = 50.0;
  bool FillBoneHoles = true;
  double MaximumBoneHoleVolume = 2000.0;
  bool SeparateMandible = false;
  int Optimiser = LLOYD;
  double BoneCellSizeFactor = 2.0;
  vtkIdType MaximumCells = 1000000;
  int Seed = 0;

private:
  vtkTissueModelFromCT(const vtkTissueModelFromCT&) = delete;
  void operator=(const vtkTissueModelFromCT&) = delete;
};

#endif
