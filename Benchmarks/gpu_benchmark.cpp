// SPDX-License-Identifier: BSD-3-Clause
// GPU benchmark: element stiffness + assembly, per-edit update and precompute, CUDA
// backend against the CPU backend on face-like spherical-shell scenes (Core's MakeFaceLikeScene).
//
//   gpu_benchmark [--out results.json] [--cases kidney,heart,mandible,10k,100k,1M]
//                 [--repeats 20] [--edit-repeats 200] [--cpu-precompute-max-tets 200000]
//                 [--no-precompute] [--no-blas-sweep] [--cpu-edit-budget-ms 60000]
//                 [--data Data]
//
// The organ cases read Data/organs/*.vtu (kidney 1.9k, heart 6.6k, mandible 10.6k tetrahedra) with
// Testing/Support/VtuReader (no VTK needed), with faceplan_report's node sets; when a file cannot
// be read a generated shell of similar size stands in (said in the output). The 10k, 100k and 1M
// cases are Core's MakeFaceLikeScene shells. Without a GPU it still runs the CPU columns (GPU
// columns empty).
#include "Backend/ComputeBackend.h"
#include "Common/RelativeDifference.h"
#include "Common/StageTimings.h"
#include "CondensedFEM/CondensedFEM.h"
#include "CondensedFEM/CondensedSystem.h"
#include "Element/StiffnessAssembly.h"
#include "Support/BoundaryNodes.h"
#include "Support/ShellMeshGenerator.h"
#include "Support/VtuReader.h"
#if FACEPLAN_HAS_CUDA
#include "CudaBackend.h"
#include "CudaDenseResponse.h"
#endif

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <dlfcn.h>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <numeric>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

using namespace faceplan;

