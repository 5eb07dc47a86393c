// SPDX-License-Identifier: BSD-3-Clause
#include "CudaBackend.h"

#include "Common/ParallelFor.h"
#include "Common/StageTimings.h"
#include "CudaCheck.h"
#include "CudaDenseResponse.h"
#include "CudaInternal.h"
#include "CudaKernels.h"
#include "CudaLargeDeformation.h"
#include "Element/ElementStiffness.h"

#include <algorithm>
#include <condition_variable>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <mutex>
#include <sstream>
#include <system_error>
#include <thread>
#include <vector>

#ifndef FACEPLAN_CUDA_ARCHITECTURES
#define FACEPLAN_CUDA_ARCHITECTURES "90"
#endif

namespace faceplan::cuda {

using detail::CudaResponse;
using detail::DeviceArray;
using detail::InitDevice;
using detail::ParallelCopy;
using detail::PinnedArray;

namespace {

// Cheap identity check of a large index array: its size and up to 2048 evenly spread entries.
// Together with the addresses and sizes it decides whether a cached pattern is the same one.
std::uint64_t Fingerprint(const int* data, size_t count, std::uint64_t seed) {
  std::uint64_t h = 1469598103934665603ull ^ seed ^ (static_cast<std::uint64_t>(count) << 17);
  auto mix = [&h](std::uint32_t v) { h = (h ^ v) * 1099511628211ull; };
  if (count == 0)
    return h;
  const size_t samples = std::min<size_t>(count, 2048);
  for (size_t s = 0; s < samples; ++s) {
    const size_t i = samples == count ? s : s * (count - 1) / (samples - 1);
    mix(static_cast<std::uint32_t>(data[i]));
  }
  return h;
}

struct PatternKey {
  const void* pattern = nullptr;
  const int* gatherStart = nullptr;
  const int* packedIndex = nullptr;
  const int* tets = nullptr;
  size_t gatherCount = 0, packedCount = 0;
  long long numTets = 0;
  std::uint64_t fingerprint = 0;
  bool operator==(const PatternKey& o) const {
    return pattern == o.pattern && gatherStart == o.gatherStart && packedIndex == o.packedIndex &&
           tets == o.tets && gatherCount == o.gatherCount && packedCount == o.packedCount &&
           numTets == o.numTets && fingerprint == o.fingerprint;
  }
};

class CudaBackendImpl final : public ComputeBackend {
public:
  ~CudaBackendImpl() override {
    for (cudaEvent_t& e : events_)
      if (e)
        cudaEventDestroy(e);
    for (cudaEvent_t& e : chunkDone_)
      if (e)
        cudaEventDestroy(e);
    if (stream_)
      cudaStreamDestroy(stream_);
  }

  bool init(std::string& error) {
    if (!InitDevice(error))
      return false;
    cudaDeviceProp prop{};
    FP_CUDA_TRY(cudaGetDeviceProperties(&prop, 0));
    name_ = std::string("CUDA (") + prop.name + ")";
    FP_CUDA_TRY(cudaStreamCreateWithFlags(&stream_, cudaStreamNonBlocking));
    for (cudaEvent_t& e : events_)
      FP_CUDA_TRY(cudaEventCreate(&e));
    for (cudaEvent_t& e : chunkDone_)
      FP_CUDA_TRY(cudaEventCreateWithFlags(&e, cudaEventDisableTiming));
    return true;
  }

  std::string name() const override { return name_; }

  Status assembleStiffness(const TetMesh& mesh, const Materials& materials,
                           AssemblyPattern& pattern, AssemblyTimings& timings) override {
    std::lock_guard<std::mutex> lock(mutex_);
    StageClock clock;
    AssemblyDetail detail;
    std::string error;
    const bool ok = assemble(mesh, materials, pattern, timings, detail, error);
    detail.wallMs = clock.elapsedMs();
    if (ok)
      last_ = detail;
    if (!ok)
      releasePattern(); // a failed call leaves nothing half-cached
    return ok ? Status::Ok() : Status::Error(error);
  }

  Status makeResponseOperator(const Eigen::MatrixXd& response,
                              std::unique_ptr<ResponseOperator>& op) override {
    auto device = std::make_unique<CudaResponse>();
    std::string error;
    if (!device->init(response, error))
      return Status::Error(error);
    op = std::move(device);
    return Status::Ok();
  }

