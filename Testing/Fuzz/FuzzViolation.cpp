// SPDX-License-Identifier: BSD-3-Clause
#include "FuzzBytes.h"

#include <cstdio>
#include <cstdlib>

namespace faceplan::fuzz {

void Violation(const char* what) {
  std::fprintf(stderr, "fuzz: promise broken: %s\n", what);
  std::abort();
}

} // namespace faceplan::fuzz
