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

  // Element stiffness for every tetrahedron and assembly into pattern.upper's values.
  // Returns false with `error` set when the device fails; the caller then falls back to the CPU.
  virtual bool assembleStiffness(const TetMesh& mesh, const Materials& materials,
                                 AssemblyPattern& pattern, std::string& error) = 0;

  // Per-edit update with a dense response held by the backend:
  // kept = response * roi + offset. setResponse is called once per precompute.
  virtual bool setResponse(const Eigen::MatrixXd& response, std::string& error) = 0;
  virtual bool applyResponse(const Eigen::VectorXd& roi, Eigen::VectorXd& kept,
                             std::string& error) = 0;
};

// The CPU implementation (OpenMP-free: std::thread for element stiffness, Eigen for GEMV).
std::shared_ptr<ComputeBackend> MakeCpuBackend();

} // namespace faceplan