  // The large-deformation solve's steps (CudaLargeDeformation.h): objects of their own, with their
  // own streams, not under mutex_.
  Status makeHyperelasticForces(const HyperelasticCells& cells,
                                std::unique_ptr<HyperelasticForces>& forces) override {
    return detail::MakeCudaHyperelasticForces(cells, forces);
  }
  Status makeFactorOnDevice(const SinglePrecisionFactor& factor, const SparseMatrix& upper,
                            std::unique_ptr<FactorOnDevice>& device) override {
    return detail::MakeCudaFactorOnDevice(factor, upper, device);
  }

  // Numeric factorization and dense response on the GPU (CudaDenseResponse.h). Not under mutex_:
  // it uses its own stream and handles, and assemblies may run meanwhile.
  bool providesFactorAndResponse() const override { return true; }
  Status factorAndBuildResponse(const SparseMatrix& kffUpper, const SparseMatrix& kfr,
                                Eigen::Index keptDofs, CholmodFactor& factor,
                                Eigen::MatrixXd& response, std::unique_ptr<ResponseOperator>& op,
                                FactorResponseReport& report) override {
    FactorAndResponseDetail detail;
    const Status status =
        FactorAndBuildResponse(kffUpper, kfr, keptDofs, factor, response, op, detail);
    // The copy into CHOLMOD runs beside the response: only what was left of it after the response
    // counts as factorization time.
    report.factorizationMs = detail.factorizeMs + detail.factorDownloadWaitMs;
    report.worstRelativeResidual = detail.response.worstRelativeResidual;
    std::ostringstream line;
    line.precision(3);
    line << "GPU numeric factorization " << detail.factorizeMs << " ms (+ "
         << detail.factorDownloadMs << " ms copy into CHOLMOD beside the response, "
         << detail.factorDownloadWaitMs << " ms of it after), GPU response "
         << detail.response.wallMs << " ms (" << detail.response.supernodes << " supernodes, "
         << detail.response.blocks << " pass(es), residual "
         << detail.response.worstRelativeResidual << ")";
    report.detail = line.str();
    std::lock_guard<std::mutex> lock(factorMutex_);
    detail.succeeded = status.ok;
    detail.call = ++factorCalls_;
    lastFactor_ = detail;
    return status;
  }
  bool lastFactorDetail(FactorAndResponseDetail& detail) const {
    std::lock_guard<std::mutex> lock(factorMutex_);
    detail = lastFactor_;
    return factorCalls_ > 0;
  }

  AssemblyDetail lastDetail() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return last_;
  }

private:
  void releasePattern() {
    key_ = PatternKey{};
    cachedValid_ = false;
    tets_.release();
    gatherStart_.release();
    packedIndex_.release();
  }

public:
  void releaseAll() {
    std::lock_guard<std::mutex> lock(mutex_);
    releasePattern();
    points_.release();
    youngs_.release();
    poisson_.release();
    packed_.release();
    values_.release();
  }
  void setPinnedTransfers(bool on) {
    std::lock_guard<std::mutex> lock(mutex_);
    pinnedTransfers_ = on;
  }

private:
  // One assembly's sizes and sources, handed from stage to stage.
  struct AssemblyCall {
    long long m = 0, n = 0, nnz = 0; // cells, points, nonzeros of the upper triangle
    size_t nE = 0, nNu = 0;          // Young's moduli and Poisson ratios (1 or one per cell)
    size_t packedCount = 0;
    size_t tetBytes = 0, gatherBytes = 0, indexBytes = 0, pointBytes = 0, elementBytes = 0,
           valueBytes = 0;
    PatternKey key;
    bool reuse = false; // the cells and gather map on the device are this pattern's
    const double* srcPoints = nullptr;
    const double* srcYoungs = nullptr;
    const double* srcPoisson = nullptr;
    double* dstValues = nullptr; // where the values come back (the staging buffer or the matrix)
    double uploaded = 0.0;       // bytes
  };

