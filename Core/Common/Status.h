// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Result of every Core entry point: Core never throws across its interface.
#include <string>
#include <utility>
#include <vector>

namespace faceplan {

struct Status {
  bool ok = true;
  std::string message;               // why it failed; empty when ok
  std::vector<std::string> warnings; // non-fatal findings (slivers, large strain, ...)

  static Status Ok() { return {}; }
  static Status Error(std::string why) {
    Status s;
    s.ok = false;
    s.message = std::move(why);
    return s;
  }
  explicit operator bool() const { return ok; }
};

} // namespace faceplan
