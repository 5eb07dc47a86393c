// SPDX-License-Identifier: BSD-3-Clause
#include "Comparison/FloatCpuBackend.h"

namespace faceplan {

namespace {

class FloatCpuResponse final : public ResponseOperator {
public:
  explicit FloatCpuResponse(const Eigen::MatrixXd& response) : response_(response.cast<float>()) {}
  Status apply(const Eigen::VectorXd& roi, Eigen::VectorXd& kept) override {
    if (response_.cols() != roi.size())
      return Status::Error("ROI vector does not match the response");
    const Eigen::VectorXf roiF = roi.cast<float>();
    const Eigen::VectorXf keptF = response_ * roiF;
    kept = keptF.cast<double>();
    return Status::Ok();
  }

private:
  Eigen::MatrixXf response_;
};

class FloatCpuBackend final : public ComputeBackend {
public:
  std::string name() const override { return "CPU-float"; }
  Status assembleStiffness(const TetMesh& mesh, const Materials& materials,
                           AssemblyPattern& pattern, AssemblyTimings& timings) override {
    return cpu_->assembleStiffness(mesh, materials, pattern, timings);
  }
  Status makeResponseOperator(const Eigen::MatrixXd& response,
                              std::unique_ptr<ResponseOperator>& op) override {
    op = std::make_unique<FloatCpuResponse>(response);
    return Status::Ok();
  }

private:
  std::shared_ptr<ComputeBackend> cpu_ = MakeCpuBackend();
};

} // namespace

std::shared_ptr<ComputeBackend> MakeFloatCpuBackend() {
  return std::make_shared<FloatCpuBackend>();
}

} // namespace faceplan