  // The element stiffness and gather assembly on the GPU, in stages: check the inputs, find
  // whether the cached pattern is this one, size the device buffers, stage and upload, run the
  // kernels, copy the values back, and report.
  bool assemble(const TetMesh& mesh, const Materials& materials, AssemblyPattern& pattern,
                AssemblyTimings& timings, AssemblyDetail& detail, std::string& error) {
    AssemblyCall call;
    bool empty = false;
    if (!checkAssemblyInputs(mesh, materials, pattern, call, empty, error))
      return false;
    if (empty) {
      std::fill(pattern.upper.valuePtr(), pattern.upper.valuePtr() + call.nnz, 0.0);
      timings = AssemblyTimings{};
      return true;
    }
    FP_CUDA_TRY(cudaSetDevice(0));
    identifyPattern(mesh, pattern, call);
    if (!checkCellIndices(mesh, call, error) || !allocateBuffers(call, error) ||
        !stageInputs(mesh, materials, pattern, call, error) ||
        !uploadInputs(mesh, pattern, call, error) || !runKernels(call, error) ||
        !downloadValues(pattern, call, error) || !reportAssembly(call, timings, detail, error))
      return false;
    key_ = call.key;
    cachedValid_ = true;
    return true;
  }

  // Sizes and materials against the pattern; `empty` when there is nothing to assemble.
  static bool checkAssemblyInputs(const TetMesh& mesh, const Materials& materials,
                                  const AssemblyPattern& pattern, AssemblyCall& call, bool& empty,
                                  std::string& error) {
    call.m = mesh.numTets();
    call.n = mesh.numPoints();
    call.nnz = pattern.upper.nonZeros();
    if (static_cast<long long>(pattern.gatherStart.size()) != call.nnz + 1) {
      error = "assembly pattern: gatherStart does not match the number of nonzeros";
      return false;
    }
    if (call.m > std::numeric_limits<int>::max() / kPackedElementSize) {
      error = "mesh too large for 32-bit packed indices";
      return false;
    }
    call.nE = materials.youngsModulus.size();
    call.nNu = materials.poissonRatio.size();
    if ((call.nE != 1 && call.nE != static_cast<size_t>(call.m)) ||
        (call.nNu != 1 && call.nNu != static_cast<size_t>(call.m))) {
      error = "materials: Young's modulus and Poisson ratio need one value or one per cell";
      return false;
    }
    if (static_cast<long long>(pattern.packedIndex.size()) != pattern.gatherStart.back()) {
      error = "assembly pattern: packedIndex does not match gatherStart";
      return false;
    }
    empty = call.m == 0 || call.nnz == 0;
    return true;
  }

  // The pattern's identity (PatternKey) and the call's buffer sizes.
  void identifyPattern(const TetMesh& mesh, const AssemblyPattern& pattern,
                       AssemblyCall& call) const {
    PatternKey& key = call.key;
    key.pattern = &pattern;
    key.gatherStart = pattern.gatherStart.data();
    key.packedIndex = pattern.packedIndex.data();
    key.tets = mesh.tets.data();
    key.gatherCount = pattern.gatherStart.size();
    key.packedCount = pattern.packedIndex.size();
    key.numTets = call.m;
    key.fingerprint = Fingerprint(pattern.gatherStart.data(), pattern.gatherStart.size(), 1) ^
                      Fingerprint(pattern.packedIndex.data(), pattern.packedIndex.size(), 2) ^
                      Fingerprint(mesh.tets.data(), static_cast<size_t>(4 * call.m), 3);
    call.reuse = cachedValid_ && key == key_;

    call.packedCount = pattern.packedIndex.size();
    call.tetBytes = sizeof(int) * 4 * static_cast<size_t>(call.m);
    call.gatherBytes = sizeof(int) * pattern.gatherStart.size();
    call.indexBytes = sizeof(int) * std::max<size_t>(call.packedCount, 1);
    call.pointBytes = sizeof(double) * 3 * static_cast<size_t>(call.n);
    call.elementBytes = sizeof(double) * kPackedElementSize * static_cast<size_t>(call.m);
    call.valueBytes = sizeof(double) * static_cast<size_t>(call.nnz);
  }

  // Cell indices are checked once per pattern: a bad index would fault the kernel.
  bool checkCellIndices(const TetMesh& mesh, const AssemblyCall& call, std::string& error) {
    if (!call.reuse) {
      releasePattern();
      const int* t = mesh.tets.data();
      int maxNode = -1;
      for (size_t i = 0; i < 4 * static_cast<size_t>(call.m); ++i) {
        if (t[i] < 0) {
          error = "mesh: negative node index in a cell";
          return false;
        }
        maxNode = std::max(maxNode, t[i]);
      }
      maxNode_ = maxNode;
    }
    if (maxNode_ >= call.n) {
      error = "mesh: a cell refers to a node beyond the point array";
      return false;
    }
    return true;
  }

