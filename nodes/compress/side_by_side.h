#pragma once
// Two independent jobs of a decoder side by side: on two threads where oneTBB allows two (its
// parallel_invoke), one after the other where it allows one or is absent (the WebAssembly
// decoder, web/CMakeLists.txt, builds without it). Errors come out the same either way.

#include <exception>

#ifndef __EMSCRIPTEN__
#include <tbb/parallel_invoke.h>
#endif

namespace meshflow::compress {

/// Runs first() and second() and returns when both have; they must not touch the same data.
/// If either throws, rethrows first()'s exception when it threw, else second()'s (both run to
/// their end or their own throw): the same error at any thread count. O(their work).
template <typename First, typename Second>
void side_by_side(First&& first, Second&& second) {
  std::exception_ptr first_error, second_error;
  const auto run_first = [&] {
    try {
      first();
    } catch (...) {
      first_error = std::current_exception();
    }
  };
  const auto run_second = [&] {
    try {
      second();
    } catch (...) {
      second_error = std::current_exception();
    }
  };
#ifdef __EMSCRIPTEN__
  run_first();
  run_second();
#else
  tbb::parallel_invoke(run_first, run_second);
#endif
  if (first_error) std::rethrow_exception(first_error);
  if (second_error) std::rethrow_exception(second_error);
}

}  // namespace meshflow::compress
