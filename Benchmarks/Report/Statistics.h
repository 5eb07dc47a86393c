// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Medians of repeated timings with their spread, and the clock they are taken with.
#include <limits>
#include <string>
#include <vector>

namespace faceplan::report {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct Spread {
  double median = kNaN, lo = kNaN, hi = kNaN;
  int n = 0;
  std::string kind; // "min/max" (fewer than 10 samples) or "p10/p90"
};

Spread Summarize(std::vector<double> v);

// Milliseconds on the steady clock.
double NowMs();

} // namespace faceplan::report