namespace {

struct Case {
  std::string name;
  int subdivisions, layers; // the generated shell (also the fallback when `file` cannot be read)
  std::string file;         // a real mesh under the data folder, or empty
};

const std::vector<Case> kAllCases = {
    {"kidney", 4, 2, "organs/kidney_1900.vtu"},      // shell fallback: 1,920 tets
    {"heart", 6, 3, "organs/heart_6600.vtu"},        // 6,480
    {"mandible", 6, 5, "organs/mandible_10600.vtu"}, // 10,800
    {"10k", 5, 7, ""},                               // 10,500 tets
    {"100k", 16, 7, ""},                             // 107,520 tets
    {"1M", 50, 7, ""},                               // 1,050,000 tets
};

struct BenchScene {
  TetMesh mesh;
  Materials materials;
  std::vector<int> constrained, movable, kept;
  std::string source;
};

// An organ mesh of Data/ with the node sets of faceplan_report's organ scenes: BoneContact nodes
// fixed, the 30 % of them nearest the contact centre moved (the ROI), boundary nodes not in
// contact kept; E = 3 kPa, nu = 0.45.
bool OrganScene(const std::string& path, BenchScene& out, std::string& error) {
  bench::VtuMesh vtu;
  if (!bench::ReadVtuTets(path, vtu, error))
    return false;
  auto contact = vtu.pointData.find("BoneContact");
  if (contact == vtu.pointData.end())
    return error = path + " has no BoneContact array", false;
  out.mesh = vtu.mesh;
  out.materials = Materials::Uniform(3.0e3, 0.45);
  const Eigen::Index n = out.mesh.numPoints();
  const std::vector<char> boundary = bench::BoundaryNodes(out.mesh);
  for (Eigen::Index i = 0; i < n; ++i) {
    if (contact->second[i] > 0.5)
      out.constrained.push_back(static_cast<int>(i));
    else if (boundary[i])
      out.kept.push_back(static_cast<int>(i));
  }
  if (out.constrained.empty())
    return error = path + ": no BoneContact nodes", false;
  Eigen::RowVector3d centre = Eigen::RowVector3d::Zero();
  for (int i : out.constrained)
    centre += out.mesh.points.row(i);
  centre /= double(out.constrained.size());
  int seed = out.constrained[0];
  for (int i : out.constrained)
    if ((out.mesh.points.row(i) - centre).norm() < (out.mesh.points.row(seed) - centre).norm())
      seed = i;
  std::vector<std::pair<double, int>> byDistance;
  for (int i : out.constrained)
    byDistance.push_back({(out.mesh.points.row(i) - out.mesh.points.row(seed)).norm(), i});
  std::sort(byDistance.begin(), byDistance.end());
  const size_t count = std::max<size_t>(1, byDistance.size() * 3 / 10);
  for (size_t k = 0; k < count; ++k)
    out.movable.push_back(byDistance[k].second);
  out.source =
      path + " (BoneContact fixed, 30 % of it moved, free boundary kept; E = 3 kPa, nu = 0.45)";
  return true;
}

double Median(std::vector<double> v) {
  if (v.empty())
    return std::nan("");
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double NowMs() {
  return std::chrono::duration<double, std::milli>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// Three tissue bands through the thickness (skin-, fat- and muscle-like), one value per cell.
Materials LayeredMaterials(const ShellMesh& shell) {
  const Eigen::Index m = shell.mesh.numTets();
  Materials materials;
  materials.youngsModulus.resize(m);
  materials.poissonRatio.resize(m);
  const int layers =
      static_cast<int>(shell.mesh.numPoints() / std::max(shell.nodesPerLayer, 1)) - 1;
  for (Eigen::Index e = 0; e < m; ++e) {
    int layer = std::numeric_limits<int>::max();
    for (int k = 0; k < 4; ++k)
      layer = std::min(layer, shell.mesh.tets(e, k) / shell.nodesPerLayer);
    const double f = layers > 0 ? double(layer) / layers : 0.0;
    const int band = f < 0.34 ? 0 : (f < 0.67 ? 1 : 2);
    static const double E[3] = {10.0, 1.0, 3.0}, nu[3] = {0.45, 0.49, 0.47};
    materials.youngsModulus[e] = E[band];
    materials.poissonRatio[e] = nu[band];
  }
  return materials;
}

// Minimal JSON writer: an object of key -> number/string/bool, nested by hand.
class Json {
public:
  void num(const std::string& key, double value) {
    std::ostringstream v;
    v.precision(10);
    if (std::isfinite(value))
      v << value;
    else
      v << "null";
    add(key, v.str());
  }
  void str(const std::string& key, const std::string& value) {
    std::string escaped;
    for (char c : value) {
      if (c == '"' || c == '\\')
        escaped += '\\';
      escaped += c;
    }
    add(key, "\"" + escaped + "\"");
  }
  void boolean(const std::string& key, bool value) { add(key, value ? "true" : "false"); }
  void raw(const std::string& key, const std::string& json) { add(key, json); }
  std::string text() const { return "{" + body_ + "}"; }

private:
  void add(const std::string& key, const std::string& value) {
    if (!body_.empty())
      body_ += ", ";
    body_ += "\"" + key + "\": " + value;
  }
  std::string body_;
};

struct Options {
  std::string out;
  std::vector<std::string> cases;
  int repeats = 20;
  int editRepeats = 200;
  long long cpuPrecomputeMaxTets = 200000;
  bool precompute = true;
  bool blasSweep = true;
  double cpuEditBudgetMs = 60000.0; // CPU per-edit repeats stop after this much time (at least 5)
  std::string dataDir = "Data";     // organ meshes: <dataDir>/organs/*.vtu
};

std::vector<std::string> Split(const std::string& s) {
  std::vector<std::string> parts;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, ','))
    if (!item.empty())
      parts.push_back(item);
  return parts;
}

struct Row { // one line of the human-readable tables
  std::string name;
  long long tets = 0, nodes = 0, nnz = 0;
  double cpuKeMs = NAN, cpuAsmMs = NAN, gpuKeKernelMs = NAN, gpuGatherKernelMs = NAN,
         gpuKernelMs = NAN, gpuWithTransfersMs = NAN, gpuPageableMs = NAN, gpuFirstCallMs = NAN,
         floorMs = NAN, fraction = NAN, asmDiff = NAN;
  long long keptDofs = 0, roiDofs = 0;
  double cpuEditMs = NAN, gpuEditMs = NAN, gpuSolveMs = NAN, editDiff = NAN, editFloorMs = NAN;
  int cpuEditRepeats = 0, gpuEditRepeats = 0;
  double cpuPrecomputeS = NAN, coreGpuPrecomputeS = NAN;
  double responseResidual = NAN, responseDiff = NAN, solveDiff = NAN;
  std::string method;
};

#if FACEPLAN_HAS_CUDA
// CHOLMOD's CPU factorization time against the number of OpenBLAS threads.
using SetBlasThreads = void (*)(int);
SetBlasThreads BlasThreadSetter() {
  return reinterpret_cast<SetBlasThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"));
}
#endif

} // namespace

int main(int argc, char** argv) {
  Options opt;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--out")
      opt.out = next();
    else if (a == "--cases")
      opt.cases = Split(next());
    else if (a == "--repeats")
      opt.repeats = std::max(1, std::atoi(next().c_str()));
    else if (a == "--edit-repeats")
      opt.editRepeats = std::max(1, std::atoi(next().c_str()));
    else if (a == "--cpu-precompute-max-tets")
      opt.cpuPrecomputeMaxTets = std::atoll(next().c_str());
    else if (a == "--no-precompute")
      opt.precompute = false;
    else if (a == "--no-blas-sweep")
      opt.blasSweep = false;
    else if (a == "--cpu-edit-budget-ms")
      opt.cpuEditBudgetMs = std::atof(next().c_str());
    else if (a == "--data")
      opt.dataDir = next();
    else {
      std::fprintf(
          stderr,
          "usage: %s [--out results.json] [--cases kidney,heart,mandible,10k,100k,1M] "
          "[--repeats N] [--edit-repeats N] [--cpu-precompute-max-tets N] [--no-precompute] "
          "[--no-blas-sweep] [--cpu-edit-budget-ms MS] [--data DIR]\n",
          argv[0]);
      return 2;
    }
  }
  std::vector<Case> cases;
  for (const Case& c : kAllCases)
    if (opt.cases.empty() ||
        std::find(opt.cases.begin(), opt.cases.end(), c.name) != opt.cases.end())
      cases.push_back(c);

  Json top;
  top.str("benchmark", "FacePlan gpu_benchmark");
  top.num("hardware_threads", std::thread::hardware_concurrency());
  std::shared_ptr<ComputeBackend> gpu;
  std::string gpuWhy;
  double deviceBandwidthGBs = NAN, d2hPinnedGBs = NAN, d2hPageableGBs = NAN;