  bool allocateBuffers(const AssemblyCall& call, std::string& error) {
    return tets_.ensure(call.tetBytes, error) && gatherStart_.ensure(call.gatherBytes, error) &&
           packedIndex_.ensure(call.indexBytes, error) && points_.ensure(call.pointBytes, error) &&
           youngs_.ensure(sizeof(double) * call.nE, error) &&
           poisson_.ensure(sizeof(double) * call.nNu, error) &&
           packed_.ensure(call.elementBytes, error) && values_.ensure(call.valueBytes, error);
  }

  // Points and materials go through page-locked staging (a parallel host copy, then a copy at
  // full link speed) unless pinned transfers are off; likewise the values on the way back.
  bool stageInputs(const TetMesh& mesh, const Materials& materials, AssemblyPattern& pattern,
                   AssemblyCall& call, std::string& error) {
    call.srcPoints = mesh.points.data();
    call.srcYoungs = materials.youngsModulus.data();
    call.srcPoisson = materials.poissonRatio.data();
    if (pinnedTransfers_) {
      const size_t inBytes = call.pointBytes + sizeof(double) * (call.nE + call.nNu);
      if (!stageIn_.ensure(inBytes, error) || !stageOut_.ensure(call.valueBytes, error))
        return false;
      double* stage = stageIn_.as<double>();
      ParallelCopy(stage, call.srcPoints, call.pointBytes);
      ParallelCopy(stage + 3 * call.n, call.srcYoungs, sizeof(double) * call.nE);
      ParallelCopy(stage + 3 * call.n + call.nE, call.srcPoisson, sizeof(double) * call.nNu);
      call.srcPoints = stage;
      call.srcYoungs = stage + 3 * call.n;
      call.srcPoisson = stage + 3 * call.n + call.nE;
    }
    call.dstValues = pinnedTransfers_ ? stageOut_.as<double>() : pattern.upper.valuePtr();
    return true;
  }

  // Cells and gather map (when not cached), points and materials; between events 0 and 1.
  bool uploadInputs(const TetMesh& mesh, const AssemblyPattern& pattern, AssemblyCall& call,
                    std::string& error) {
    FP_CUDA_TRY(cudaEventRecord(events_[0], stream_));
    if (!call.reuse) {
      FP_CUDA_TRY(cudaMemcpyAsync(tets_.as<int>(), mesh.tets.data(), call.tetBytes,
                                  cudaMemcpyHostToDevice, stream_));
      FP_CUDA_TRY(cudaMemcpyAsync(gatherStart_.as<int>(), pattern.gatherStart.data(),
                                  call.gatherBytes, cudaMemcpyHostToDevice, stream_));
      if (call.packedCount > 0)
        FP_CUDA_TRY(cudaMemcpyAsync(packedIndex_.as<int>(), pattern.packedIndex.data(),
                                    sizeof(int) * call.packedCount, cudaMemcpyHostToDevice,
                                    stream_));
      call.uploaded +=
          static_cast<double>(call.tetBytes + call.gatherBytes + sizeof(int) * call.packedCount);
    }
    FP_CUDA_TRY(cudaMemcpyAsync(points_.as<double>(), call.srcPoints, call.pointBytes,
                                cudaMemcpyHostToDevice, stream_));
    FP_CUDA_TRY(cudaMemcpyAsync(youngs_.as<double>(), call.srcYoungs, sizeof(double) * call.nE,
                                cudaMemcpyHostToDevice, stream_));
    FP_CUDA_TRY(cudaMemcpyAsync(poisson_.as<double>(), call.srcPoisson, sizeof(double) * call.nNu,
                                cudaMemcpyHostToDevice, stream_));
    call.uploaded += static_cast<double>(call.pointBytes + sizeof(double) * (call.nE + call.nNu));
    FP_CUDA_TRY(cudaEventRecord(events_[1], stream_));
    return true;
  }

