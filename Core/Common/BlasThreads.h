// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Sets OpenBLAS's thread count for a scope, when the BLAS in use is OpenBLAS (looked up at run
// time, so any BLAS links). FacePlan runs one single-threaded CHOLMOD solve per core for the
// dense response: its supernodes are too small for threaded BLAS to pay, and both at once would
// oversubscribe the cores. The count is one per process: while scopes are open on several threads,
// a Pinned scope's request holds over the Shared ones (a solve's round-off must not depend on the
// count another thread's precompute set meanwhile: OpenBLAS splits some products by thread count),
// and among Shared ones the smallest request holds (a single-threaded caller is not run threaded).
namespace faceplan {

enum class BlasScope { Shared, Pinned };

class ScopedBlasThreads {
public:
  explicit ScopedBlasThreads(int threads, BlasScope kind = BlasScope::Shared);
  ~ScopedBlasThreads();
  ScopedBlasThreads(const ScopedBlasThreads&) = delete;
  ScopedBlasThreads& operator=(const ScopedBlasThreads&) = delete;

private:
  int requested_ = -1; // this scope's request; -1 when the BLAS is not OpenBLAS
  BlasScope kind_ = BlasScope::Shared;
};

// Marks the calling thread as background work (the refactorization ahead of a drag, at the lowest
// priority): the threaded BLAS steps it asks for then run on one thread. OpenBLAS's threads are
// the process's, at normal priority, and spin for about a tenth of a second after each threaded
// call before they sleep, so a background step's threaded BLAS would take as many cores from the
// edit the user waits for.
void MarkThreadAsBackground();
bool ThreadIsBackground();

} // namespace faceplan