#if FACEPLAN_HAS_CUDA
  gpuWhy = cuda::MakeCudaBackend(gpu).message;
  if (gpu) {
    cuda::Bandwidth bw;
    const Status measured = cuda::MeasureBandwidth(bw);
    if (measured) {
      deviceBandwidthGBs = bw.deviceToDeviceGBs;
      d2hPinnedGBs = bw.deviceToHostPinnedGBs;
      d2hPageableGBs = bw.deviceToHostPageableGBs;
      Json b;
      b.num("device_to_device_GBs_read_plus_write", bw.deviceToDeviceGBs);
      b.num("host_to_device_pinned_GBs", bw.hostToDevicePinnedGBs);
      b.num("device_to_host_pinned_GBs", bw.deviceToHostPinnedGBs);
      b.num("host_to_device_pageable_GBs", bw.hostToDevicePageableGBs);
      b.num("device_to_host_pageable_GBs", bw.deviceToHostPageableGBs);
      top.raw("bandwidth", b.text());
      std::printf(
          "bandwidth: device-to-device %.0f GB/s (read+write), H2D pinned %.1f, D2H pinned %.1f, "
          "H2D pageable %.1f, D2H pageable %.1f GB/s\n",
          bw.deviceToDeviceGBs, bw.hostToDevicePinnedGBs, bw.deviceToHostPinnedGBs,
          bw.hostToDevicePageableGBs, bw.deviceToHostPageableGBs);
    } else {
      std::printf("bandwidth measurement failed: %s\n", measured.message.c_str());
    }
    top.str("device", cuda::DeviceDescription());
  }
#else
  gpuWhy = "built without CUDA";
