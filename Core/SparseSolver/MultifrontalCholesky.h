// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Numeric supernodal Cholesky factorization into CHOLMOD's own layout (the factor CHOLMOD's
// analysis made: its supernodes, row lists and value offsets), computed multifrontally over the
// supernodal elimination tree so that independent subtrees run on their own threads.
//
// Why not cholmod_factorize: CHOLMOD parallelises only inside each supernode's BLAS calls, so the
// many small supernodes below the top of the nested dissection use one core at a time, and its
// factorization gains little from more cores. Here every
// supernode is a task that runs as soon as its children are done, with single-threaded BLAS, and
// only the few large supernodes at the top, whose dense blocks are big enough for threaded BLAS to
// pay, run one after another with all threads.
//
// Deterministic: a supernode's frontal matrix adds its children's update matrices in ascending
// child order whatever thread ran them, so the factor is the same bit for bit on every run with
// the same thread count for the top (OpenBLAS's threaded kernels may split sums by thread count).
// For .cpp files only (CHOLMOD is a private dependency of FacePlanSparseSolver).
#include "Common/Status.h"
#include "Element/StiffnessAssembly.h"
#include "SparseSolver/MultifrontalWorkspace.h"

#include <cholmod.h>

namespace faceplan {

struct MultifrontalReport {
  int supernodes = 0;
  int topSupernodes = 0;    // run last, one after another, with threaded BLAS
  double topFlopsShare = 0; // their share of the factorization's flops
  int threads = 0;
  int topBlasThreads = 0; // the BLAS threads the top asked for (1 on a background thread)
  // With a reference (MultifrontalRefactorizeSingle): the supernodes factored, and their share of
  // a whole factorization's flops; without, every supernode and 1.
  int supernodesFactored = 0;
  double factoredFlopsShare = 1.0;
};

// L: a supernodal symbolic (or numeric) factor of `upper`'s matrix with 32-bit indices, as
// CholmodFactor's analysis makes it; `upper`: the matrix's upper triangle in the original order
// (compressed). Fills L's values (allocating them through `common`) and marks L numeric LL^T.
// Fails, leaving L's values undefined, when the matrix is not positive definite (then L->minor is
// the elimination-order column where a pivot failed, not necessarily the first such column:
// subtrees run in parallel) or memory runs out in a task; callers that report the failing column
// should factor again with CHOLMOD, as CholmodFactor does.
Status MultifrontalFactorize(const SparseMatrix& upper, cholmod_factor* L, cholmod_common* common,
                             int threads, MultifrontalReport* report = nullptr,
                             MultifrontalWorkspace* workspace = nullptr);

// The same factorization computed in single precision into `values` (analysis.px[nsuper] floats
// in CHOLMOD's supernodal layout), from `analysis`, a supernodal analysis of `upper`'s pattern
// (symbolic or numeric; only its structure and ordering are read, so other threads may read it
// meanwhile). Half the bytes moved and twice the BLAS's vector width of the double factorization.
// Fails when an entry is beyond a float's range, or a pivot is not positive in single precision
// (the matrix need not be indefinite: single precision's rounding may break down on an
// ill-conditioned one).
// With `keep`, a successful factorization is kept there as the reference of later ones (see
// MultifrontalReference); a failed one leaves it empty.
Status MultifrontalFactorizeSingle(const SparseMatrix& upper, const cholmod_factor& analysis,
                                   float* values, int threads, MultifrontalReport* report = nullptr,
                                   MultifrontalWorkspace* workspace = nullptr,
                                   MultifrontalReference* keep = nullptr);

// The single-precision factorization of `upper` that reuses `reference` (made by
// MultifrontalFactorizeSingle with the same analysis and a matrix of the same pattern) wherever
// the entries of a supernode's columns and of all its descendants' differ from the reference's by
// at most `tolerance` times sqrt(|a_ii a_jj|) of the reference's diagonal (NaN differs; 0 reuses
// only exactly equal columns, and the factor is then the whole factorization's bit for bit). A
// reference that is empty or was made for another analysis or pattern: the whole factorization.
Status MultifrontalRefactorizeSingle(const SparseMatrix& upper, const cholmod_factor& analysis,
                                     float* values, int threads,
                                     const MultifrontalReference& reference, double tolerance,
                                     MultifrontalReport* report = nullptr,
                                     MultifrontalWorkspace* workspace = nullptr);

} // namespace faceplan
