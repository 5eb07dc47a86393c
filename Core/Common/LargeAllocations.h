// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// glibc raises its mmap threshold each time a large block is freed, so the next blocks of that size
// come from the heap and stay with the process after they are freed: every precompute of a new ROI
// or material then leaves its dense response and factor behind, and a long session's resident
// memory climbs to several working sets. A fixed threshold keeps blocks of 4 MiB and more mapped on
// their own, so freeing them returns them to the system.
namespace faceplan {

// Sets the fixed threshold once per process (later calls do nothing). Leaves glibc's choice when
// the user set MALLOC_MMAP_THRESHOLD_ (non-empty), and does nothing on other C libraries. Returns
// whether the threshold is now FacePlan's.
bool ReturnLargeAllocationsToSystem();

} // namespace faceplan