  // Element stiffness (events 1 to 2), then the gather into the matrix's values (2 to 3).
  bool runKernels(const AssemblyCall& call, std::string& error) {
    FP_CUDA_TRY(detail::LaunchElementStiffness(
        points_.as<double>(), tets_.as<int>(), call.m, youngs_.as<double>(), call.nE == 1 ? 0 : 1,
        poisson_.as<double>(), call.nNu == 1 ? 0 : 1, packed_.as<double>(), stream_));
    FP_CUDA_TRY(cudaEventRecord(events_[2], stream_));
    FP_CUDA_TRY(detail::LaunchGather(gatherStart_.as<int>(), packedIndex_.as<int>(),
                                     packed_.as<double>(), static_cast<int>(call.nnz),
                                     values_.as<double>(), stream_));
    FP_CUDA_TRY(cudaEventRecord(events_[3], stream_));
    return true;
  }

  // The values come back in a few chunks, each copied out of the staging buffer while the next
  // one is still on the link (events 3 to 4).
  bool downloadValues(AssemblyPattern& pattern, const AssemblyCall& call, std::string& error) {
    const size_t valueBytes = call.valueBytes;
    const int chunks =
        pinnedTransfers_ ? static_cast<int>(std::min<size_t>(4, 1 + valueBytes / (size_t(8) << 20)))
                         : 1;
    const size_t chunkBytes = (valueBytes / chunks + 7) & ~size_t(7);
    for (int c = 0; c < chunks; ++c) {
      const size_t from = std::min(valueBytes, c * chunkBytes),
                   to = std::min(valueBytes, (c + 1) * chunkBytes);
      if (to > from)
        FP_CUDA_TRY(cudaMemcpyAsync(reinterpret_cast<char*>(call.dstValues) + from,
                                    reinterpret_cast<const char*>(values_.as<double>()) + from,
                                    to - from, cudaMemcpyDeviceToHost, stream_));
      FP_CUDA_TRY(cudaEventRecord(chunkDone_[c], stream_));
    }
    FP_CUDA_TRY(cudaEventRecord(events_[4], stream_));
    if (pinnedTransfers_) {
      for (int c = 0; c < chunks; ++c) {
        FP_CUDA_TRY(cudaEventSynchronize(chunkDone_[c]));
        const size_t from = std::min(valueBytes, c * chunkBytes),
                     to = std::min(valueBytes, (c + 1) * chunkBytes);
        if (to > from)
          ParallelCopy(reinterpret_cast<char*>(pattern.upper.valuePtr()) + from,
                       reinterpret_cast<const char*>(call.dstValues) + from, to - from);
      }
    }
    FP_CUDA_TRY(cudaStreamSynchronize(stream_));
    return true;
  }

  // Device times between the events, bytes moved, and the stage times Core books.
  bool reportAssembly(const AssemblyCall& call, AssemblyTimings& timings, AssemblyDetail& detail,
                      std::string& error) const {
    float ms[4] = {0, 0, 0, 0};
    for (int i = 0; i < 4; ++i)
      FP_CUDA_TRY(cudaEventElapsedTime(&ms[i], events_[i], events_[i + 1]));
    detail.uploadMs = ms[0];
    detail.stiffnessKernelMs = ms[1];
    detail.gatherKernelMs = ms[2];
    detail.downloadMs = ms[3];
    detail.patternReused = call.reuse;
    detail.bytesUploaded = call.uploaded;
    detail.bytesDownloaded = static_cast<double>(call.valueBytes);
    detail.kernelBytes =
        static_cast<double>(call.tetBytes) + static_cast<double>(call.pointBytes) +
        sizeof(double) * static_cast<double>(call.nE + call.nNu) +
        2.0 * static_cast<double>(call.elementBytes) + // packed: written, read back
        sizeof(int) * static_cast<double>(call.packedCount) +
        static_cast<double>(call.gatherBytes) + static_cast<double>(call.valueBytes);
    timings.elementStiffnessMs = ms[0] + ms[1];
    timings.assemblyMs = ms[2] + ms[3];
    return true;
  }

  mutable std::mutex mutex_;
  std::string name_ = "CUDA";
  cudaStream_t stream_ = nullptr;
  cudaEvent_t events_[5] = {nullptr, nullptr, nullptr, nullptr, nullptr};
  cudaEvent_t chunkDone_[4] = {nullptr, nullptr, nullptr, nullptr};
  // Cached per pattern: cells, gather map.
  PatternKey key_;
  bool cachedValid_ = false;
  int maxNode_ = -1;
  DeviceArray tets_, gatherStart_, packedIndex_;
  // Per call: points, materials, packed element matrices, assembled values.
  DeviceArray points_, youngs_, poisson_, packed_, values_;
  PinnedArray stageIn_, stageOut_;
  bool pinnedTransfers_ = true;
  AssemblyDetail last_;
  mutable std::mutex factorMutex_;
  FactorAndResponseDetail lastFactor_;
  long long factorCalls_ = 0;
};

} // namespace

