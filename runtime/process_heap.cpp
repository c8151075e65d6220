#include "runtime/process_heap.h"

#include <cstdint>
#include <cstdlib>

#if defined(__GLIBC__)
#include <malloc.h>
#include <sys/mman.h>
#include <unistd.h>
#endif

namespace meshflow {

#if defined(__GLIBC__)

namespace {

constexpr int kMiB = 1 << 20;
constexpr int kLargestFromHeap = 32 * kMiB;  // glibc's upper limit for M_MMAP_THRESHOLD
constexpr int kFirstGrowth = 256 * kMiB;     // address space reserved and flagged at once
constexpr int kLaterGrowth = 64 * kMiB;
constexpr std::uintptr_t kHugePage = 2u * kMiB;

}  // namespace

bool tune_process_heap() {
  mallopt(M_ARENA_MAX, 1);
  mallopt(M_MMAP_THRESHOLD, kLargestFromHeap);
  mallopt(M_TRIM_THRESHOLD, 0x7fffffff);  // never give the heap's top back
  mallopt(M_TOP_PAD, kFirstGrowth);
  // One allocation larger than what the heap has left makes malloc grow it by the allocation
  // plus the top pad; freed, it stays in the heap (no trim), so the whole grown range is there
  // for the run's buffers. (volatile: the compiler may not drop the pair.)
  auto* const before = static_cast<char*>(sbrk(0));
  void* volatile probe = std::malloc(4 * kMiB);
  std::free(probe);
  auto* const after = static_cast<char*>(sbrk(0));
  mallopt(M_TOP_PAD, kLaterGrowth);
  const auto from = reinterpret_cast<std::uintptr_t>(before);
  const auto to = reinterpret_cast<std::uintptr_t>(after);
  const bool grown = from != ~std::uintptr_t{0} && to > from && to - from > kFirstGrowth / 2;
  if (!grown) return false;  // sbrk failed (returns -1) or malloc took memory elsewhere
  // Whole huge pages inside the grown range.
  char* const begin = before + (kHugePage - from % kHugePage) % kHugePage;
  char* const end = after - to % kHugePage;
  if (end <= begin) return false;
  return madvise(begin, static_cast<std::size_t>(end - begin), MADV_HUGEPAGE) == 0;
}

#else

bool tune_process_heap() { return false; }

#endif

}  // namespace meshflow
