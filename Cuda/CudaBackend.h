// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// CUDA implementation of faceplan::ComputeBackend.
//
// - assembleStiffness: element stiffness Ke = B^T D B V of every tetrahedron on the GPU in double
//   (same formula and packed 78-entry layout as Core/ElementStiffness.cpp), then the gather of
//   AssemblyPattern into pattern.upper's values on the GPU (same summation order as the CPU), and
//   one copy of the values back. The pattern's gather map and the mesh's cells stay on the device
//   while the same pattern is passed again (checked by address, sizes and a sampled fingerprint),
//   so a repeated assembly uploads only the points and materials.
// - makeResponseOperator: the dense response lives in GPU memory; apply() uploads the ROI vector,
//   runs cuBLAS DGEMV and downloads the kept vector (pinned buffers, one stream, one mutex).
//
// Nothing here throws or aborts: every CUDA/cuBLAS call and kernel launch is checked and a
// failure comes back as false/null with a message, so the caller can fall back to the CPU.
#include "Backend/ComputeBackend.h"

#include <cstddef>
#include <memory>
#include <string>

namespace faceplan::cuda {

// True when a CUDA device is present and can run this library's kernels; otherwise false and,
// if `why` is given, a sentence saying why (no driver, no device, wrong architecture...).
bool DeviceAvailable(std::string* why = nullptr);

// "NVIDIA H200 (sm_90, 132 SMs, 139.8 GiB)"; empty when no device.
std::string DeviceDescription();

// The CUDA backend on device 0; fails (backend null) when no usable device is present.
// Its name() starts with "CUDA".
Status MakeCudaBackend(std::shared_ptr<ComputeBackend>& backend);

// Breakdown of the most recent assembleStiffness call of a backend made by MakeCudaBackend
// (device times from CUDA events, wall time from the host clock).
struct AssemblyDetail {
  double uploadMs = 0.0;          // points and materials (+ cells and gather map when not cached)
                                  // (device timeline; staging copies on the host are in wallMs)
  double stiffnessKernelMs = 0.0; // element stiffness kernel
  double gatherKernelMs = 0.0;    // assembly gather kernel
  double downloadMs = 0.0;        // values device -> host
  double wallMs = 0.0;            // the whole call on the host clock
  bool patternReused = false;     // the gather map and cells were already on the device
  double bytesUploaded = 0.0;
  double bytesDownloaded = 0.0;
  // Bytes the two kernels must move through device memory at least (each input read once, each
  // output written once, the packed element matrices written and read once).
  double kernelBytes = 0.0;
};
// False when `backend` is not a CUDA backend.
bool LastAssemblyDetail(const ComputeBackend& backend, AssemblyDetail& detail);

// Copy bandwidths measured on device 0 (for benchmark floors). Device-to-device counts the bytes
// read plus the bytes written, as a memory-bandwidth ceiling should.
struct Bandwidth {
  double deviceToDeviceGBs = 0.0;
  double hostToDevicePinnedGBs = 0.0;
  double deviceToHostPinnedGBs = 0.0;
  double hostToDevicePageableGBs = 0.0;
  double deviceToHostPageableGBs = 0.0;
};
Status MeasureBandwidth(Bandwidth& bandwidth, size_t bytes = size_t(1) << 30, int repeats = 10);

// Forget the cached pattern and free the assembly's device memory; the next assembly uploads
// the pattern again.
void ReleasePatternCache(ComputeBackend& backend);

// Assembly transfers through page-locked staging buffers with parallel host copies (default on)
// or straight from/to the caller's pageable memory (off).
void SetPinnedTransfers(ComputeBackend& backend, bool on);

} // namespace faceplan::cuda
