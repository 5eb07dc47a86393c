// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A std::vector whose resize() leaves new elements of trivial types uninitialized. A large buffer
// that parallel workers then fill completely is first touched by those workers, so its page faults
// (Benchmarks/kernel_probe measures their cost) spread over the cores instead of running in one
// thread's zero-fill before the work starts.
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace faceplan {

template <class T> struct DefaultInitAllocator : std::allocator<T> {
  template <class U> struct rebind { using other = DefaultInitAllocator<U>; };
  DefaultInitAllocator() = default;
  template <class U> DefaultInitAllocator(const DefaultInitAllocator<U>&) noexcept {}

  template <class U> void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U; // default-initialization: no zero-fill for double
  }
  template <class U, class... Args> void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

template <class T> using UninitializedVector = std::vector<T, DefaultInitAllocator<T>>;

} // namespace faceplan
