#include "Support/FEMTestScenes.h"

namespace faceplan::testing {

PrecomputeRequest ShellRequest(int subdivisions, int layers, double E, double nu) {
  FaceLikeScene scene = MakeFaceLikeScene(subdivisions, layers, 0.1);
  PrecomputeRequest request;
  request.mesh = scene.shell.mesh;
  request.materials = Materials::Uniform(E, nu, 1.0e-6);
  request.sets.constrained = scene.constrained;
  request.sets.movable = scene.movable;
  request.sets.kept = scene.kept;
  return request;
}

RowVectors3d SmoothRoiField(const PrecomputeRequest& request, double amplitude) {
  RowVectors3d u(static_cast<Eigen::Index>(request.sets.movable.size()), 3);
  for (size_t k = 0; k < request.sets.movable.size(); ++k) {
    const Eigen::RowVector3d p = request.mesh.points.row(request.sets.movable[k]);
    u.row(k) << amplitude * std::sin(p(0) / 20.0), amplitude * std::cos(p(1) / 25.0) * 0.5,
        -amplitude * (1.0 + std::sin(p(0) * p(1) / 900.0));
  }
  return u;
}

} // namespace faceplan::testing
