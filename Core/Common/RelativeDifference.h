// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The one measure of how far a result is from a reference, used by the tests, the benchmarks and
// the report: max |a - b| / max |b| (max |a - b| when b is all zero). A non-finite entry of `a`,
// or mismatched sizes, give infinity, so a NaN never passes a "below tolerance" check.
//  - RelativeMaxDifference: entry by entry (GPU against CPU values, matrices, vectors);
//  - RelativeMaxNodeDifference: per node of an n x 3 field, |a_i - b_i| / max |b_i| with the
//    Euclidean norm of each row (displacements against a reference solve).
#include <Eigen/Core>

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

template <class A, class B>
double RelativeMaxDifference(const Eigen::DenseBase<A>& a, const Eigen::DenseBase<B>& b) {
  if (a.rows() != b.rows() || a.cols() != b.cols() || !a.derived().allFinite())
    return std::numeric_limits<double>::infinity();
  if (a.size() == 0)
    return 0.0;
  const double diff = (a.derived() - b.derived()).cwiseAbs().maxCoeff();
  const double scale = b.derived().cwiseAbs().maxCoeff();
  return scale > 0 ? diff / scale : diff;
}

template <class A, class B>
double RelativeMaxNodeDifference(const Eigen::DenseBase<A>& a, const Eigen::DenseBase<B>& b) {
  if (a.rows() != b.rows() || a.cols() != b.cols() || !a.derived().allFinite())
    return std::numeric_limits<double>::infinity();
  if (a.size() == 0)
    return 0.0;
  const double diff = (a.derived() - b.derived()).rowwise().norm().maxCoeff();
  const double scale = b.derived().rowwise().norm().maxCoeff();
  return scale > 0 ? diff / scale : diff;
}

} // namespace faceplan