namespace detail {

bool InitDevice(std::string& error) {
  int count = 0;
  const cudaError_t status = cudaGetDeviceCount(&count);
  if (status != cudaSuccess) {
    cudaGetLastError(); // not sticky; clear it
    error = std::string("no usable CUDA device: ") + cudaGetErrorString(status);
    return false;
  }
  if (count == 0) {
    error = "no CUDA device is present";
    return false;
  }
  FP_CUDA_TRY(cudaSetDevice(0));
  const cudaError_t image = detail::CheckKernelImage();
  if (image != cudaSuccess) {
    cudaGetLastError();
    cudaDeviceProp prop{};
    cudaGetDeviceProperties(&prop, 0);
    std::ostringstream why;
    why << "the CUDA kernels were built for CUDA architecture " << FACEPLAN_CUDA_ARCHITECTURES
        << " and cannot run on " << prop.name << " (sm_" << prop.major << prop.minor
        << "): " << cudaGetErrorString(image)
        << "; reconfigure with -DCMAKE_CUDA_ARCHITECTURES=" << prop.major << prop.minor;
    error = why.str();
    return false;
  }
  return true;
}

namespace {

// Page-locked staging buffers, kept for the process once made: allocating them per copy would
// cost about as much as the copy (Cuda/tools/host_transfer_probe). A copy takes a set and gives it
// back; two copies at once (the factor's and the response's) take two sets.
constexpr size_t kStageBytes = size_t(64) << 20;
constexpr int kStageBuffers = 3;
struct StagingSet {
  PinnedArray buffer[kStageBuffers];
  cudaEvent_t copied[kStageBuffers] = {};
  ~StagingSet() {
    for (cudaEvent_t e : copied)
      if (e)
        cudaEventDestroy(e);
  }
};
std::mutex stagingMutex;
std::vector<std::unique_ptr<StagingSet>> idleStaging;

std::unique_ptr<StagingSet> TakeStaging(std::string& error) {
  {
    std::lock_guard<std::mutex> lock(stagingMutex);
    if (!idleStaging.empty()) {
      std::unique_ptr<StagingSet> set = std::move(idleStaging.back());
      idleStaging.pop_back();
      return set;
    }
  }
  auto set = std::make_unique<StagingSet>();
  for (int b = 0; b < kStageBuffers; ++b) {
    if (!set->buffer[b].ensure(kStageBytes, error))
      return nullptr;
    if (cudaEventCreateWithFlags(&set->copied[b], cudaEventDisableTiming) != cudaSuccess) {
      error = "could not create an event for a staged copy";
      return nullptr;
    }
  }
  return set;
}

void GiveStaging(std::unique_ptr<StagingSet> set) {
  std::lock_guard<std::mutex> lock(stagingMutex);
  idleStaging.push_back(std::move(set));
}

} // namespace

bool DownloadLarge(void* dst, const void* src, size_t bytes, cudaStream_t stream,
                   std::string& error) {
  if (bytes == 0)
    return true;
  std::unique_ptr<StagingSet> set = TakeStaging(error);
  if (!set)
    return false;
  // A pipeline: this thread queues each 64 MB chunk's device-to-host copy into a free staging
  // buffer; `threads` host threads, started once, each copy their slice of every chunk out of it
  // as soon as its copy has arrived. Three buffers keep the link busy while the host copies.
  const size_t chunks = (bytes + kStageBytes - 1) / kStageBytes;
  const int threads =
      static_cast<int>(std::min<size_t>(WorkerThreads(16), std::max<size_t>(1, bytes >> 22)));
  std::mutex mutex;
  std::condition_variable changed;
  size_t queued = 0;                   // chunks whose copy (and event) are queued
  int slicesDone[kStageBuffers] = {0}; // of the chunk now in each buffer
  bool failed = false;
  std::string why;                           // the first failure, under `mutex`
  auto fail = [&](const std::string& what) { // with `mutex` held
    if (!failed)
      why = what;
    failed = true;
    changed.notify_all();
  };
  auto worker = [&](int t) {
    for (size_t k = 0; k < chunks; ++k) {
      {
        std::unique_lock<std::mutex> lock(mutex);
        changed.wait(lock, [&] { return queued > k || failed; });
        if (failed)
          return;
      }
      const int b = static_cast<int>(k % kStageBuffers);
      if (cudaEventSynchronize(set->copied[b]) != cudaSuccess) {
        std::lock_guard<std::mutex> lock(mutex);
        fail("staged device-to-host copy: waiting for a chunk failed");
        return;
      }
      const size_t off = k * kStageBytes, len = std::min(kStageBytes, bytes - off);
      const size_t slice = (len + threads - 1) / threads, from = std::min(len, t * slice),
                   to = std::min(len, from + slice);
      if (to > from)
        std::memcpy(static_cast<char*>(dst) + off + from, set->buffer[b].as<char>() + from,
                    to - from);
      std::lock_guard<std::mutex> lock(mutex);
      if (++slicesDone[b] == threads)
        changed.notify_all();
    }
  };
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t) {
    try {
      pool.emplace_back(worker, t);
    } catch (const std::system_error&) { // every slice needs its thread: stop the started ones
      std::lock_guard<std::mutex> lock(mutex);
      fail("staged device-to-host copy: could not start a copy thread");
      break;
    }
  }
  for (size_t k = 0; k < chunks; ++k) {
    const int b = static_cast<int>(k % kStageBuffers);
    {
      // Before reusing a buffer, its previous chunk must be copied out.
      std::unique_lock<std::mutex> lock(mutex);
      changed.wait(lock, [&] { return k < kStageBuffers || slicesDone[b] == threads || failed; });
      if (failed)
        break;
    }
    const size_t off = k * kStageBytes, len = std::min(kStageBytes, bytes - off);
    const bool queuedOk =
        cudaMemcpyAsync(set->buffer[b].as<void>(), static_cast<const char*>(src) + off, len,
                        cudaMemcpyDeviceToHost, stream) == cudaSuccess &&
        cudaEventRecord(set->copied[b], stream) == cudaSuccess;
    std::lock_guard<std::mutex> lock(mutex);
    if (!queuedOk) {
      fail(std::string("staged device-to-host copy: ") + cudaGetErrorString(cudaGetLastError()));
      break;
    }
    slicesDone[b] = 0;
    ++queued;
    changed.notify_all();
  }
  for (std::thread& th : pool)
    th.join();
  if (failed) { // a set whose copy failed is dropped
    error = why;
    return false;
  }
  GiveStaging(std::move(set));
  return true;
}

} // namespace detail

