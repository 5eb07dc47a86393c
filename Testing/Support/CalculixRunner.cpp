// SPDX-License-Identifier: BSD-3-Clause
#include "Support/CalculixRunner.h"

#include "Common/StageTimings.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <unordered_map>
#include <utility>
#include <vector>

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
  for (char c : text)
    quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

// Cells grouped by their (E, nu), in order of first appearance.
struct MaterialGroup {
  double E = 0.0, nu = 0.0;
  std::vector<Eigen::Index> cells;
};
std::vector<MaterialGroup> GroupCellsByMaterial(const PrecomputeRequest& r) {
  std::vector<MaterialGroup> groups;
  std::map<std::pair<double, double>, size_t> index;
  for (Eigen::Index e = 0; e < r.mesh.numTets(); ++e) {
    const std::pair<double, double> key(r.materials.E(e), r.materials.nu(e));
    auto it = index.find(key);
    if (it == index.end()) {
      it = index.emplace(key, groups.size()).first;
      groups.push_back({key.first, key.second, {}});
    }
    groups[it->second].cells.push_back(e);
  }
  return groups;
}

void WriteMaterials(const PrecomputeRequest& r, const CalculixOptions& options, std::ostream& out) {
  const std::vector<MaterialGroup> groups = GroupCellsByMaterial(r);
  for (size_t g = 0; g < groups.size(); ++g) {
    const MaterialGroup& group = groups[g];
    const std::string elset = groups.size() == 1 ? "EALL" : "M" + std::to_string(g + 1);
    if (groups.size() > 1) {
      out << "*ELSET, ELSET=" << elset << "\n";
      for (size_t k = 0; k < group.cells.size(); ++k)
        out << group.cells[k] + 1 << (k % 12 == 11 || k + 1 == group.cells.size() ? "\n" : ", ");
    }
    out << "*MATERIAL, NAME=TISSUE" << g + 1 << "\n";
    if (options.model == CalculixModel::NeoHookean) {
      // W = C10 (J^-2/3 I1 - 3) + (J - 1)^2 / D1 with the small-strain limit (E, nu): C10 = mu / 2,
      // D1 = 2 / kappa. Written out here, not taken from NeoHookeanFromLinear, so that the peer
      // checks that conversion too.
      const double c10 = group.E / (4.0 * (1.0 + group.nu));
      const double d1 = 6.0 * (1.0 - 2.0 * group.nu) / group.E;
      out << "*HYPERELASTIC, NEO HOOKE\n" << Num(c10) << ", " << Num(d1) << "\n";
    } else {
      out << "*ELASTIC\n" << Num(group.E) << ", " << Num(group.nu) << "\n";
    }
    out << "*SOLID SECTION, ELSET=" << elset << ", MATERIAL=TISSUE" << g + 1 << "\n";
  }
}

void WriteStepStart(const CalculixOptions& options, std::ostream& out) {
  if (options.model != CalculixModel::NeoHookean) {
    out << "*STEP\n*STATIC\n";
    return;
  }
  out << "*STEP, NLGEOM, INC=10000\n*STATIC\n"
      << Num(options.initialIncrement) << ", 1.0, " << Num(options.minimumIncrement) << ", "
      << Num(options.maximumIncrement)
      << "\n"
      // R_alpha_n, C_alpha_n, q_alpha_0, q_alpha_u, R_alpha_p: the residual test alone decides
      // (with R_alpha_n below R_alpha_l = 1e-8, ccx's solution-change test passes with it).
      << "*CONTROLS, PARAMETERS=FIELD\n"
      << Num(options.residualTolerance) << ", " << Num(options.residualTolerance) << ", , , "
      << Num(options.residualTolerance) << "\n";
}

void WriteInput(const PrecomputeRequest& r, const RowVectors3d& movable,
                const CalculixOptions& options, const std::string& path) {
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
  for (size_t k = 0; k < r.sets.kept.size(); ++k)
    out << r.sets.kept[k] + 1 << (k % 12 == 11 ? ",\n" : ", ");
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
    out << "*NSET, NSET=S" << node + 1 << "\n"
        << node + 1 << "\n*TRANSFORM, NSET=S" << node + 1 << ", TYPE=R\n"
        << Num(n[0]) << ", " << Num(n[1]) << ", " << Num(n[2]) << ", " << Num(inPlane[0]) << ", "
        << Num(inPlane[1]) << ", " << Num(inPlane[2]) << "\n";
  }
  WriteMaterials(r, options, out);
  WriteStepStart(options, out);
  out << "*BOUNDARY\n";
  std::unordered_map<int, Eigen::Index> movableRow;
  for (size_t k = 0; k < r.sets.movable.size(); ++k)
    movableRow[r.sets.movable[k]] = static_cast<Eigen::Index>(k);
  for (int node : r.sets.constrained) {
    auto it = movableRow.find(node);
    const Eigen::Vector3d u = it == movableRow.end()
                                  ? Eigen::Vector3d::Zero()
                                  : Eigen::Vector3d(movable.row(it->second).transpose());
    auto sliding = slidingNormal.find(node);
    if (sliding != slidingNormal.end()) {
      out << node + 1 << ", 1, 1, " << Num(u.dot(sliding->second)) << "\n";
      continue;
    }
    for (int c = 0; c < 3; ++c)
      out << node + 1 << ", " << c + 1 << ", " << c + 1 << ", " << Num(u[c]) << "\n";
  }
  out << "*NODE PRINT, NSET=KEPT, GLOBAL=YES\nU\n*END STEP\n";
}

