#include "Backend/ComputeBackend.h"

#include "Element/ElementStiffness.h"
#include "Common/StageTimings.h"

namespace faceplan {

namespace {

class CpuResponse final : public ResponseOperator {
public:
  explicit CpuResponse(const Eigen::MatrixXd& response) : response_(response) {}
  Status apply(const Eigen::VectorXd& roi, Eigen::VectorXd& kept) override {
    if (response_.cols() != roi.size())
      return Status::Error("ROI vector does not match the response");
    kept.noalias() = response_ * roi;
    return Status::Ok();
  }

private:
  const Eigen::MatrixXd& response_; // owned by the CondensedSystem, which owns this operator too
};

class CpuBackend final : public ComputeBackend {
public:
  std::string name() const override { return "CPU"; }

  Status assembleStiffness(const TetMesh& mesh, const Materials& materials,
                           AssemblyPattern& pattern, AssemblyTimings& timings) override {
    StageClock clock;
    std::vector<double> packed;
    ComputePackedElementStiffness(mesh, materials, packed);
    timings.elementStiffnessMs = clock.lapMs();
    AssembleFromPacked(packed, pattern);
    timings.assemblyMs = clock.lapMs();
    return Status::Ok();
  }

  Status makeResponseOperator(const Eigen::MatrixXd& response,
                              std::unique_ptr<ResponseOperator>& op) override {
    op = std::make_unique<CpuResponse>(response);
    return Status::Ok();
  }
};

} // namespace

std::shared_ptr<ComputeBackend> MakeCpuBackend() { return std::make_shared<CpuBackend>(); }

} // namespace faceplan
