#pragma once
// The compute steps that have a second (CUDA) implementation. Core runs the CPU one; Cuda/
// provides another behind this same interface, and the caller chooses which to pass in.
#include "StiffnessAssembly.h"
#include "TetMesh.h"

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

namespace faceplan {

class ComputeBackend {
public:
  virtual ~ComputeBackend() = default;
  virtual std::string name() const = 0;

  struct AssemblyTimings {
    double elementStiffnessMs = 0.0;
    double assemblyMs = 0.0; // includes moving the values back to the host
  };
  // Element stiffness for every tetrahedron and assembly into pattern.upper's values.
  // Returns false with `error` set when the device fails; the caller then falls back to the CPU.
  virtual bool assembleStiffness(const TetMesh& mesh, const Materials& materials,
                                 AssemblyPattern& pattern, AssemblyTimings& timings,
                                 std::string& error) = 0;

  // Per-edit update with the dense response held where the backend computes (the GPU's memory
  // for CUDA): the precompute makes one operator, each edit applies it. Null (with `error` set)
  // when the backend cannot hold it; the caller then falls back to the CPU.
  virtual std::unique_ptr<class ResponseOperator>
  makeResponseOperator(const Eigen::MatrixXd& response, std::string& error) = 0;
};

// kept = response * roi. Safe to call from several threads.
class ResponseOperator {
public:
  virtual ~ResponseOperator() = default;
  virtual bool apply(const Eigen::VectorXd& roi, Eigen::VectorXd& kept, std::string& error) = 0;
};

// The CPU implementation (OpenMP-free: std::thread for element stiffness, Eigen for GEMV).
std::shared_ptr<ComputeBackend> MakeCpuBackend();

} // namespace faceplan
