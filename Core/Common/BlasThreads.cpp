#include "Common/BlasThreads.h"

#include <dlfcn.h>

#include <mutex>

namespace faceplan {

namespace {
using SetThreads = void (*)(int);
using GetThreads = int (*)();
SetThreads SetFunction() {
  return reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"));
}
GetThreads GetFunction() {
  return reinterpret_cast<GetThreads>(dlsym(RTLD_DEFAULT, "openblas_get_num_threads"));
}

// OpenBLAS's thread count is one per process, while scopes may open and close on several threads
// in any order (a background precompute beside another filter's): the count before the first open
// scope is restored when the last one closes, whatever the order.
std::mutex scopeMutex;
int openScopes = 0;
int countBeforeScopes = -1;
} // namespace

ScopedBlasThreads::ScopedBlasThreads(int threads) {
  SetThreads set = SetFunction();
  GetThreads get = GetFunction();
  if (!set || !get)
    return;
  std::lock_guard<std::mutex> lock(scopeMutex);
  previous_ = get();
  if (openScopes++ == 0)
    countBeforeScopes = previous_;
  set(threads);
}

ScopedBlasThreads::~ScopedBlasThreads() {
  if (previous_ <= 0)
    return;
  std::lock_guard<std::mutex> lock(scopeMutex);
  // A nested scope gives back its enclosing scope's count; the last one the original count.
  SetFunction()(--openScopes == 0 ? countBeforeScopes : previous_);
}

} // namespace faceplan
