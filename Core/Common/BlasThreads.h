#pragma once
// Sets OpenBLAS's thread count for a scope, when the BLAS in use is OpenBLAS (looked up at run
// time, so any BLAS links). FacePlan runs one single-threaded CHOLMOD solve per core for the
// dense response: its supernodes are too small for threaded BLAS to pay, and both at once would
// oversubscribe the cores.
namespace faceplan {

class ScopedBlasThreads {
public:
  explicit ScopedBlasThreads(int threads);
  ~ScopedBlasThreads();
  ScopedBlasThreads(const ScopedBlasThreads&) = delete;
  ScopedBlasThreads& operator=(const ScopedBlasThreads&) = delete;

private:
  int previous_ = -1;
};

} // namespace faceplan