// The last displacement block of job.dat (a nonlinear step prints one per increment) and its
// time, -1 when there is none.
struct DatBlock {
  double time = -1.0;
  std::unordered_map<int, Eigen::RowVector3d> values; // 0-based node -> u
};
DatBlock ReadLastDisplacementBlock(const std::string& path) {
  std::ifstream dat(path);
  DatBlock block;
  std::string line;
  while (std::getline(dat, line)) {
    // " displacements (vx,vy,vz) for set KEPT and time  0.1000000E+01"
    if (line.find("displacements") != std::string::npos) {
      const size_t at = line.rfind("time");
      block.values.clear();
      block.time = at == std::string::npos ? -1.0 : std::atof(line.c_str() + at + 4);
      continue;
    }
    std::istringstream in(line);
    int node;
    double x, y, z;
    if (in >> node >> x >> y >> z)
      block.values[node - 1] = Eigen::RowVector3d(x, y, z);
  }
  return block;
}

bool LogHasError(const std::string& path) {
  std::ifstream log(path);
  std::string line;
  while (std::getline(log, line))
    if (line.find("*ERROR") != std::string::npos)
      return true;
  return false;
}

} // namespace

CalculixResult RunCalculix(const PrecomputeRequest& request, const RowVectors3d& movable,
                           const std::string& workDir, const CalculixOptions& options) {
  CalculixResult result;
  const Eigen::Index cells = request.mesh.numTets();
  const Eigen::Index nE = request.materials.youngsModulus.size();
  const Eigen::Index nNu = request.materials.poissonRatio.size();
  if ((nE != 1 && nE != cells) || (nNu != 1 && nNu != cells)) {
    result.error = "the CalculiX peer needs one material, or one per cell";
    return result;
  }
  if (movable.rows() != static_cast<Eigen::Index>(request.sets.movable.size()) ||
      movable.cols() != 3) {
    result.error = "the CalculiX peer needs one displacement per movable node";
    return result;
  }
  WriteInput(request, movable, options, workDir + "/job.inp");
  const int threads = std::max(1, options.threads);
  const std::string command = "cd " + ShellQuoted(workDir) +
                              " && rm -f job.dat && OMP_NUM_THREADS=" + std::to_string(threads) +
                              " CCX_NPROC_STIFFNESS=" + std::to_string(threads) +
                              " ccx -i job > ccx.log 2>&1";
  StageClock clock;
  const int rc = std::system(command.c_str());
  result.wallMs = clock.elapsedMs();
  if (rc != 0 || LogHasError(workDir + "/ccx.log")) {
    result.error = "ccx failed (exit " + std::to_string(rc) + "), see " + workDir + "/ccx.log";
    return result;
  }
  const DatBlock block = ReadLastDisplacementBlock(workDir + "/job.dat");
  // The step's period is 1: a last block before it means ccx stopped early.
  if (std::abs(block.time - 1.0) > 1e-6) {
    result.error = "job.dat does not reach the end of the step (last time " +
                   std::to_string(block.time) + "), see " + workDir + "/ccx.log";
    return result;
  }
  result.keptDisplacement.resize(static_cast<Eigen::Index>(request.sets.kept.size()), 3);
  for (size_t k = 0; k < request.sets.kept.size(); ++k) {
    auto it = block.values.find(request.sets.kept[k]);
    if (it == block.values.end()) {
      result.error = "job.dat lacks node " + std::to_string(request.sets.kept[k] + 1);
      return result;
    }
    result.keptDisplacement.row(static_cast<Eigen::Index>(k)) = it->second;
  }
  result.ok = true;
  return result;
}

CalculixResult RunCalculix(const PrecomputeRequest& request, const RowVectors3d& movable,
                           const std::string& workDir, int threads) {
  CalculixOptions options;
  options.threads = threads;
  return RunCalculix(request, movable, workDir, options);
}

} // namespace faceplan::bench
