#include "Comparison/FloatCpuBackend.h"

namespace faceplan {

namespace {

class FloatCpuResponse final : public ResponseOperator {
public:
  explicit FloatCpuResponse(const Eigen::MatrixXd& response) : response_(response.cast<float>()) {}
  bool apply(const Eigen::VectorXd& roi, Eigen::VectorXd& kept, std::string& error) override {
    if (response_.cols() != roi.size()) {
      error = "ROI vector does not match the response";
      return false;
    }
    const Eigen::VectorXf roiF = roi.cast<float>();
    const Eigen::VectorXf keptF = response_ * roiF;
    kept = keptF.cast<double>();
    return true;
  }

private:
  Eigen::MatrixXf response_;
};

class FloatCpuBackend final : public ComputeBackend {
public:
  std::string name() const override { return "CPU-float"; }
  bool assembleStiffness(const TetMesh& mesh, const Materials& materials, AssemblyPattern& pattern,
                         AssemblyTimings& timings, std::string& error) override {
    return cpu_->assembleStiffness(mesh, materials, pattern, timings, error);
  }
  std::unique_ptr<ResponseOperator> makeResponseOperator(const Eigen::MatrixXd& response,
                                                         std::string&) override {
    return std::make_unique<FloatCpuResponse>(response);
  }

private:
  std::shared_ptr<ComputeBackend> cpu_ = MakeCpuBackend();
};

} // namespace

std::shared_ptr<ComputeBackend> MakeFloatCpuBackend() {
  return std::make_shared<FloatCpuBackend>();
}

} // namespace faceplan
