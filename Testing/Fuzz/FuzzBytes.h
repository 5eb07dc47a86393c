// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Reads typed values from a fuzzer's byte string; past its end every read gives zero, so any input
// is a valid (if short) description.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>

namespace faceplan::fuzz {

class FuzzBytes {
public:
  FuzzBytes(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}

  std::uint8_t byte() { return pos_ < size_ ? data_[pos_++] : 0; }
  // An integer in [lo, hi].
  int range(int lo, int hi) {
    const unsigned span = unsigned(hi - lo) + 1u;
    return lo + int((unsigned(byte()) | unsigned(byte()) << 8) % span);
  }
  bool flag() { return byte() & 1u; }
  // A signed value in [-scale, scale] from one byte.
  double scaled(double scale) { return scale * (double(int(byte()) - 128) / 128.0); }
  // Any double, including NaN, infinities, denormals and huge values.
  double raw() {
    std::uint64_t bits = 0;
    for (int k = 0; k < 8; ++k)
      bits |= std::uint64_t(byte()) << (8 * k);
    double value;
    std::memcpy(&value, &bits, sizeof value);
    return value;
  }
  // Mostly ordinary values near `typical`, sometimes a special one.
  double number(double typical) {
    switch (byte() % 8) {
    case 0:
      return raw();
    case 1:
      return std::nan("");
    case 2:
      return (byte() & 1 ? 1.0 : -1.0) * HUGE_VAL;
    case 3:
      return 0.0;
    default:
      return typical * (1.0 + scaled(1.0));
    }
  }
  std::int32_t int32() {
    std::uint32_t bits = 0;
    for (int k = 0; k < 4; ++k)
      bits |= std::uint32_t(byte()) << (8 * k);
    return std::int32_t(bits);
  }
  bool exhausted() const { return pos_ >= size_; }

private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

// Stops the run the way a crash would, so the fuzzer keeps the input (a broken promise, not a
// crash of the code itself).
[[noreturn]] void Violation(const char* what);

} // namespace faceplan::fuzz
