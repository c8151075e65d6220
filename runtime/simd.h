#pragma once
// Vector code that stays portable: MESHFLOW_AVX2_CLONES and the vector value types below.
//
// MESHFLOW_AVX2_CLONES: put before a function whose loops vectorise; on x86-64 Linux (GCC or
// Clang) the compiler builds it twice, for AVX2 and for the baseline instruction set, and the
// loader picks the variant the CPU supports (function multi-versioning through an ifunc). The
// build stays portable and the binary uses 8-wide vectors where they exist. Empty elsewhere and
// under the sanitizers (their runtimes start after ifunc resolvers run).

#if defined(__x86_64__) && defined(__linux__) && (defined(__GNUC__) || defined(__clang__)) && \
    !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
#define MESHFLOW_AVX2_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define MESHFLOW_AVX2_CLONES
#endif

#include <cstdint>

namespace meshflow::simd {

// Vector values (GCC / Clang vector extensions): operators apply lane by lane, a scalar operand
// to every lane, comparisons give all ones or zero per lane. A 32-byte type is one AVX2 register
// in a function built for AVX2 (MESHFLOW_AVX2_CLONES), two SSE registers otherwise. Keep such
// values inside functions (pass them by reference), so that no call depends on the vector ABI
// of a clone.
using Floats8 = float __attribute__((vector_size(32)));
using Ints8 = std::int32_t __attribute__((vector_size(32)));
using Doubles4 = double __attribute__((vector_size(32)));
using Uints4 = std::uint32_t __attribute__((vector_size(16)));  ///< one SSE register

}  // namespace meshflow::simd
