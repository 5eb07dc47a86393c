// SPDX-License-Identifier: BSD-3-Clause
#include "Report/Statistics.h"

#include <algorithm>
#include <chrono>

namespace faceplan::report {

Spread Summarize(std::vector<double> v) {
  Spread s;
  s.n = static_cast<int>(v.size());
  if (v.empty())
    return s;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  s.median = n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
  if (n < 10) {
    s.lo = v.front();
    s.hi = v.back();
    s.kind = "min/max";
  } else {
    auto q = [&](double f) { return v[std::min(n - 1, static_cast<size_t>(f * (n - 1) + 0.5))]; };
    s.lo = q(0.1);
    s.hi = q(0.9);
    s.kind = "p10/p90";
  }
  return s;
}

double NowMs() {
  return std::chrono::duration<double, std::milli>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

} // namespace faceplan::report
