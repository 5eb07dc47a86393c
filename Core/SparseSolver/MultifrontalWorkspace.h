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

// A single-precision factorization kept as the reference of later ones of the same pattern and
// analysis (the rest tangent's, for the tangents of a large-deformation solve): its matrix, its
// factor, and the update matrices of the supernodes whose subtrees cost many flops per entry of
// their update. A later factorization (MultifrontalRefactorizeSingle) recomputes only the
// supernodes whose columns hold an entry that differs from the reference's by more than a
// tolerance, their ancestors, and those of their children whose update matrices are not kept;
// every other supernode's columns are the reference's. The factor is then the exact factor of the
// matrix that takes the reference's entries in those columns and the given ones elsewhere: close
// to the matrix given, not equal, and so meant for an initial Hessian or a preconditioner.
// Read-only once made, so that factorizations on several threads may reuse it at once.
class MultifrontalReference {
public:
  MultifrontalReference();
  ~MultifrontalReference();
  MultifrontalReference(const MultifrontalReference&) = delete;
  MultifrontalReference& operator=(const MultifrontalReference&) = delete;
  // Whether a factorization filled it.
  bool made() const;
  // Bytes it holds (matrix, factor, update matrices).
  double keptBytes() const;

  struct Impl;
  std::unique_ptr<Impl> impl;
};

} // namespace faceplan
