// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Non-owning CHOLMOD views of Eigen storage (no copies), shared by Core and the CUDA backend, and
// the quiet cholmod_common every CHOLMOD caller here starts. For .cpp files only: CHOLMOD is a
// private dependency of FacePlanSparseSolver, so no public Core header includes cholmod.h.
#include "Element/StiffnessAssembly.h"

#include <Eigen/Core>
#include <cholmod.h>
#include <vector>

namespace faceplan {

// An Eigen upper-triangular CSC matrix as a symmetric cholmod_sparse (stype = 1).
inline cholmod_sparse ViewUpper(const SparseMatrix& upper) {
  cholmod_sparse view{};
  view.nrow = static_cast<size_t>(upper.rows());
  view.ncol = static_cast<size_t>(upper.cols());
  view.nzmax = static_cast<size_t>(upper.nonZeros());
  view.p = const_cast<int*>(upper.outerIndexPtr());
  view.i = const_cast<int*>(upper.innerIndexPtr());
  view.x = const_cast<double*>(upper.valuePtr());
  view.stype = 1;
  view.itype = CHOLMOD_INT;
  view.xtype = CHOLMOD_REAL;
  view.dtype = CHOLMOD_DOUBLE;
  view.sorted = 1;
  view.packed = 1;
  return view;
}

// A CSC pattern (upper triangle, unsorted rows) as a symmetric pattern cholmod_sparse; `dummyRow`
// stands in for an empty row array (CHOLMOD wants a non-null one).
inline cholmod_sparse ViewPattern(int n, std::vector<int>& columnStart, std::vector<int>& rows,
                                  std::vector<int>& dummyRow) {
  cholmod_sparse view{};
  view.nrow = view.ncol = static_cast<size_t>(n);
  view.nzmax = rows.size();
  view.p = columnStart.data();
  view.i = rows.empty() ? dummyRow.data() : rows.data();
  view.stype = 1;
  view.itype = CHOLMOD_INT;
  view.xtype = CHOLMOD_PATTERN;
  view.dtype = CHOLMOD_DOUBLE;
  view.sorted = 0;
  view.packed = 1;
  return view;
}

// A column-major Eigen matrix as a cholmod_dense.
inline cholmod_dense ViewDense(const Eigen::MatrixXd& b) {
  cholmod_dense view{};
  view.nrow = b.rows();
  view.ncol = b.cols();
  view.nzmax = b.size();
  view.d = b.rows();
  view.x = const_cast<double*>(b.data());
  view.xtype = CHOLMOD_REAL;
  view.dtype = CHOLMOD_DOUBLE;
  return view;
}

// A cholmod_common for the owner's lifetime that prints nothing and has no error handler: every
// caller checks return values and status itself and reports through Status. Free what was
// allocated with it before it goes (members declared after it are destroyed first).
struct QuietCholmodCommon {
  cholmod_common common;
  QuietCholmodCommon() {
    cholmod_start(&common);
    common.print = 0;
    common.error_handler = nullptr;
  }
  ~QuietCholmodCommon() { cholmod_finish(&common); }
  QuietCholmodCommon(const QuietCholmodCommon&) = delete;
  QuietCholmodCommon& operator=(const QuietCholmodCommon&) = delete;
};

} // namespace faceplan
