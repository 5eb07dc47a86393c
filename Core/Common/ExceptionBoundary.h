// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Core's one exception boundary. Core code reports its failures as Status and throws nothing
// itself; what can still throw is the allocator (std::bad_alloc from Eigen and the standard
// library) and the standard library's own checks. Every public entry that allocates runs its body
// through ReturnStatusOnException, so no exception crosses Core's interface.
#include "Common/Status.h"

#include <exception>
#include <new>
#include <string>

namespace faceplan {

// Runs body() (which returns Status); an exception becomes an error naming `operation`.
template <class Body> Status ReturnStatusOnException(const char* operation, Body&& body) noexcept {
  try {
    return body();
  } catch (const std::bad_alloc&) {
    return Status::Error(std::string("out of memory during ") + operation);
  } catch (const std::exception& e) {
    return Status::Error(std::string(operation) + " failed: " + e.what());
  } catch (...) {
    return Status::Error(std::string(operation) + " failed");
  }
}

} // namespace faceplan
