// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class vtkCondensedFEMDeform
 * @brief Soft-tissue deformation by linear static FEM with interior condensation (FacePlanCore).
 *
 * Input port 0 ("Input"): the soft tissue, a vtkUnstructuredGrid of tetrahedra (any other cell
 * type is an error that suggests ParaView's Tetrahedralize filter).
 * Input port 1 ("Bone"): one or more surfaces, each the operated bone or a fixed one (a connection
 * without the point array `Displacement` is bone that stays put) (several connections are merged:
 * their SegmentIds renumbered, their SegmentTransforms concatenated) with a point vector array
 * `Displacement` (the output of vtkBezierCut or Osteotomy) and optionally `ROIMask`, `SegmentId`
 * (int, 0 = not moved rigidly), `Sliding` (uint8, for ContactModel ByArray), `Released` (uint8: 1
 * where the surgeon detached the tissue; tied nodes whose nearest bone point is flagged become
 * free) and field data `SegmentTransform` (12 doubles [R|t] row-major per segment; a NaN transform
 * marks a segment as not rigid). When the bone carries SegmentId and SegmentTransform and its
 * Displacement follows them, the rigid-segment path (Method field data `RigidSegments`) is used;
 * otherwise a warning says why not. Contact: tissue boundary nodes within ContactDistance of the
 * undeformed bone (bone points minus Displacement) are tied to it and take the bone's Displacement
 * interpolated at the closest point; tied nodes where the bone's ROIMask is 0 stay fixed (every
 * tied node may move without ROIMask).
 *
 * Output port 0: the deformed tissue (Surface mode, the default: the tissue's boundary triangles
 * only, and interior displacements are never computed; Volume mode: every tetrahedron) with point
 * array `Displacement` and field data `RelativeResidual`, `SolveTimeMs`, `PrecomputeTimeMs`,
 * `Method`, `Backend` (and `VerifyMaxRelativeError` with Verify on), `ConditionEstimate`,
 * `ElementOrder`, `LargestStrain`, `InvertedCells`, `Model` (the model that ran) and `ModelNote`
 * (why); when the neo-Hookean model ran also `LargeDeformationSolver` (`SolverNote` when it fell
 * back to Newton), `SmallestVolumeRatio`, with Newton `LoadSteps` and `NewtonIterations`, with
 * Precomputed `QuasiNewtonIterations`, `FactorSolves`, `Refactorizations` (of them
 * `PartialRefactorizations`: those that reused the rest factor's supernodes) and `WarmStarted`, and
 * with LiftOff `LiftedNodes`. Precompute and solve warnings (slivers, strain above 10%, cells
 * inverted by the displacement, single-precision fallback, a tissue moving far beyond every bone)
 * are reported with vtkWarningMacro, once per state (an edit of the same situation does not repeat
 * them); released nodes are information (field data `ReleasedNodes`, vtkLog at INFO). Output port
 * 1: a vtkTable of stage timings (columns `Stage`, `TimeMs` (this update's; 0 for a reused stage),
 * `Reused`, `Backend`, `CachedTimeMs` (what a reused stage took when it was computed)).
 *
 * The precompute (assembly, ordering, factorization, condensation) runs on a worker thread and is
 * cached: when only the bone's Displacement values change (a new cut on the same bone, ROI and
 * tissue) the filter re-solves without any new factorization and the table marks those stages as
 * reused. The inputs are never modified.
 */
#ifndef vtkCondensedFEMDeform_h
#define vtkCondensedFEMDeform_h

#include "FacePlanFiltersModule.h"
#include "vtkUnstructuredGridAlgorithm.h"

#include "vtkTimeStamp.h"

#include <algorithm>
#include <memory>
#include <string>

class vtkPointSet;
class vtkTable;

namespace faceplan {
namespace fem_filter {
struct Settings;
}
} // namespace faceplan

class FACEPLANFILTERS_EXPORT vtkCondensedFEMDeform : public vtkUnstructuredGridAlgorithm {
public:
  static vtkCondensedFEMDeform* New();
  vtkTypeMacro(vtkCondensedFEMDeform, vtkUnstructuredGridAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  // The values of Core's SolveMethod and ElementOrder. Out-of-range values are kept as set and
  // rejected with an error by RequestData (pvpython bypasses the GUI's domains).
  enum OutputModes { VOLUME = 0, SURFACE = 1 };
  enum Backends { BACKEND_AUTO = 0, BACKEND_CPU = 1, BACKEND_CUDA = 2 };
  enum Methods {
    METHOD_AUTO = 0,
    METHOD_DENSE_RESPONSE = 1,
    METHOD_CACHED_FACTOR = 2,
    METHOD_FULL_REFERENCE = 3
  };
  enum ContactModels {
    CONTACT_TIED = 0,
    CONTACT_SLIDING = 1,
    CONTACT_BY_ARRAY = 2,
    CONTACT_AUTO = 3
  };
  static constexpr double LIP_SEAL_AUTO = -1.0; // LipSeal: decided by the bone (see LipSeal)
  enum ElementOrders { LINEAR_ELEMENTS = 0, QUADRATIC_ELEMENTS = 1, QUADRATIC_NODAL_PRESSURE = 2 };
  enum Models { LINEAR_ELASTIC = 0, NEO_HOOKEAN = 1, AUTO_MODEL = 2 };
  enum LargeDeformationSolvers { PRECOMPUTED = 0, NEWTON = 1 };

  /// Connects the bone surface (port 1).
  void SetBoneConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(1, output); }
  /// Adds one more bone surface to port 1 (several are merged, see the class description).
  void AddBoneConnection(vtkAlgorithmOutput* output) { this->AddInputConnection(1, output); }
  /// Removes every connection of port 1 only (the proxy's clean command for the Bone input).
  void RemoveAllBoneConnections() { this->RemoveAllInputConnections(1); }

  ///@{
  /// Young's modulus in Pa (default 15 kPa, facial soft tissue) and Poisson ratio (default 0.45).
  vtkSetMacro(YoungsModulus, double);
  vtkGetMacro(YoungsModulus, double);
  vtkSetMacro(PoissonRatio, double);
  vtkGetMacro(PoissonRatio, double);
  ///@}

  ///@{
  /// Use the input's cell arrays `YoungsModulus` / `PoissonRatio` (several tissues) where present.
  vtkSetMacro(UseCellMaterials, bool);
  vtkGetMacro(UseCellMaterials, bool);
  ///@}

  ///@{
  /// Metres per mesh length unit (0.001 for millimetres): converts E, density and gravity.
  vtkSetMacro(LengthUnit, double);
  vtkGetMacro(LengthUnit, double);
  ///@}

  ///@{
  /// Largest distance (mesh units) between a tissue boundary node and the bone for a tie.
  vtkSetMacro(ContactDistance, double);
  vtkGetMacro(ContactDistance, double);
  ///@}

  ///@{
  /// Optional gravity load: density in kg/m^3, gravity in m/s^2. Off by default.
  vtkSetMacro(UseGravity, bool);
  vtkGetMacro(UseGravity, bool);
  vtkSetMacro(Density, double);
  vtkGetMacro(Density, double);
  vtkSetVector3Macro(Gravity, double);
  vtkGetVector3Macro(Gravity, double);
  ///@}

  ///@{
  /// Output (VOLUME or SURFACE), Backend (Auto, CPU, CUDA), Method (Auto, DenseResponse,
  /// CachedFactor, FullReference): see Plugin/CondensedFEMDeform.xml.
  vtkSetMacro(OutputMode, int);
  vtkGetMacro(OutputMode, int);
  vtkSetMacro(Backend, int);
  vtkGetMacro(Backend, int);
  vtkSetMacro(Method, int);
  vtkGetMacro(Method, int);
  ///@}

  ///@{
  /// Element order: LINEAR_ELEMENTS (0, 4-node tetrahedra, the default), QUADRATIC_ELEMENTS (1,
  /// 10-node tetrahedra with mean dilatation, locking-free for nearly incompressible tissue) or
  /// QUADRATIC_NODAL_PRESSURE (2, 10-node tetrahedra with a continuous nodal pressure). Outputs
  /// stay at the input's points. FullReference is linear only (docs/STABILITY.md).
  vtkSetMacro(ElementOrder, int);
  vtkGetMacro(ElementOrder, int);
  ///@}

  ///@{
  /// Material model: LINEAR_ELASTIC (0: small-strain linear elasticity, condensed and
  /// precomputed, so an edit is a re-solve), NEO_HOOKEAN (1: a compressible neo-Hookean material
  /// with the same small-strain moduli, for large deformations; linear elements only) or
  /// AUTO_MODEL (2, the default: linear when the linear result's largest strain is within the
  /// small-strain limit, NeoHookean otherwise).
  vtkSetMacro(Model, int);
  vtkGetMacro(Model, int);
  ///@}

  ///@{
  /// How the neo-Hookean model is solved: PRECOMPUTED (0, the default: with a factor made on the
  /// worker thread, warm-started from the last converged state; falls back to Newton when it does
  /// not converge) or NEWTON (1: one numeric factorization per iteration, the reference).
  vtkSetMacro(LargeDeformationSolver, int);
  vtkGetMacro(LargeDeformationSolver, int);
  ///@}

  ///@{
  /// For studies of error against iterations: k > 0 stops the Precomputed solver after k
  /// quasi-Newton iterations and outputs that iterate, which is not the equilibrium (field data
  /// `Converged` 0, a `SolverNote` and a warning say so). 0 (the default): no limit.
  vtkSetMacro(QuasiNewtonIterationLimit, int);
  vtkGetMacro(QuasiNewtonIterationLimit, int);
  ///@}

  ///@{
  /// Contact: CONTACT_TIED (0, every component follows the bone), CONTACT_SLIDING (1, only the
  /// component along the bone's normal follows it; the tissue slides tangentially) or
  /// CONTACT_BY_ARRAY (2, the bone point array `Sliding` picks per node) or CONTACT_AUTO (3, the
  /// default: ByArray where the bone carries `Sliding`, as an Osteotomy operation preset's output
  /// does, Tied otherwise). Field data `ContactModel` names the one used.
  vtkSetMacro(ContactModel, int);
  vtkGetMacro(ContactModel, int);
  ///@}

  ///@{
  /// When the neo-Hookean model runs: sliding tissue may lift off the bone (unilateral contact: the
  /// normal displacement only keeps the tissue out of the bone) instead of following the bone's
  /// normal motion both ways. On by default. The linear model keeps sliding nodes on the bone.
  vtkSetMacro(LiftOff, bool);
  vtkGetMacro(LiftOff, bool);
  ///@}

  ///@{
  /// Closed lips: the tissue's facing boundary surfaces (the upper and lower lip across the oral
  /// fissure) within this gap (mesh units) are tied to each other, each face to the nearest node
  /// facing it, by bridging cells 1000 times as stiff as the tissue (Core/Mesh/LipSeal.h). The
  /// output keeps the input's cells; field data `LipSealBridges` counts the ties and `LipSealGap`
  /// gives the gap used. 0 ties nothing. LIP_SEAL_AUTO (-1, the default): 3 mm where a Bone input
  /// comes from an Osteotomy operation preset (field data `Operation`), whose plan puts the teeth
  /// in occlusion, where competent lips (at rest at most 3 mm apart) are closed; 0 otherwise.
  vtkSetMacro(LipSeal, double);
  vtkGetMacro(LipSeal, double);
  ///@}

  ///@{
  /// Tied tissue nodes within this distance (mesh units) of a cut line or cut face (bone points of
  /// another SegmentId) or of the ROI's boundary (the other side of ROIMask) are released: they
  /// become free nodes, as when the surgeon detaches the tissue there. 0 (default) releases none.
  vtkSetMacro(ReleaseDistance, double);
  vtkGetMacro(ReleaseDistance, double);
  ///@}

  ///@{
  /// Also run the reference full solve and report the largest relative difference to it.
  vtkSetMacro(Verify, bool);
  vtkGetMacro(Verify, bool);
  ///@}

  /// Number of precomputes (factorizations) this filter has started; for tests and the GUI.
  int GetPrecomputeCount();

  /// Number of times this filter built the tissue-bone contact map; for tests.
  int GetContactBuildCount();

  /// Blocks until the large-deformation model's background work is done: its precompute, the
  /// refactorization that follows each solve and the corrections of the drag's state ahead. The
  /// next update then starts from the same factor on every run, whatever the machine's load (for
  /// tests and scripted measurements; the GUI never needs it).
  void WaitForBackgroundWork();

  /// Newer than the last output while an upstream edit arrived during the last RequestData (from a
  /// progress callback, while the precompute ran): the pipeline stamps the output after the edit,
  /// so without this the next update would keep a result of the superseded inputs.
  vtkMTimeType GetMTime() override;

protected:
  vtkCondensedFEMDeform();
  ~vtkCondensedFEMDeform() override;
  int FillInputPortInformation(int port, vtkInformation* info) override;
  int FillOutputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  double YoungsModulus = 15000.0;
  double PoissonRatio = 0.45;
  bool UseCellMaterials = true;
  double LengthUnit = 0.001;
  double ContactDistance = 1.0;
  int ContactModel = CONTACT_AUTO;
  double ReleaseDistance = 0.0;
  bool UseGravity = false;
  double Density = 1100.0;
  double Gravity[3] = {0.0, 0.0, -9.81};
  int OutputMode = SURFACE;
  int Backend = BACKEND_AUTO;
  int Method = METHOD_AUTO;
  bool Verify = false;
  int ElementOrder = LINEAR_ELEMENTS;
  int Model = AUTO_MODEL;
  int LargeDeformationSolver = PRECOMPUTED;
  int QuasiNewtonIterationLimit = 0;
  bool LiftOff = true;
  double LipSeal = LIP_SEAL_AUTO;

private:
  vtkCondensedFEMDeform(const vtkCondensedFEMDeform&) = delete;
  void operator=(const vtkCondensedFEMDeform&) = delete;

  faceplan::fem_filter::Settings CurrentSettings() const;
  // The Operation named by a Bone connection's field data (an Osteotomy preset), set per update.
  std::string BoneOperation;
  // The serial filter on whole inputs; false (after logging the error) when it failed.
  bool Deform(vtkUnstructuredGrid* tissue, vtkPointSet* bone, vtkUnstructuredGrid* output,
              vtkTable* table);

  struct Cache;
  std::unique_ptr<Cache> State;
  bool InputsChangedWhileRunning = false;
  vtkTimeStamp OutdatedTime;
};

#endif
