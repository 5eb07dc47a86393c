// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The compute steps that have a second (CUDA) implementation. Core runs the CPU one; Cuda/
// provides another behind this same interface, and the caller chooses which to pass in.
#include "Common/Status.h"
#include "Element/StiffnessAssembly.h"
#include "Mesh/TetMesh.h"

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

namespace faceplan {

class CholmodFactor;
class SinglePrecisionFactor;
class ResponseOperator;
class HyperelasticForces;
class FactorOnDevice;

// The cells of a large-deformation solve (PrecomputedLargeDeformation.h) in plain arrays, for a
// backend that evaluates their forces: each cell's corners, shape-function gradients, volume and
// moduli, and each node's frame (the solve's DOFs are in the nodes' frames).
struct HyperelasticCells {
  int nodes = 0;
  std::vector<int> corners;      // 4 per cell
  std::vector<double> gradients; // 12 per cell: grad N_a of corner a at [3 a, 3 a + 3)
  std::vector<double> volume, mu, kappa;
  std::vector<char> smallStrain; // per cell: small-strain elastic instead of neo-Hookean
  std::vector<int> frameOf;      // per node: index into frames, -1 for the identity
  std::vector<double> frames;    // 9 per frame, column-major (columns: normal, two tangents)
};

class ComputeBackend {
public:
  virtual ~ComputeBackend() = default;
  virtual std::string name() const = 0;

  struct AssemblyTimings {
    double elementStiffnessMs = 0.0;
    double assemblyMs = 0.0; // includes moving the values back to the host
  };
  // Element stiffness for every tetrahedron and assembly into pattern.upper's values.
  // Fails when the device fails; the caller then falls back to the CPU.
  virtual Status assembleStiffness(const TetMesh& mesh, const Materials& materials,
                                   AssemblyPattern& pattern, AssemblyTimings& timings) = 0;

  // Per-edit update with the dense response held where the backend computes (the GPU's memory
  // for CUDA): the precompute makes one operator, each edit applies it. Fails (op stays null)
  // when the backend cannot hold it; the caller then falls back to the CPU.
  virtual Status makeResponseOperator(const Eigen::MatrixXd& response,
                                      std::unique_ptr<ResponseOperator>& op) = 0;

  // Optional: numeric factorization and dense response in one step (the CUDA backend).
  // True when the backend implements factorAndBuildResponse. The CPU backend keeps the default:
  // Precompute then runs CholmodFactor::factorize and its own blocked CPU response.
  virtual bool providesFactorAndResponse() const { return false; }

  struct FactorResponseReport {
    double factorizationMs = 0.0; // numeric factorization, its uploads and the copy into `factor`
    double worstRelativeResidual = 0.0; // max over ROI columns b of ||K_FF x - b|| / ||b||
    std::string detail;                 // one line: what ran where (for logs and the benchmark)
  };
  // Called by Precompute (method DenseResponse) after factor.analyze(kffUpper), instead of
  // factor.factorize + the CPU response. Computes the numeric factorization into `factor` (leaving
  // it usable for CPU solves, factor.isFactorized()), the dense response
  //   response = -(rows [0, keptDofs) of K_FF^-1 K_FR)      (host copy, keptDofs x ROI DOFs)
  // and the per-edit operator holding it (`op`, may stay null: the caller then makes one).
  // On failure `factor` may be factorized or not, and the caller does on the CPU whatever is
  // missing (with a warning).
  virtual Status factorAndBuildResponse(const SparseMatrix& kffUpper, const SparseMatrix& kfr,
                                        Eigen::Index keptDofs, CholmodFactor& factor,
                                        Eigen::MatrixXd& response,
                                        std::unique_ptr<ResponseOperator>& op,
                                        FactorResponseReport& report) {
    (void)kffUpper, (void)kfr, (void)keptDofs, (void)factor, (void)response, (void)op, (void)report;
    return Status::Error("unsupported");
  }

  // Optional: the large-deformation solve's steps (the CUDA backend). The cells' energy and
  // internal force at a state (NeoHookeanTetState and SmallStrainTetState, summed per node and
  // turned into the nodes' frames), made once per precompute. Fails when the backend has none.
  virtual Status makeHyperelasticForces(const HyperelasticCells& cells,
                                        std::unique_ptr<HyperelasticForces>& forces) {
    (void)cells, (void)forces;
    return Status::Error("this backend has no large-deformation steps");
  }
  // Optional: a copy of a factor's single-precision values and structure (`factor`, assigned) and
  // of the symmetric matrix `upper` (its upper triangle; the factored matrix before pinning), for
  // the solve's substitutions and tangent products. Called on the background refactorization's
  // thread. Fails when the backend has none, `factor` is not assigned or the copy does not fit.
  virtual Status makeFactorOnDevice(const SinglePrecisionFactor& factor, const SparseMatrix& upper,
                                    std::unique_ptr<FactorOnDevice>& device) {
    (void)factor, (void)upper, (void)device;
    return Status::Error("this backend has no large-deformation steps");
  }
};

// The energy and internal force of HyperelasticCells at a state. Not for concurrent calls.
class HyperelasticForces {
public:
  virtual ~HyperelasticForces() = default;
  // u and force: 3 per node in the nodes' frames. `admissible` is false (energy and force then
  // undefined) when a cell would be inverted (det F <= 0) or a value is not finite.
  virtual Status evaluate(const Eigen::VectorXd& u, double& energy, Eigen::VectorXd& force,
                          bool& admissible) = 0;
  // The smallest det F over the cells, the largest absolute principal Green strain and the first
  // cell that has it (as the CPU's MeasureDeformation, to round-off).
  virtual Status measure(const Eigen::VectorXd& u, double& smallestVolumeRatio,
                         double& largestGreenStrain, long long& largestStrainCell) {
    (void)u, (void)smallestVolumeRatio, (void)largestGreenStrain, (void)largestStrainCell;
    return Status::Error("unsupported");
  }
};

// A factor and a matrix held by a backend. Not for concurrent calls.
class FactorOnDevice {
public:
  virtual ~FactorOnDevice() = default;
  // x = A^-1 b (A = L L^T, the factored matrix, original numbering) in single precision after
  // scaling b to unit largest entry, as SinglePrecisionFactor::solve.
  virtual Status solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) = 0;
  // out = M v, M the symmetric matrix whose upper triangle was given, in double precision.
  virtual Status multiply(const Eigen::VectorXd& v, Eigen::VectorXd& out) = 0;
  // One line on how the copy is laid out (for benchmarks and logs).
  virtual std::string describe() const { return {}; }
};

// kept = response * roi. Safe to call from several threads.
class ResponseOperator {
public:
  virtual ~ResponseOperator() = default;
  virtual Status apply(const Eigen::VectorXd& roi, Eigen::VectorXd& kept) = 0;
};

// The CPU implementation (OpenMP-free: std::thread for element stiffness, Eigen for GEMV).
std::shared_ptr<ComputeBackend> MakeCpuBackend();

} // namespace faceplan
