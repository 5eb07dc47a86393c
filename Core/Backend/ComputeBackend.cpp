#include "Backend/ComputeBackend.h"

#include "Element/ElementStiffness.h"
#include "Common/StageTimings.h"

namespace faceplan {

namespace {

class CpuResponse final : public ResponseOperator {
public:
  explicit CpuResponse(const Eigen::MatrixXd& response) : response_(response) {}
  bool apply(const Eigen::VectorXd& roi, Eigen::VectorXd& kept, std::string& error) override {
    if (response_.cols() != roi.size()) {
      error = "ROI vector does not match the response";
      return false;
    }
    kept.noalias() = response_ * roi;
    return true;
  }

private:
  const Eigen::MatrixXd& response_; // owned by the CondensedSystem, which owns this operator too
};

class CpuBackend final : public ComputeBackend {
public:
  std::string name() const override { return "CPU"; }

  bool assembleStiffness(const TetMesh& mesh, const Materials& materials, AssemblyPattern& pattern,
                         AssemblyTimings& timings, std::string&) override {
    StageClock clock;
    std::vector<double> packed;
    ComputePackedElementStiffness(mesh, materials, packed);
    timings.elementStiffnessMs = clock.lapMs();
    AssembleFromPacked(packed, pattern);
    timings.assemblyMs = clock.lapMs();
    return true;
  }

  std::unique_ptr<ResponseOperator> makeResponseOperator(const Eigen::MatrixXd& response,
                                                         std::string&) override {
    return std::make_unique<CpuResponse>(response);
  }
};

} // namespace

std::shared_ptr<ComputeBackend> MakeCpuBackend() { return std::make_shared<CpuBackend>(); }

} // namespace faceplan
