// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// How many threads Core's parallel steps use: the hardware threads, at most `cap`, and at most
// FACEPLAN_THREADS when that environment variable holds a positive integer (to leave cores to
// other work, or one core per process when many run at once, as the parallel fuzzing does).
namespace faceplan {

int WorkerThreads(int cap);

} // namespace faceplan
