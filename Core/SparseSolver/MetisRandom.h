// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// One random generator per thread for METIS, so that orderings can be made on several threads at
// once and still be reproducible.
//
// Why: METIS draws every random number (matching order, initial partitions) through GKlib's
// gk_randinit / gk_randint32 / gk_randint64, which in Debian's METIS 5.1 use the C library's one
// process-wide rand() state. Two METIS calls at once would draw from it in turn, so the same graph
// would get a different ordering, and round-off, from run to run. MetisRandom.cpp defines those
// three functions with a per-thread state: libmetis calls them through its PLT, so the dynamic
// linker binds its calls to these definitions (they come before libmetis in the lookup order of
// every program and plugin that links FacePlan's Core). Each thread draws the sequence rand()
// would give a lone caller after the same seed, so an ordering made on a thread equals the one
// made alone, and equals what METIS made before this file existed.

namespace faceplan {

// True when libmetis's own calls reach the per-thread generator in this process (checked once, by
// ordering a small graph through CHOLMOD and watching this thread's generator being seeded). When
// false (a METIS built another way, or linked so that its calls bind inside itself), callers must
// serialise METIS calls with MetisMutex (FillReducingOrdering.h).
bool MetisRandomIsPerThread();

} // namespace faceplan
