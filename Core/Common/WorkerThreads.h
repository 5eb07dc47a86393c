// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// How many threads Core's parallel steps use: the hardware threads, at most `cap`, and at most
// FACEPLAN_THREADS when that environment variable holds a positive integer (to leave cores to
// other work, or one core per process when many run at once, as the parallel fuzzing does).
namespace faceplan {

int WorkerThreads(int cap);

// Names the calling thread (at most 15 characters) where the system keeps thread names (Linux), so
// that top -H, perf and /proc/<pid>/task tell FacePlan's threads from the host application's.
void NameThisThread(const char* name);

} // namespace faceplan
