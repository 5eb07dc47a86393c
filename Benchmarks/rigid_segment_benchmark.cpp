// SPDX-License-Identifier: BSD-3-Clause
// The rigid-segment fast path on the Badin face with a Le Fort I-sized segment: the tissue tied to
// the maxilla moves rigidly, the rest of the bone contact stays. Compares the RigidSegments
// precompute and edits with the general dense response for the same ROI.
//
//   rigid_segment_benchmark [--mesh Data/face/face_tissue.vtu] [--precompute-repeats N]
//                           [--edits N] [--json FILE]
#include "CondensedFEM/CondensedFEM.h"
#include "Support/BoundaryNodes.h"
#include "Support/VtuReader.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cstdio>
#include <fstream>
#include <map>
#include <random>
#include <string>
#include <vector>

using namespace faceplan;

namespace {

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n == 0 ? 0.0 : (n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]));
}

// A Le Fort I-like move: advancement along +y-ish of 3-6 mm, a few degrees of rotation about the
// segment's centroid.
SegmentTransform RandomMove(const Eigen::Vector3d& pivot, std::mt19937& rng) {
  std::uniform_real_distribution<double> advance(3.0, 6.0), small(-1.5, 1.5), angle(-3.0, 3.0);
  const Eigen::Matrix3d r = (Eigen::AngleAxisd(angle(rng) * M_PI / 180, Eigen::Vector3d::UnitX()) *
                             Eigen::AngleAxisd(angle(rng) * M_PI / 180, Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(angle(rng) * M_PI / 180, Eigen::Vector3d::UnitZ()))
                                .toRotationMatrix();
  SegmentTransform t;
  t.leftCols<3>() = r;
  t.col(3) = pivot - r * pivot + Eigen::Vector3d(small(rng), -advance(rng), small(rng));
  return t;
}

RowVectors3d Follow(const PrecomputeRequest& r, const SegmentTransform& t) {
  RowVectors3d u(static_cast<Eigen::Index>(r.sets.movable.size()), 3);
  for (size_t k = 0; k < r.sets.movable.size(); ++k) {
    const Eigen::Vector3d x = r.mesh.points.row(r.sets.movable[k]).transpose();
    u.row(static_cast<Eigen::Index>(k)) = (t.leftCols<3>() * x + t.col(3) - x).transpose();
  }
  return u;
}

struct PrecomputeFigures {
  double totalMs = 0.0, condensationMs = 0.0;
  SystemInfo info;
  std::shared_ptr<const CondensedSystem> system;
};

bool RunPrecompute(const PrecomputeRequest& request, int repeats, PrecomputeFigures& out) {
  std::vector<double> total, condensation;
  for (int k = 0; k < repeats; ++k) {
    out.system.reset();
    const Status s = Precompute(request, out.system);
    if (!s) {
      std::fprintf(stderr, "precompute failed: %s\n", s.message.c_str());
      return false;
    }
    out.info = Describe(*out.system);
    total.push_back(out.info.precomputeTimings[Stage::Total].ms);
    condensation.push_back(out.info.precomputeTimings[Stage::Condensation].ms);
  }
  out.totalMs = Median(total);
  out.condensationMs = Median(condensation);
  return true;
}

} // namespace

