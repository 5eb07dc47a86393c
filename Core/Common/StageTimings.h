// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Stage-by-stage timing in the spirit of the ICAT 2008 paper's Table 2.
#include <chrono>
#include <string>
#include <vector>

namespace faceplan {

enum class Stage {
  Reordering,
  ElementStiffness,
  Assembly,
  Separation,
  Condensation,
  Factorization,
  BoundaryCondition,
  Load,
  Solve,
  Total
};
constexpr int kNumStages = 10;
const char* StageName(Stage stage);

struct StageTime {
  double ms = 0.0;
  bool reused = false; // taken from the cached precompute instead of being recomputed
};

struct StageTimings {
  StageTime stages[kNumStages];
  StageTime& operator[](Stage s) { return stages[static_cast<int>(s)]; }
  const StageTime& operator[](Stage s) const { return stages[static_cast<int>(s)]; }
};

class StageClock {
public:
  StageClock() : start_(std::chrono::steady_clock::now()) {}
  double elapsedMs() const {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_)
        .count();
  }
  // Milliseconds since construction or the previous lap.
  double lapMs() {
    auto now = std::chrono::steady_clock::now();
    double ms = std::chrono::duration<double, std::milli>(now - start_).count();
    start_ = now;
    return ms;
  }

private:
  std::chrono::steady_clock::time_point start_;
};

} // namespace faceplan
