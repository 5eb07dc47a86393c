// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The memory a precompute may use, checked against the sizes known after the symbolic analysis
// (the sparse factor, the dense response) before either is allocated, so that a scene too large
// for the machine gets an error or a cheaper method instead of the out-of-memory killer.
#include <string>

namespace faceplan {

// MemAvailable from /proc/meminfo in bytes (the kernel's estimate of what can be allocated without
// swapping); 0 when it cannot be read.
double AvailableMemoryBytes();

// The budget in force: `requestedBytes` when positive, else AvailableMemoryBytes() (infinite when
// that is unknown).
double MemoryBudgetBytes(double requestedBytes);

// "12.3 MB"-style text for messages.
std::string MegabyteText(double bytes);

} // namespace faceplan
