#pragma once
// Vectors whose resize() leaves new elements uninitialised (trivial types): for large buffers a
// parallel loop fills whole, so that their pages are first touched (faulted in) by the threads
// that fill them instead of by a serial zero-fill before the loop.

#include <memory>
#include <type_traits>
#include <utility>
#include <vector>

namespace meshflow {

/// std::allocator whose construct() without arguments default-initialises (for a trivial type:
/// writes nothing); with arguments it constructs as std::allocator does. Thread-safety and
/// complexity those of std::allocator.
template <class T, class A = std::allocator<T>>
class DefaultInitAllocator : public A {
  using Traits = std::allocator_traits<A>;

 public:
  template <class U>
  struct rebind {  // NOLINT(readability-identifier-naming): the allocator requirements' name
    using other = DefaultInitAllocator<U, typename Traits::template rebind_alloc<U>>;
  };
  using A::A;
  /// Default-initialises a U at p (a trivial U: nothing written). O(1).
  template <class U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible<U>::value) {
    ::new (static_cast<void*>(p)) U;
  }
  /// Constructs a U at p from args, as std::allocator does.
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    Traits::construct(static_cast<A&>(*this), p, std::forward<Args>(args)...);
  }
};

/// A vector whose resize() default-initialises new elements (leaves trivial ones unwritten).
template <class T>
using UninitVector = std::vector<T, DefaultInitAllocator<T>>;

}  // namespace meshflow