#endif
  if (!gpu)
    std::printf("no GPU (%s): CPU columns only\n", gpuWhy.c_str());
  else
    std::printf("device: %s\n", gpu->name().c_str());
  top.str("gpu_backend", gpu ? gpu->name() : std::string("none: ") + gpuWhy);

  std::vector<Row> rows;
  std::string casesJson;
  int bestBlasThreads = 0; // from the first case that sweeps
  auto cpu = MakeCpuBackend();
  for (const Case& c : cases) {
    Row row;
    row.name = c.name;
    Json j;
    j.str("case", c.name);
    j.num("subdivisions", c.subdivisions);
    j.num("layers", c.layers);
    double t0 = NowMs();
    BenchScene scene;
    std::string readError;
    if (c.file.empty() || !OrganScene(opt.dataDir + "/" + c.file, scene, readError)) {
      if (!c.file.empty())
        std::printf("%s: %s; using a generated shell of similar size\n", c.name.c_str(),
                    readError.c_str());
      FaceLikeScene shell = MakeFaceLikeScene(c.subdivisions, c.layers, 0.1);
      scene.materials = LayeredMaterials(shell.shell);
      scene.mesh = std::move(shell.shell.mesh);
      scene.constrained = std::move(shell.constrained);
      scene.movable = std::move(shell.movable);
      scene.kept = std::move(shell.kept);
      std::ostringstream d;
      d << "MakeFaceLikeScene(" << c.subdivisions << ", " << c.layers
        << ", 0.1): inner surface fixed, 10 % cap of it moved, outer surface kept; three tissue "
           "bands E = 10/1/3, "
           "nu = 0.45/0.49/0.47 (per cell)";
      scene.source = d.str();
    }
    j.str("mesh", scene.source);
    const TetMesh& mesh = scene.mesh;
    const Materials& materials = scene.materials;
    row.tets = mesh.numTets();
    row.nodes = mesh.numPoints();
    j.num("tets", double(row.tets));
    j.num("nodes", double(row.nodes));
    j.num("scene_ms", NowMs() - t0);
    std::printf("\n== %s: %lld tets, %lld nodes ==\n", c.name.c_str(), row.tets, row.nodes);
    std::fflush(stdout);

    // ---- element stiffness + assembly of the whole mesh's stiffness (identity numbering) ----
    std::vector<int> identity(mesh.numPoints());
    std::iota(identity.begin(), identity.end(), 0);
    t0 = NowMs();
    AssemblyPattern pattern;

    if (!BuildAssemblyPattern(mesh, identity, static_cast<int>(mesh.numPoints()), pattern))
      return 1;
    j.num("pattern_build_ms_cpu", NowMs() - t0);
    row.nnz = pattern.upper.nonZeros();
    j.num("upper_nonzeros", double(row.nnz));
    j.num("gather_entries", double(pattern.packedIndex.size()));

    std::vector<double> cpuKe, cpuAsm, cpuTotal;
    AssemblyPattern cpuPattern = pattern;
    const int repeats = row.tets > 500000 ? std::min(opt.repeats, 10) : opt.repeats;
    for (int r = 0; r < repeats + 1; ++r) {
      ComputeBackend::AssemblyTimings at;
      const double w0 = NowMs();
      if (!cpu->assembleStiffness(mesh, materials, cpuPattern, at))
        return 1;
      const double wall = NowMs() - w0;
      if (r == 0)
        continue; // warm-up
      cpuKe.push_back(at.elementStiffnessMs);
      cpuAsm.push_back(at.assemblyMs);
      cpuTotal.push_back(wall);
    }
    row.cpuKeMs = Median(cpuKe);
    row.cpuAsmMs = Median(cpuAsm);
    Json cj;
    cj.num("repeats", repeats);
    cj.num("element_stiffness_ms_median", row.cpuKeMs);
    cj.num("assembly_ms_median", row.cpuAsmMs);
    cj.num("total_ms_median", Median(cpuTotal));
    j.raw("cpu_assembly", cj.text());

#if FACEPLAN_HAS_CUDA
    if (gpu) {
      AssemblyPattern gpuPattern = pattern;
      cuda::ReleasePatternCache(*gpu);
      std::vector<double> keK, gaK, up, down, wall, withTransfers;
      cuda::AssemblyDetail first;
      Status assembled;
      bool ok = true;
      for (int r = 0; r < repeats + 2 && ok; ++r) {
        std::fill(gpuPattern.upper.valuePtr(),
                  gpuPattern.upper.valuePtr() + gpuPattern.upper.nonZeros(),
                  std::numeric_limits<double>::quiet_NaN());
        ComputeBackend::AssemblyTimings at;
        assembled = gpu->assembleStiffness(mesh, materials, gpuPattern, at);
        ok = assembled.ok;
        cuda::AssemblyDetail d;
        cuda::LastAssemblyDetail(*gpu, d);
        if (r == 0) {
          first = d;
          row.asmDiff =
              RelativeMaxDifference(gpuPattern.upper.valuePtr(), cpuPattern.upper.valuePtr(),
                                    static_cast<size_t>(row.nnz));
          continue;
        }
        if (r == 1)
          continue; // second warm-up (pattern now cached)
        keK.push_back(d.stiffnessKernelMs);
        gaK.push_back(d.gatherKernelMs);
        up.push_back(d.uploadMs);
        down.push_back(d.downloadMs);
        wall.push_back(d.wallMs);
        withTransfers.push_back(d.uploadMs + d.stiffnessKernelMs + d.gatherKernelMs + d.downloadMs);
        row.asmDiff = std::max(row.asmDiff, RelativeMaxDifference(gpuPattern.upper.valuePtr(),
                                                                  cpuPattern.upper.valuePtr(),
                                                                  static_cast<size_t>(row.nnz)));
      }
      if (!ok)
        std::printf("GPU assembly failed: %s\n", assembled.message.c_str());
      cuda::AssemblyDetail last;
      cuda::LastAssemblyDetail(*gpu, last);
      // The same with the transfers straight from/to pageable memory (no staging).
      std::vector<double> pageableWall, pageableDown;
      cuda::SetPinnedTransfers(*gpu, false);
      for (int r = 0; r < repeats && ok; ++r) {
        ComputeBackend::AssemblyTimings at;
        assembled = gpu->assembleStiffness(mesh, materials, gpuPattern, at);
        ok = assembled.ok;
        cuda::AssemblyDetail d;
        cuda::LastAssemblyDetail(*gpu, d);
        pageableWall.push_back(d.wallMs);
        pageableDown.push_back(d.downloadMs);
      }
      cuda::SetPinnedTransfers(*gpu, true);
      row.gpuPageableMs = Median(pageableWall);
      row.gpuKeKernelMs = Median(keK);
      row.gpuGatherKernelMs = Median(gaK);
      std::vector<double> kernelSum(keK.size());
      for (size_t i = 0; i < keK.size(); ++i)
        kernelSum[i] = keK[i] + gaK[i];
      row.gpuKernelMs = Median(kernelSum);
      row.gpuWithTransfersMs = Median(wall);
      row.gpuFirstCallMs = first.wallMs;
      row.floorMs = last.kernelBytes / (deviceBandwidthGBs * 1e9) * 1e3;
      row.fraction = row.floorMs / row.gpuKernelMs;
      Json gj;
      gj.num("repeats", double(keK.size()));
      gj.num("stiffness_kernel_ms_median", row.gpuKeKernelMs);
      gj.num("gather_kernel_ms_median", row.gpuGatherKernelMs);
      gj.num("kernels_ms_median", row.gpuKernelMs);
      gj.num("upload_ms_median", Median(up));
      gj.num("download_ms_median", Median(down));
      gj.num("device_timeline_with_transfers_ms_median", Median(withTransfers));
      gj.num("wall_with_transfers_ms_median", row.gpuWithTransfersMs);
      gj.num("first_call_wall_ms_pattern_upload", first.wallMs);
      gj.num("pageable_transfers_wall_ms_median", row.gpuPageableMs);
      gj.num("pageable_transfers_download_ms_median", Median(pageableDown));
      gj.num("first_call_bytes_uploaded", first.bytesUploaded);
      gj.num("cached_call_bytes_uploaded", last.bytesUploaded);
      gj.num("bytes_downloaded", last.bytesDownloaded);
      gj.num("kernel_bytes_floor", last.kernelBytes);
      gj.num("kernel_floor_ms", row.floorMs);
      gj.num("achieved_fraction_of_bandwidth", row.fraction);
      gj.num("download_floor_ms_pinned", last.bytesDownloaded / (d2hPinnedGBs * 1e9) * 1e3);
      gj.num("download_floor_ms_pageable", last.bytesDownloaded / (d2hPageableGBs * 1e9) * 1e3);
      gj.num("max_relative_difference_vs_cpu", row.asmDiff);
      j.raw("gpu_assembly", gj.text());
    }
#endif
    { AssemblyPattern().upper.swap(pattern.upper); }
    pattern = AssemblyPattern();
    cpuPattern = AssemblyPattern();

    // ---- precompute (dense response) and per-edit update ----
    if (opt.precompute) {
      PrecomputeRequest request;
      request.mesh = mesh;
      request.materials = materials;
      request.sets.constrained = scene.constrained;
      request.sets.movable = scene.movable;
      request.sets.kept = scene.kept;
      request.options.method = SolveMethod::DenseResponse;
      request.options.denseResponseBudgetBytes = 1e12;

      // Core's Precompute() with the CPU backend (cases up to --cpu-precompute-max-tets) and with
      // the CUDA backend (every case).
      std::shared_ptr<const CondensedSystem> coreGpuSystem, coreCpuSystem;
      auto runPrecompute = [&](std::shared_ptr<ComputeBackend> backend,
                               std::shared_ptr<const CondensedSystem>& sys,
                               const char* label) -> double {
        request.options.backend = std::move(backend);
        const double w0 = NowMs();
        const Status s = Precompute(request, sys);
        const double seconds = (NowMs() - w0) / 1e3;
        if (!s.ok) {
          std::printf("%s precompute failed: %s\n", label, s.message.c_str());
          sys.reset();
          return NAN;
        }
        for (const auto& w : s.warnings)
          std::printf("%s precompute warning: %s\n", label, w.c_str());
        const SystemInfo info = Describe(*sys);
        Json pj;
        pj.num("wall_s", seconds);
        pj.str("backend", info.backend);
        pj.str("method", MethodName(info.method));
        pj.num("free_dofs", double(info.freeDofs));
        pj.num("kept_dofs", double(info.keptDofs));
        pj.num("roi_dofs", double(info.roiDofs));
        pj.num("factor_nonzeros", info.factorNonzeros);
        pj.num("response_bytes", info.responseBytes);
        std::printf("%s: %.2f s (%s, %s): ", label, seconds, info.backend.c_str(),
                    MethodName(info.method));
        for (int st = 0; st < kNumStages; ++st) {
          const double ms = info.precomputeTimings.stages[st].ms;
          pj.num(std::string("stage_ms_") + StageName(static_cast<Stage>(st)), ms);
          if (ms > 0)
            std::printf("%s %.0f ms; ", StageName(static_cast<Stage>(st)), ms);
        }
        std::printf("factor nnz %.3g\n", info.factorNonzeros);
        std::printf("  beside the stages: ordering thread %.0f ms (%s), mesh-check thread %.0f ms; "
                    "inside them: "
                    "response probe %.0f ms (%.0f %% of rows), condition estimate %.0f ms\n",
                    info.orderingThreadMs,
                    info.orderedBesideAssembly ? "beside the assembly" : "in line",
                    info.meshChecksThreadMs, info.responseProbeMs,
                    100.0 * info.responseProbeRowFraction, info.conditionEstimateMs);
        pj.num("ordering_thread_ms", info.orderingThreadMs);
        pj.num("mesh_checks_thread_ms", info.meshChecksThreadMs);
        pj.num("response_probe_ms", info.responseProbeMs);
        pj.num("condition_estimate_ms", info.conditionEstimateMs);
        std::fflush(stdout);
        j.raw(label, pj.text());
        return seconds;
      };
      const bool smallEnough = row.tets <= opt.cpuPrecomputeMaxTets;
      if (smallEnough || !gpu)
        row.cpuPrecomputeS = runPrecompute(cpu, coreCpuSystem, "core_precompute_cpu_backend");
#if FACEPLAN_HAS_CUDA
      // Core's Precompute() with the CUDA backend: GPU assembly, CHOLMOD ordering + symbolic
      // analysis on the CPU, numeric factorization and dense response on the GPU (ComputeBackend
      // hook).
      if (gpu) {
        cuda::FactorAndResponseDetail fd;
        const long long callsBefore = cuda::LastFactorAndResponseDetail(*gpu, fd) ? fd.call : 0;
        row.coreGpuPrecomputeS = runPrecompute(gpu, coreGpuSystem, "core_precompute_cuda_backend");
        if (coreGpuSystem && cuda::LastFactorAndResponseDetail(*gpu, fd) && fd.call > callsBefore &&
            fd.succeeded) {
          const cuda::DenseResponseDetail& rd = fd.response;
          const double sweepTflops = rd.flops / ((rd.forwardMs + rd.backwardMs) * 1e-3) / 1e12;
          row.responseResidual = rd.worstRelativeResidual;
          Json pj;
          pj.num("wall_ms", fd.wallMs);
          pj.num("factorize_ms_gpu", fd.factorizeMs);
          pj.num("factor_copy_to_cholmod_ms", fd.factorDownloadMs);
          pj.num("factor_copy_left_after_response_ms", fd.factorDownloadWaitMs);
          pj.num("factor_mark_factorized_ms", fd.markFactorizedMs);
          pj.num("response_wall_ms", rd.wallMs);
          pj.num("response_host_prepare_ms", rd.hostPrepareMs);
          pj.num("response_allocate_ms", rd.allocateMs);
          pj.num("response_upload_ms", rd.uploadMs);
          pj.num("response_host_touch_wait_ms", rd.hostTouchWaitMs);
          pj.num("response_forward_ms", rd.forwardMs);
          pj.num("response_backward_ms", rd.backwardMs);
          pj.num("response_residual_ms", rd.residualMs);
          pj.num("response_extract_ms", rd.extractMs);
          pj.num("response_download_ms", rd.downloadMs);
          pj.num("response_download_wait_ms", rd.downloadWaitMs);
          pj.num("response_sweep_gflops", rd.flops / 1e9);
          pj.num("response_sweep_tflop_per_s", sweepTflops);
          pj.num("supernodes", rd.supernodes);
          pj.num("passes", rd.blocks);
          pj.num("columns_per_pass", rd.columnsPerBlock);
          pj.num("factor_nonzeros", fd.factorNonzeros);
          pj.num("worst_relative_residual", rd.worstRelativeResidual);
          j.raw("core_precompute_cuda_backend_gpu_factor_and_response", pj.text());
          std::printf(
              "  GPU factor + response inside Precompute: %.0f ms = factorize %.0f + response %.0f "
              "ms "
              "(host %.0f, allocate %.0f, upload %.0f, forward %.0f, backward %.0f, residual %.0f, "
              "extract %.0f, download %.0f beside the residual, %.0f of it after; "
              "%d supernodes, %.0f GFLOP at %.2f TFLOP/s, residual %.2e; host pages %.0f ms after "
              "the "
              "sweeps); beside the response the copy to CHOLMOD %.0f ms and its trailing block "
              "%.0f ms, %.0f ms of "
              "them left after\n",
              fd.wallMs, fd.factorizeMs, rd.wallMs, rd.hostPrepareMs, rd.allocateMs, rd.uploadMs,
              rd.forwardMs, rd.backwardMs, rd.residualMs, rd.extractMs, rd.downloadMs,
              rd.downloadWaitMs, rd.supernodes, rd.flops / 1e9, sweepTflops,
              rd.worstRelativeResidual, rd.hostTouchWaitMs, fd.factorDownloadMs,
              fd.markFactorizedMs, fd.factorDownloadWaitMs);
          std::fflush(stdout);
        } else if (coreGpuSystem) {
          std::printf("  the CUDA backend's factor/response hook did not run (CPU fallback: see "
                      "warnings)\n");
        }
        // CPU factorization of the same matrix against the OpenBLAS thread count.
        if (coreGpuSystem && opt.blasSweep && row.tets >= 100000 && BlasThreadSetter()) {
          std::vector<int> counts;
          if (bestBlasThreads > 0)
            counts = {bestBlasThreads};
          else
            counts = {16, 8, 4, 2, 1};
          Json sj;
          double best = INFINITY;
          for (int threads : counts) {
            BlasThreadSetter()(threads);
            cuda::SupernodalCholesky cpuFactor;
            const bool fok = cpuFactor.factor(coreGpuSystem->kff).ok;
            std::printf("CPU CHOLMOD factorization with %2d OpenBLAS threads: analyze %.0f ms, "
                        "factorize %.0f ms%s\n",
                        threads, cpuFactor.analyzeMs(), cpuFactor.factorizeMs(),
                        fok ? "" : " FAILED");
            std::fflush(stdout);
            sj.num("threads_" + std::to_string(threads) + "_factorize_ms", cpuFactor.factorizeMs());
            if (fok && cpuFactor.factorizeMs() < best) {
              best = cpuFactor.factorizeMs();
              if (counts.size() > 1)
                bestBlasThreads = threads;
            }
          }
          BlasThreadSetter()(static_cast<int>(std::thread::hardware_concurrency()));
          j.raw("cpu_factorization_vs_blas_threads", sj.text());
        }
        if (coreGpuSystem && coreCpuSystem &&
            coreCpuSystem->response.size() == coreGpuSystem->response.size() &&
            coreGpuSystem->response.size() > 0) {
          row.responseDiff =
              RelativeMaxDifference(coreGpuSystem->response.data(), coreCpuSystem->response.data(),
                                    static_cast<size_t>(coreGpuSystem->response.size()));
          j.num("cuda_backend_response_vs_cpu_backend_response_max_relative_difference",
                row.responseDiff);
        }
      }
#endif
      ResponseOperator* gpuOp = coreGpuSystem && coreGpuSystem->responseOperator
                                    ? coreGpuSystem->responseOperator.get()
                                    : nullptr;

      // Per-edit: GPU operator vs CPU GEMV on the same response.
      const Eigen::MatrixXd* response = gpuOp           ? &coreGpuSystem->response
                                        : coreCpuSystem ? &coreCpuSystem->response
                                                        : nullptr;
      if (response && response->size() > 0) {
        row.keptDofs = response->rows();
        row.roiDofs = response->cols();
        std::mt19937 rng(7);
        std::normal_distribution<double> normal(0.0, 0.5);
        std::vector<Eigen::VectorXd> edits(8);
        for (auto& v : edits) {
          v.resize(response->cols());
          for (Eigen::Index i = 0; i < v.size(); ++i)
            v[i] = normal(rng);
        }
        std::unique_ptr<ResponseOperator> cpuOp;
        if (!cpu->makeResponseOperator(*response, cpuOp))
          return 1;
        std::vector<Eigen::VectorXd> cpuOut(edits.size());
        std::vector<double> cpuMs;
        double spent = 0.0;
        for (int r = 0; r < opt.editRepeats + 1; ++r) {
          const auto& roi = edits[r % edits.size()];
          Eigen::VectorXd kept;
          const double w0 = NowMs();
          if (!cpuOp->apply(roi, kept))
            return 1;
          const double ms = NowMs() - w0;
          if (r < static_cast<int>(edits.size()))
            cpuOut[r] = kept;
          if (r == 0)
            continue;
          cpuMs.push_back(ms);
          spent += ms;
          if (spent > opt.cpuEditBudgetMs && r >= static_cast<int>(edits.size()) &&
              cpuMs.size() >= 5)
            break;
        }
        row.cpuEditMs = Median(cpuMs);
        row.cpuEditRepeats = static_cast<int>(cpuMs.size());
        Json ej;
        ej.num("kept_dofs", double(row.keptDofs));
        ej.num("roi_dofs", double(row.roiDofs));
        ej.num("response_bytes", 8.0 * double(response->size()));
        ej.num("cpu_apply_ms_median", row.cpuEditMs);
        ej.num("cpu_repeats", row.cpuEditRepeats);
        if (gpuOp) {
          std::vector<double> gpuMs;
          double worst = 0.0;
          Status applied;
          bool ok = true;
          for (int r = 0; r < opt.editRepeats + 3 && ok; ++r) {
            const auto& roi = edits[r % edits.size()];
            Eigen::VectorXd kept;
            const double w0 = NowMs();
            applied = gpuOp->apply(roi, kept);
            ok = applied.ok;
            const double ms = NowMs() - w0;
            if (!ok)
              break;
            if (r < static_cast<int>(edits.size()))
              worst = std::max(worst,
                               RelativeMaxDifference(kept.data(), cpuOut[r].data(), kept.size()));
            if (r >= 3)
              gpuMs.push_back(ms);
          }
          if (!ok)
            std::printf("GPU apply failed: %s\n", applied.message.c_str());
          row.gpuEditMs = Median(gpuMs);
          row.gpuEditRepeats = static_cast<int>(gpuMs.size());
          row.editDiff = worst;
          row.editFloorMs = 8.0 * double(response->size()) / (deviceBandwidthGBs * 1e9) * 1e3;
          ej.num("gpu_apply_ms_median", row.gpuEditMs);
          ej.num("gpu_apply_ms_min",
                 gpuMs.empty() ? NAN : *std::min_element(gpuMs.begin(), gpuMs.end()));
          ej.num("gpu_repeats", row.gpuEditRepeats);
          ej.num("gpu_apply_floor_ms_response_read_once", row.editFloorMs);
          ej.num("max_relative_difference_vs_cpu", row.editDiff);
        }
        // End to end: Core's Solve with the CUDA backend's operator (smaller cases).
        if (coreGpuSystem) {
          SolveInput input;
          input.movableDisplacement.resize(static_cast<Eigen::Index>(scene.movable.size()), 3);
          for (Eigen::Index i = 0; i < input.movableDisplacement.size(); ++i)
            input.movableDisplacement.data()[i] = normal(rng);
          std::vector<double> solveMs;
          SolveResult cpuResult;
          if (coreCpuSystem)
            Solve(*coreCpuSystem, input, cpuResult);
          for (int r = 0; r < opt.editRepeats + 3; ++r) {
            SolveResult result;
            const double w0 = NowMs();
            const Status s = Solve(*coreGpuSystem, input, result);
            const double ms = NowMs() - w0;
            if (!s.ok) {
              std::printf("Solve failed: %s\n", s.message.c_str());
              break;
            }
            if (r == 0 && coreCpuSystem)
              row.solveDiff = RelativeMaxDifference(
                  result.keptDisplacement.data(), cpuResult.keptDisplacement.data(),
                  static_cast<size_t>(cpuResult.keptDisplacement.size()));
            if (r >= 3)
              solveMs.push_back(ms);
          }
          row.gpuSolveMs = Median(solveMs);
          ej.num("core_solve_cuda_backend_ms_median", row.gpuSolveMs);
          ej.num("core_solve_cuda_vs_cpu_backend_max_relative_difference", row.solveDiff);
        }
        j.raw("per_edit", ej.text());
      }
      j.num("core_precompute_cuda_backend_s", row.coreGpuPrecomputeS);
      j.num("core_precompute_cpu_backend_s", row.cpuPrecomputeS);
    }
    rows.push_back(row);
    if (!casesJson.empty())
      casesJson += ",\n  ";
    casesJson += j.text();
    std::printf("assembly: CPU Ke %.3f + asm %.3f ms | GPU kernels %.3f ms (Ke %.3f, gather %.3f), "
                "with transfers %.3f ms, "
                "floor %.3f ms (%.0f%%), diff %.2e\n",
                row.cpuKeMs, row.cpuAsmMs, row.gpuKernelMs, row.gpuKeKernelMs,
                row.gpuGatherKernelMs, row.gpuWithTransfersMs, row.floorMs, 100 * row.fraction,
                row.asmDiff);
    if (row.keptDofs)
      std::printf(
          "per edit (%lld x %lld): CPU %.4f ms, GPU apply %.4f ms, GPU Solve %.4f ms, diff %.2e\n",
          row.keptDofs, row.roiDofs, row.cpuEditMs, row.gpuEditMs, row.gpuSolveMs, row.editDiff);
    std::fflush(stdout);
  }

  if (!opt.out.empty()) {
    std::ofstream out(opt.out);
    out << "{\"meta\": " << top.text() << ",\n \"cases\": [\n  " << casesJson << "\n]}\n";
    std::printf("\nwrote %s\n", opt.out.c_str());
  }

  std::printf("\nElement stiffness + assembly (ms, medians; GPU with transfers = upload of "
              "points/materials + kernels + "
              "download of values, pattern cached)\n");
  std::printf("%-9s %9s %10s | %8s %8s %8s | %8s %8s %8s %8s %8s %8s %9s %6s %9s\n", "case", "tets",
              "nnz(U)", "CPU Ke", "CPU asm", "CPU sum", "GPU Ke", "GPU gath", "GPU kern",
              "GPU+xfer", "pageable", "1st call", "floor", "frac", "rel diff");
  for (const Row& r : rows)
    std::printf("%-9s %9lld %10lld | %8.3f %8.3f %8.3f | %8.4f %8.4f %8.4f %8.3f %8.3f %8.3f %9.4f "
                "%5.0f%% %9.2e\n",
                r.name.c_str(), r.tets, r.nnz, r.cpuKeMs, r.cpuAsmMs, r.cpuKeMs + r.cpuAsmMs,
                r.gpuKeKernelMs, r.gpuGatherKernelMs, r.gpuKernelMs, r.gpuWithTransfersMs,
                r.gpuPageableMs, r.gpuFirstCallMs, r.floorMs, 100 * r.fraction, r.asmDiff);
  std::printf("\nPer-edit update (ms, medians; GPU = upload ROI vector + cuBLAS DGEMV + download "
              "kept vector)\n");
  std::printf("%-9s %9s %8s %7s | %9s(%4s) %9s(%4s) %9s %9s | %10s %9s\n", "case", "tets", "kept",
              "roi", "CPU edit", "n", "GPU edit", "n", "floor", "rel diff", "Core Solve",
              "rel diff");
  for (const Row& r : rows)
    std::printf("%-9s %9lld %8lld %7lld | %9.4f(%4d) %9.4f(%4d) %9.4f %9.2e | %10.4f %9.2e\n",
                r.name.c_str(), r.tets, r.keptDofs, r.roiDofs, r.cpuEditMs, r.cpuEditRepeats,
                r.gpuEditMs, r.gpuEditRepeats, r.editFloorMs, r.editDiff, r.gpuSolveMs,
                r.solveDiff);
  std::printf("\nPrecompute, dense response (s): Core Precompute() with the CUDA backend (GPU "
              "assembly, CPU "
              "ordering, GPU factorization + response) and with the CPU backend\n");
  std::printf("%-9s %9s | %12s %12s | %12s %12s\n", "case", "tets", "Core+CUDA", "Core CPU",
              "residual", "resp diff");
  for (const Row& r : rows)
    std::printf("%-9s %9lld | %12.2f %12.2f | %12.2e %12.2e\n", r.name.c_str(), r.tets,
                r.coreGpuPrecomputeS, r.cpuPrecomputeS, r.responseResidual, r.responseDiff);
  return 0;
}
