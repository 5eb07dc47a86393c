#pragma once
// Entry-by-entry comparison of two arrays of the same length. A non-finite entry of `a` gives
// infinity, so a NaN never passes a "below tolerance" check.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

namespace faceplan {

// max |a - b|.
inline double MaxAbsDifference(const double* a, const double* b, std::size_t count) {
  double diff = 0.0;
  for (std::size_t i = 0; i < count; ++i) {
    if (!std::isfinite(a[i]))
      return std::numeric_limits<double>::infinity();
    diff = std::max(diff, std::abs(a[i] - b[i]));
  }
  return diff;
}

// max |b|.
inline double MaxAbs(const double* b, std::size_t count) {
  double scale = 0.0;
  for (std::size_t i = 0; i < count; ++i)
    scale = std::max(scale, std::abs(b[i]));
  return scale;
}

// max |a - b| / max |b| (max |a - b| when b is all zero).
inline double RelativeMaxDifference(const double* a, const double* b, std::size_t count) {
  const double diff = MaxAbsDifference(a, b, count), scale = MaxAbs(b, count);
  return scale > 0 ? diff / scale : diff;
}

} // namespace faceplan
