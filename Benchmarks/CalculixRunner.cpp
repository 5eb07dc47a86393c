#include "CalculixRunner.h"

#include "Common/StageTimings.h"

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <unordered_map>

namespace faceplan::bench {

namespace {

// CalculiX reads at most 20 characters per field: 12 significant digits keep every number whole.
std::string Num(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.12g", v);
  return buffer;
}

// One shell word whatever the path holds (spaces, quotes): '...' with each ' written as '\''.
std::string ShellQuoted(const std::string& text) {
  std::string quoted = "'";
  for (char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

void WriteInput(const PrecomputeRequest& r, const RowVectors3d& movable, const std::string& path) {
  std::ofstream out(path);
  out << "*HEADING\nFacePlan benchmark peer\n*NODE, NSET=NALL\n";
  for (Eigen::Index i = 0; i < r.mesh.numPoints(); ++i)
    out << i + 1 << ", " << Num(r.mesh.points(i, 0)) << ", " << Num(r.mesh.points(i, 1)) << ", "
        << Num(r.mesh.points(i, 2)) << "\n";
  out << "*ELEMENT, TYPE=C3D4, ELSET=EALL\n";
  for (Eigen::Index e = 0; e < r.mesh.numTets(); ++e)
    out << e + 1 << ", " << r.mesh.tets(e, 0) + 1 << ", " << r.mesh.tets(e, 1) + 1 << ", "
        << r.mesh.tets(e, 2) + 1 << ", " << r.mesh.tets(e, 3) + 1 << "\n";
  out << "*NSET, NSET=KEPT\n";
  for (size_t k = 0; k < r.sets.kept.size(); ++k) out << r.sets.kept[k] + 1 << (k % 12 == 11 ? ",\n" : ", ");
  out << "\n";
  // Sliding nodes: a local system per node whose x axis is the normal (*TRANSFORM, TYPE=R: x along
  // the first point, the second point in the local x-y plane); only local DOF 1 is prescribed.
  std::unordered_map<int, Eigen::Vector3d> slidingNormal;
  for (size_t k = 0; k < r.sets.sliding.size(); ++k) {
    const int node = r.sets.sliding[k];
    const Eigen::Vector3d n = r.sets.slidingNormal[k];
    slidingNormal[node] = n;
    Eigen::Index axis;
    n.cwiseAbs().minCoeff(&axis);
    const Eigen::Vector3d inPlane = Eigen::Vector3d::Unit(axis);
    out << "*NSET, NSET=S" << node + 1 << "\n" << node + 1 << "\n*TRANSFORM, NSET=S" << node + 1
        << ", TYPE=R\n" << Num(n[0]) << ", " << Num(n[1]) << ", " << Num(n[2]) << ", "
        << Num(inPlane[0]) << ", " << Num(inPlane[1]) << ", " << Num(inPlane[2]) << "\n";
  }
  out << "*MATERIAL, NAME=TISSUE\n*ELASTIC\n" << Num(r.materials.E(0)) << ", " << Num(r.materials.nu(0))
      << "\n*SOLID SECTION, ELSET=EALL, MATERIAL=TISSUE\n*STEP\n*STATIC\n*BOUNDARY\n";
  std::unordered_map<int, Eigen::Index> movableRow;
  for (size_t k = 0; k < r.sets.movable.size(); ++k) movableRow[r.sets.movable[k]] = static_cast<Eigen::Index>(k);
  for (int node : r.sets.constrained) {
    auto it = movableRow.find(node);
    const Eigen::Vector3d u =
        it == movableRow.end() ? Eigen::Vector3d::Zero() : Eigen::Vector3d(movable.row(it->second).transpose());
    auto sliding = slidingNormal.find(node);
    if (sliding != slidingNormal.end()) {
      out << node + 1 << ", 1, 1, " << Num(u.dot(sliding->second)) << "\n";
      continue;
    }
    for (int c = 0; c < 3; ++c) out << node + 1 << ", " << c + 1 << ", " << c + 1 << ", " << Num(u[c]) << "\n";
  }
  out << "*NODE PRINT, NSET=KEPT, GLOBAL=YES\nU\n*END STEP\n";
}

} // namespace

CalculixResult RunCalculix(const PrecomputeRequest& request, const RowVectors3d& movable,
                           const std::string& workDir, int threads) {
  CalculixResult result;
  if (request.materials.youngsModulus.size() != 1 || request.materials.poissonRatio.size() != 1) {
    result.error = "the CalculiX peer supports one material";
    return result;
  }
  WriteInput(request, movable, workDir + "/job.inp");
  const std::string command = "cd " + ShellQuoted(workDir) + " && OMP_NUM_THREADS=" + std::to_string(threads) +
                              " CCX_NPROC_STIFFNESS=" + std::to_string(threads) +
                              " ccx -i job > ccx.log 2>&1";
  StageClock clock;
  const int rc = std::system(command.c_str());
  result.wallMs = clock.elapsedMs();
  if (rc != 0) {
    result.error = "ccx failed (exit " + std::to_string(rc) + "), see " + workDir + "/ccx.log";
    return result;
  }
  std::ifstream dat(workDir + "/job.dat");
  std::unordered_map<int, Eigen::RowVector3d> values;
  std::string line;
  while (std::getline(dat, line)) {
    std::istringstream in(line);
    int node;
    double x, y, z;
    if (in >> node >> x >> y >> z) values[node - 1] = Eigen::RowVector3d(x, y, z);
  }
  result.keptDisplacement.resize(static_cast<Eigen::Index>(request.sets.kept.size()), 3);
  for (size_t k = 0; k < request.sets.kept.size(); ++k) {
    auto it = values.find(request.sets.kept[k]);
    if (it == values.end()) {
      result.error = "job.dat lacks node " + std::to_string(request.sets.kept[k] + 1);
      return result;
    }
    result.keptDisplacement.row(k) = it->second;
  }
  result.ok = true;
  return result;
}

} // namespace faceplan::bench
