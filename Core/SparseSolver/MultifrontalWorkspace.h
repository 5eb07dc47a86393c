// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Declared apart from MultifrontalCholesky.h (which needs CHOLMOD's header) so that the libraries
// above SparseSolver can keep one.
#include <memory>

namespace faceplan {

// What successive factorizations of matrices of one pattern with one analysis keep: the plan (each
// entry's place in the fronts) and the update matrices' buffers. A factorization's update matrices
// add up to several times the factor, mostly in blocks the C library maps afresh and returns to
// the system when freed, so each factorization would page-fault them in and have them zero-filled
// again (a third of a single-precision factorization's time on the face's tangent). The buffers
// kept are trimmed after each factorization to what it used at most at once.
// One factorization at a time per workspace.
class MultifrontalWorkspace {
public:
  MultifrontalWorkspace();
  ~MultifrontalWorkspace();
  MultifrontalWorkspace(const MultifrontalWorkspace&) = delete;
  MultifrontalWorkspace& operator=(const MultifrontalWorkspace&) = delete;
  // Bytes of the update buffers kept between factorizations.
  double keptBytes() const;
  // Factorizations that found their plan here.
  int plansReused() const;

  struct Impl;
  std::unique_ptr<Impl> impl;
};

} // namespace faceplan
