#pragma once
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
