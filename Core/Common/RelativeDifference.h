#pragma once
// max |a - b| / max |b| over `count` entries (max |a - b| when b is all zero); infinity when a
// has a non-finite entry, so a NaN never passes a "below tolerance" check. Shared by the CUDA
// tests and the GPU benchmark, which compare GPU results with the CPU's entry by entry.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

namespace faceplan {

inline double RelativeMaxDifference(const double* a, const double* b, std::size_t count) {
  double diff = 0.0, scale = 0.0;
  for (std::size_t i = 0; i < count; ++i) {
    if (!std::isfinite(a[i]))
      return std::numeric_limits<double>::infinity();
    diff = std::max(diff, std::abs(a[i] - b[i]));
    scale = std::max(scale, std::abs(b[i]));
  }
  return scale > 0 ? diff / scale : diff;
}

} // namespace faceplan
