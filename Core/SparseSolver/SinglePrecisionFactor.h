// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A single-precision copy of a numeric supernodal LL^T factor (CholmodFactor), for substitutions
// that need only be close to exact: an initial inverse Hessian or a preconditioner, whose caller
// measures convergence with the double-precision residual. A substitution reads every non-zero of
// the factor twice and is bound by memory bandwidth, so half the bytes is about half the time (and
// a factor of a few million non-zeros then fits a server's last-level cache).
//
// The substitutions run on two threads where the supernodal tree splits into two subtrees of
// similar work below a small top part: each subtree's forward sweep accumulates its updates of the
// top part privately, the top part runs alone, then the subtrees' backward sweeps run side by side.
#include "Common/Status.h"
#include "Element/StiffnessAssembly.h"

#include <Eigen/Core>
#include <cstdint>
#include <memory>

namespace faceplan {

class CholmodFactor;
class MultifrontalWorkspace;
class MultifrontalReference;

// A factorization's use of a reference factorization (MultifrontalReference): `keep` receives
// this one's, or this one reuses `from`'s unchanged supernodes (with `tolerance`, as
// MultifrontalRefactorizeSingle).
struct FactorReuse {
  MultifrontalReference* keep = nullptr;
  const MultifrontalReference* from = nullptr;
  double tolerance = 0.0;
};

// The value buffers of single-precision factors that are gone, kept for the next factorization of
// the same size: a fresh buffer is mapped and page-faulted in, zero-filled by the kernel, on each
// factorization (a sixth of its time on the face's tangent). Holds at most two. A factor returns
// its buffer when it is destroyed, on whichever thread; the bin may go first.
class FactorValueBin {
public:
  FactorValueBin();
  ~FactorValueBin();
  FactorValueBin(const FactorValueBin&) = delete;
  FactorValueBin& operator=(const FactorValueBin&) = delete;
  double keptBytes() const;

  struct Impl;
  std::unique_ptr<Impl> impl;
};

class SinglePrecisionFactor {
public:
  SinglePrecisionFactor();
  ~SinglePrecisionFactor();
  SinglePrecisionFactor(const SinglePrecisionFactor&) = delete;
  SinglePrecisionFactor& operator=(const SinglePrecisionFactor&) = delete;

  // Copies factor's numeric supernodal LL^T factor (fails for any other kind). threads: 1 or 2.
  Status assign(const CholmodFactor& factor, int threads = 2);
  // Factors `upper` (a matrix with the pattern `analysed` was analysed for, upper triangle) in
  // single precision directly, in `analysed`'s ordering and supernodes (multifrontal, as
  // CholmodFactor::factorize; `analysed` need not be factorized and is only read). About half the
  // time of factoring in double and copying. Fails where single precision's pivots break down, as
  // they may on a matrix too ill-conditioned for it: the caller then factors in double and copies.
  // With a workspace (for successive factorizations on one thread) its plan and update buffers are
  // reused, and with a bin this factor's values come from it when it holds a buffer of their size
  // and go back to it when this factor is destroyed or factored again. With `reuse`, as FactorReuse
  // says (a factor that reuses a reference is close to the factor of `upper`, not equal).
  Status factorize(const CholmodFactor& analysed, const SparseMatrix& upper, int threads = 2,
                   MultifrontalWorkspace* workspace = nullptr,
                   const std::shared_ptr<FactorValueBin>& bin = nullptr,
                   const FactorReuse& reuse = FactorReuse());
  // The share of a whole factorization's flops that the last factorize spent (below 1 where it
  // reused a reference; 1 after assign).
  double factoredShare() const;
  // x = (L L^T)^-1 b (the factored matrix's inverse applied to b, original numbering), in single
  // precision after scaling b to unit largest entry. Safe to call from several threads at once.
  Status solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const;
  // X = (L L^T)^-1 B for every column of B at once (as the solve above, column by column, with the
  // sums in another order): the factor is read once for up to 32 columns by blocked products, which
  // costs less than one-by-one solves from about four columns on.
  Status solve(const Eigen::MatrixXd& b, Eigen::MatrixXd& x) const;
  Eigen::Index rows() const;
  // Bytes of the single-precision values.
  double valueBytes() const;

  // The copy in CHOLMOD's supernodal layout, for a backend that copies it as it is: each
  // supernode's first column (super), the starts of its row list (pi) and of its values (px), the
  // row lists (s), the columns' values (column-major per supernode) and the fill-reducing
  // permutation (column k of the factor is row perm[k] of the matrix). Arrays of nsuper + 1
  // entries (super, pi, px), pi[nsuper] (s), px[nsuper] (values) and n (perm); all null before a
  // successful assign. Valid until the next assign.
  struct Layout {
    int n = 0, nsuper = 0;
    const int* super = nullptr;
    const int* pi = nullptr;
    const std::int64_t* px = nullptr;
    const int* s = nullptr;
    const float* values = nullptr;
    const int* perm = nullptr;
  };
  Layout layout() const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

} // namespace faceplan
