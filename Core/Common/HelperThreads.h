// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Runs the parts of a parallel step on threads kept for it, instead of threads started for each
// step. A quasi-Newton iteration has a few parallel steps of 1-3 ms each (the cells' forces, the
// factor's substitutions); a thread started for each is placed by the kernel beside its parent and
// on a loaded 2-core machine was seen to start only when the parent blocked, which made the step
// serial. Kept threads wake where they last ran, and wait a little before they sleep, so the next
// step of the same iteration finds them awake.
//
// Each calling thread has its own helpers, started on its first parallel step with its priority
// (the background refactorization's low priority stays with its own helpers), and ended when it
// exits. A part that throws has its exception rethrown on the calling thread.
#include <cstdint>
#include <functional>

namespace faceplan {

// Runs work(0), ..., work(parts - 1): part 0 on the calling thread, the others on its helpers, and
// returns when all have returned. parts <= 1 runs inline, and so do the parts of a call made from
// within a part on the calling thread.
void RunOnHelpers(int parts, const std::function<void(int)>& work);

} // namespace faceplan
