// SPDX-License-Identifier: BSD-3-Clause
#include "Common/BlasThreads.h"

#include <dlfcn.h>

#include <algorithm>
#include <mutex>
#include <vector>

namespace faceplan {

namespace {
using SetThreads = void (*)(int);
using GetThreads = int (*)();
SetThreads SetFunction() { // looked up once: solves open a scope on every edit
  static const SetThreads set =
      reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"));
  return set;
}
GetThreads GetFunction() {
  static const GetThreads get =
      reinterpret_cast<GetThreads>(dlsym(RTLD_DEFAULT, "openblas_get_num_threads"));
  return get;
}

// OpenBLAS's thread count is one per process, while scopes may open and close on several threads
// in any order (a background precompute beside another filter's): the open scopes' requests decide
// it (BlasThreads.h), and the count before the first open scope is restored when the last one
// closes, whatever the order.
std::mutex scopeMutex;
std::vector<int> openShared, openPinned;
int countBeforeScopes = -1;

thread_local bool threadIsBackground = false; // MarkThreadAsBackground

// The count the open scopes ask for; -1 when none is open.
int CountInForce() {
  const std::vector<int>& deciding = openPinned.empty() ? openShared : openPinned;
  return deciding.empty() ? -1 : *std::min_element(deciding.begin(), deciding.end());
}
} // namespace

ScopedBlasThreads::ScopedBlasThreads(int threads, BlasScope kind) : kind_(kind) {
  const SetThreads set = SetFunction();
  const GetThreads get = GetFunction();
  if (!set || !get)
    return;
  std::lock_guard<std::mutex> lock(scopeMutex);
  if (CountInForce() < 0)
    countBeforeScopes = get();
  (kind == BlasScope::Pinned ? openPinned : openShared).push_back(threads);
  requested_ = threads;
  set(CountInForce());
}

ScopedBlasThreads::~ScopedBlasThreads() {
  if (requested_ <= 0)
    return;
  std::lock_guard<std::mutex> lock(scopeMutex);
  std::vector<int>& open = kind_ == BlasScope::Pinned ? openPinned : openShared;
  open.erase(std::find(open.begin(), open.end(), requested_));
  const int count = CountInForce();
  SetFunction()(count < 0 ? countBeforeScopes : count);
}

void MarkThreadAsBackground() {
  threadIsBackground = true;
}

bool ThreadIsBackground() {
  return threadIsBackground;
}

} // namespace faceplan
