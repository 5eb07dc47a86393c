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
class ResponseOperator;

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