bool DeviceAvailable(std::string* why) {
  if (const char* off = std::getenv("FACEPLAN_DISABLE_CUDA");
      off && *off && std::strcmp(off, "0") != 0) {
    if (why)
      *why = "the CUDA backend is disabled by FACEPLAN_DISABLE_CUDA";
    return false;
  }
  std::string error;
  if (!InitDevice(error)) {
    if (why)
      *why = error;
    return false;
  }
  return true;
}

std::string DeviceDescription() {
  int count = 0;
  if (cudaGetDeviceCount(&count) != cudaSuccess || count == 0) {
    cudaGetLastError();
    return {};
  }
  cudaDeviceProp prop{};
  if (cudaGetDeviceProperties(&prop, 0) != cudaSuccess)
    return {};
  std::ostringstream out;
  out.precision(4);
  out << prop.name << " (sm_" << prop.major << prop.minor << ", " << prop.multiProcessorCount
      << " SMs, " << prop.totalGlobalMem / (1024.0 * 1024.0 * 1024.0) << " GiB)";
  return out.str();
}

Status MakeCudaBackend(std::shared_ptr<ComputeBackend>& backend) {
  backend.reset();
  std::string error;
  if (!DeviceAvailable(&error))
    return Status::Error(error);
  auto made = std::make_shared<CudaBackendImpl>();
  if (!made->init(error))
    return Status::Error(error);
  backend = std::move(made);
  return Status::Ok();
}