int main(int argc, char** argv) {
  std::string meshPath = "Data/face/face_tissue.vtu", jsonPath;
  int precomputeRepeats = 5, edits = 500;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string key = argv[i], value = argv[i + 1];
    if (key == "--mesh")
      meshPath = value;
    else if (key == "--precompute-repeats")
      precomputeRepeats = std::max(1, std::stoi(value));
    else if (key == "--edits")
      edits = std::max(1, std::stoi(value));
    else if (key == "--json")
      jsonPath = value;
    else {
      std::fprintf(stderr, "unknown option %s\n", key.c_str());
      return 2;
    }
  }
  bench::VtuMesh vtu;
  std::string error;
  if (!bench::ReadVtuTets(meshPath, vtu, error)) {
    std::fprintf(stderr, "%s\n", error.c_str());
    return 1;
  }
  auto contact = vtu.pointData.find("BoneContact");
  auto bone = vtu.pointData.find("ContactBone");
  if (contact == vtu.pointData.end() || bone == vtu.pointData.end()) {
    std::fprintf(stderr, "%s needs the point arrays BoneContact and ContactBone\n",
                 meshPath.c_str());
    return 1;
  }
  // Tied: every bone contact node; the segment: those on the maxilla (ContactBone 2); kept: the
  // other boundary nodes (the skin and the tissue's cut borders).
  PrecomputeRequest rigid;
  rigid.mesh = vtu.mesh;
  rigid.materials = Materials::Uniform(3.0e3, 0.45);
  const std::vector<char> boundary = bench::BoundaryNodes(rigid.mesh);
  Eigen::Vector3d pivot = Eigen::Vector3d::Zero();
  for (Eigen::Index i = 0; i < rigid.mesh.numPoints(); ++i) {
    const int node = static_cast<int>(i);
    if (contact->second[i] > 0.5) {
      rigid.sets.constrained.push_back(node);
      if (std::lround(bone->second[i]) == 2) {
        rigid.sets.movable.push_back(node);
        rigid.sets.movableSegment.push_back(1);
        pivot += rigid.mesh.points.row(i).transpose();
      }
    } else if (boundary[i]) {
      rigid.sets.kept.push_back(node);
    }
  }
  if (rigid.sets.movable.empty()) {
    std::fprintf(stderr, "%s: no maxilla contact nodes\n", meshPath.c_str());
    return 1;
  }
  pivot /= double(rigid.sets.movable.size());
  PrecomputeRequest general = rigid;
  general.sets.movableSegment.clear();
  general.options.method = SolveMethod::DenseResponse;

  PrecomputeFigures fast, slow, unchecked;
  if (!RunPrecompute(rigid, precomputeRepeats, fast) ||
      !RunPrecompute(general, precomputeRepeats, slow))
    return 1;
  // The same rigid system without the per-edit large-strain check, to show the product's own cost.
  PrecomputeRequest rigidUnchecked = rigid;
  rigidUnchecked.options.strainWarningLimit = 0.0;
  if (!RunPrecompute(rigidUnchecked, 1, unchecked))
    return 1;

  std::mt19937 rng(7);
  std::vector<SolveInput> inputs(16);
  for (SolveInput& input : inputs) {
    input.segmentTransforms = {RandomMove(pivot, rng)};
    input.movableDisplacement = Follow(rigid, input.segmentTransforms[0]);
  }
  // Agreement first (the rigid path against the general one on every distinct move, results and
  // largest strain), then each path's edits timed in a run of their own, as a drag runs them: one
  // path's solves between another's would time the rigid product with its response evicted from
  // the cache by the general response's 80 MB.
  double worstDifference = 0.0, worstStrainDifference = 0.0;
  SolveResult a, b;
  for (const SolveInput& input : inputs) {
    Status s = Solve(*fast.system, input, a);
    if (s)
      s = Solve(*slow.system, input, b);
    if (!s) {
      std::fprintf(stderr, "solve failed: %s\n", s.message.c_str());
      return 1;
    }
    worstDifference =
        std::max(worstDifference, (a.keptDisplacement - b.keptDisplacement).cwiseAbs().maxCoeff() /
                                      b.keptDisplacement.cwiseAbs().maxCoeff());
    worstStrainDifference = std::max(worstStrainDifference,
                                     std::abs(a.largestStrain - b.largestStrain) / b.largestStrain);
  }
  auto timeEdits = [&](const CondensedSystem& system, std::vector<double>& ms) {
    SolveResult r;
    for (int e = 0; e < edits; ++e) {
      if (!Solve(system, inputs[e % inputs.size()], r))
        return false;
      ms.push_back(r.timings[Stage::Total].ms);
    }
    return true;
  };
  std::vector<double> rigidMs, generalMs, uncheckedMs;
  if (!timeEdits(*fast.system, rigidMs) || !timeEdits(*unchecked.system, uncheckedMs) ||
      !timeEdits(*slow.system, generalMs)) {
    std::fprintf(stderr, "solve failed\n");
    return 1;
  }
  Solve(*fast.system, inputs.back(), a);
  const double rigidEdit = Median(rigidMs), generalEdit = Median(generalMs);
  const double uncheckedEdit = Median(uncheckedMs);
  std::printf(
      "face: %lld tets, %lld nodes; free / kept / ROI DOFs %lld / %lld / %lld; segment nodes %zu; "
      "%lld slivers, %lld folded face pairs\n",
      static_cast<long long>(rigid.mesh.numTets()), static_cast<long long>(rigid.mesh.numPoints()),
      fast.info.freeDofs, fast.info.keptDofs, fast.info.roiDofs, rigid.sets.movable.size(),
      fast.info.sliverCells, fast.info.foldedFaces);
  std::printf("RigidSegments (%s): precompute %.1f ms (condensation %.1f ms), per-edit %.4f ms "
              "(%.4f ms without the large-strain check)\n",
              fast.info.choiceReason.c_str(), fast.totalMs, fast.condensationMs, rigidEdit,
              uncheckedEdit);
  std::printf("DenseResponse: precompute %.1f ms (condensation %.1f ms), per-edit %.4f ms\n",
              slow.totalMs, slow.condensationMs, generalEdit);
  std::printf("precompute ratio general/rigid %.1f (condensation %.1f); max rel. difference %.2e, "
              "largest strain %.2e (medians of %d precomputes, %d edits)\n",
              slow.totalMs / fast.totalMs, slow.condensationMs / fast.condensationMs,
              worstDifference, worstStrainDifference, precomputeRepeats, edits);
  for (const PrecomputeFigures* f : {&fast, &slow}) {
    std::printf("%s: ordering %s, nnz(L) %.3g; stages (last run, ms):", MethodName(f->info.method),
                f->info.ordering.c_str(), f->info.factorNonzeros);
    for (int k = 0; k < kNumStages; ++k)
      std::printf(" %s %.1f", StageName(static_cast<Stage>(k)),
                  f->info.precomputeTimings.stages[k].ms);
    std::printf("\n");
  }
  std::printf("RigidSegments edit stages (last edit, ms): BoundaryCondition %.4f Load %.4f Solve "
              "%.4f Total %.4f\n",
              a.timings[Stage::BoundaryCondition].ms, a.timings[Stage::Load].ms,
              a.timings[Stage::Solve].ms, a.timings[Stage::Total].ms);
  if (!jsonPath.empty()) {
    std::ofstream out(jsonPath);
    out.precision(6);
    out << "{\n  \"tets\": " << rigid.mesh.numTets() << ", \"nodes\": " << rigid.mesh.numPoints()
        << ", \"free_dofs\": " << fast.info.freeDofs << ", \"kept_dofs\": " << fast.info.keptDofs
        << ", \"roi_dofs\": " << fast.info.roiDofs
        << ", \"segment_nodes\": " << rigid.sets.movable.size()
        << ",\n  \"precompute_repeats\": " << precomputeRepeats << ", \"edits\": " << edits
        << ",\n  \"rigid_precompute_ms\": " << fast.totalMs
        << ", \"rigid_condensation_ms\": " << fast.condensationMs
        << ", \"rigid_edit_ms\": " << rigidEdit
        << ", \"rigid_edit_ms_without_strain_check\": " << uncheckedEdit
        << ",\n  \"general_precompute_ms\": " << slow.totalMs
        << ", \"general_condensation_ms\": " << slow.condensationMs
        << ", \"general_edit_ms\": " << generalEdit
        << ",\n  \"max_rel_difference\": " << worstDifference
        << ", \"largest_strain_rel_difference\": " << worstStrainDifference << "\n}\n";
  }
  return 0;
}
