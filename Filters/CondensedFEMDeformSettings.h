// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The CondensedFEMDeform properties as one value, passed to the filter's steps (validate, convert,
// contact, solve, output) so each step sees exactly what it uses. Private to FacePlan::Filters.
#include <string>

namespace faceplan {
namespace fem_filter {

enum class OutputMode { Volume = 0, Surface = 1 };
enum class BackendChoice { Auto = 0, CPU = 1, CUDA = 2 };
// The same values as Core's SolveMethod and ElementOrder.
enum class MethodChoice { Auto = 0, DenseResponse = 1, CachedFactor = 2, FullReference = 3 };
enum class ElementOrderChoice { Linear = 0, Quadratic = 1, QuadraticNodalPressure = 2 };
enum class ModelChoice { LinearElastic = 0, NeoHookean = 1, Auto = 2 };
enum class LargeDeformationSolverChoice { Precomputed = 0, Newton = 1 };

struct Settings {
  double youngsModulus = 15000.0; // Pa
  double poissonRatio = 0.45;
  bool useCellMaterials = true;
  double lengthUnit = 0.001; // metres per mesh unit
  double contactDistance = 1.0;
  int contactModel = 3;         // ContactModelChoice: Tied, Sliding, ByArray, Auto
  double releaseDistance = 0.0; // mesh units; 0 releases nothing
  bool useGravity = false;
  double density = 1100.0; // kg/m^3
  double gravity[3] = {0.0, 0.0, -9.81};
  int outputMode = 1, backend = 0, method = 0, elementOrder = 0; // as set, validated before use
  bool verify = false;
  int model = 2;                  // ModelChoice
  int largeDeformationSolver = 0; // LargeDeformationSolverChoice
  int iterationLimit = 0;         // Precomputed: stop after this many iterations (0: none)
  bool liftOff = true;
  // Mesh units; 0 ties no facing tissue surfaces (Core/Mesh/LipSeal.h); kLipSealAuto: sealGap().
  double lipSeal = kLipSealAuto;
  // The Operation a Bone input's Osteotomy preset names (field data Operation); empty when none.
  std::string boneOperation;

  static constexpr double kLipSealAuto = -1.0;
  // Closed lips for an operation preset's plan: the plan puts the teeth in occlusion, where
  // competent lips close; at rest they are at most 3 mm apart (the interlabial gap's normal range,
  // 0-3 mm: Jacobson & Jacobson, Radiographic Cephalometry, 2006), so facing lip surfaces up to
  // 3 mm apart are tied.
  static constexpr double kOperationLipSealMetres = 0.003;
  // The gap LipSeal ties, in mesh units: as set, or with Auto 3 mm for an operation preset's bone
  // and none otherwise.
  double sealGap() const {
    if (lipSeal != kLipSealAuto)
      return lipSeal;
    return boneOperation.empty() ? 0.0 : kOperationLipSealMetres / lengthUnit;
  }

  OutputMode output() const { return static_cast<OutputMode>(outputMode); }
  MethodChoice methodChoice() const { return static_cast<MethodChoice>(method); }
  bool fullReference() const { return methodChoice() == MethodChoice::FullReference; }
  ModelChoice modelChoice() const { return static_cast<ModelChoice>(model); }
  // Model NeoHookean as set (Auto decides per update).
  bool largeDeformation() const { return modelChoice() == ModelChoice::NeoHookean; }
  bool newtonSolver() const {
    return static_cast<LargeDeformationSolverChoice>(largeDeformationSolver) ==
           LargeDeformationSolverChoice::Newton;
  }
};

} // namespace fem_filter
} // namespace faceplan