namespace {

// Median of `repeats` timed copies (after one warm-up), in GB/s; `factor` 2 counts read + write.
bool TimeCopies(void* dst, const void* src, size_t bytes, cudaMemcpyKind kind, int repeats,
                double factor, cudaStream_t stream, cudaEvent_t start, cudaEvent_t stop,
                double& gbs, std::string& error) {
  std::vector<float> ms;
  for (int r = -1; r < repeats; ++r) {
    FP_CUDA_TRY(cudaEventRecord(start, stream));
    FP_CUDA_TRY(cudaMemcpyAsync(dst, src, bytes, kind, stream));
    FP_CUDA_TRY(cudaEventRecord(stop, stream));
    FP_CUDA_TRY(cudaEventSynchronize(stop));
    float t = 0.f;
    FP_CUDA_TRY(cudaEventElapsedTime(&t, start, stop));
    if (r >= 0)
      ms.push_back(t);
  }
  std::sort(ms.begin(), ms.end());
  const double median = ms[ms.size() / 2];
  gbs = factor * static_cast<double>(bytes) / (median * 1e-3) / 1e9;
  return true;
}

} // namespace

Status MeasureBandwidth(Bandwidth& bw, size_t bytes, int repeats) {
  std::string error;
  if (!DeviceAvailable(&error))
    return Status::Error(error);
  repeats = std::max(repeats, 1);
  DeviceArray a, b;
  PinnedArray pinned;
  std::vector<unsigned char> pageable(bytes / 4);
  cudaStream_t stream = nullptr;
  cudaEvent_t start = nullptr, stop = nullptr;
  auto run = [&]() -> bool {
    FP_CUDA_TRY(cudaStreamCreateWithFlags(&stream, cudaStreamNonBlocking));
    FP_CUDA_TRY(cudaEventCreate(&start));
    FP_CUDA_TRY(cudaEventCreate(&stop));
    if (!a.ensure(bytes, error) || !b.ensure(bytes, error) || !pinned.ensure(bytes / 4, error))
      return false;
    FP_CUDA_TRY(cudaMemset(a.as<void>(), 1, bytes));
    std::fill(pageable.begin(), pageable.end(), static_cast<unsigned char>(3));
    std::memset(pinned.as<void>(), 5, bytes / 4);
    return TimeCopies(b.as<void>(), a.as<void>(), bytes, cudaMemcpyDeviceToDevice, repeats, 2.0,
                      stream, start, stop, bw.deviceToDeviceGBs, error) &&
           TimeCopies(a.as<void>(), pinned.as<void>(), bytes / 4, cudaMemcpyHostToDevice, repeats,
                      1.0, stream, start, stop, bw.hostToDevicePinnedGBs, error) &&
           TimeCopies(pinned.as<void>(), a.as<void>(), bytes / 4, cudaMemcpyDeviceToHost, repeats,
                      1.0, stream, start, stop, bw.deviceToHostPinnedGBs, error) &&
           TimeCopies(a.as<void>(), pageable.data(), bytes / 4, cudaMemcpyHostToDevice, repeats,
                      1.0, stream, start, stop, bw.hostToDevicePageableGBs, error) &&
           TimeCopies(pageable.data(), a.as<void>(), bytes / 4, cudaMemcpyDeviceToHost, repeats,
                      1.0, stream, start, stop, bw.deviceToHostPageableGBs, error);
  };
  const bool ok = run();
  if (start)
    cudaEventDestroy(start);
  if (stop)
    cudaEventDestroy(stop);
  if (stream)
    cudaStreamDestroy(stream);
  return ok ? Status::Ok() : Status::Error(error);
}

bool LastAssemblyDetail(const ComputeBackend& backend, AssemblyDetail& detail) {
  const auto* impl = dynamic_cast<const CudaBackendImpl*>(&backend);
  if (!impl)
    return false;
  detail = impl->lastDetail();
  return true;
}

bool LastFactorAndResponseDetail(const ComputeBackend& backend, FactorAndResponseDetail& detail) {
  const auto* impl = dynamic_cast<const CudaBackendImpl*>(&backend);
  return impl && impl->lastFactorDetail(detail);
}

void ReleasePatternCache(ComputeBackend& backend) {
  if (auto* impl = dynamic_cast<CudaBackendImpl*>(&backend))
    impl->releaseAll();
}

void SetPinnedTransfers(ComputeBackend& backend, bool on) {
  if (auto* impl = dynamic_cast<CudaBackendImpl*>(&backend))
    impl->setPinnedTransfers(on);
}

} // namespace faceplan::cuda
