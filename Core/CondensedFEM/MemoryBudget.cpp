// SPDX-License-Identifier: BSD-3-Clause
#include "CondensedFEM/MemoryBudget.h"

#include <fstream>
#include <limits>
#include <sstream>
#include <string>

namespace faceplan {

double AvailableMemoryBytes() {
  std::ifstream meminfo("/proc/meminfo");
  std::string key, unit;
  double value = 0.0;
  while (meminfo >> key >> value) {
    std::getline(meminfo, unit);
    if (key == "MemAvailable:")
      return value * 1024.0; // the kernel reports kB
  }
  return 0.0;
}

double MemoryBudgetBytes(double requestedBytes) {
  if (requestedBytes > 0.0)
    return requestedBytes;
  const double available = AvailableMemoryBytes();
  return available > 0.0 ? available : std::numeric_limits<double>::infinity();
}

std::string MegabyteText(double bytes) {
  std::ostringstream text;
  text.precision(3);
  text << bytes / 1e6 << " MB";
  return text.str();
}

} // namespace faceplan
