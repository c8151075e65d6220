#include "runtime/process_heap.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>

namespace {

constexpr int kSkipped = 77;

// The VmFlags line of the /proc/self/smaps mapping holding `address` ("" if none does).
std::string vm_flags_at(const void* address) {
  const auto target = reinterpret_cast<std::uintptr_t>(address);
  std::ifstream smaps("/proc/self/smaps");
  std::string line;
  bool inside = false;
  while (std::getline(smaps, line)) {
    std::uintptr_t begin = 0, end = 0;  // a mapping's first line: "begin-end perms ..."
    if (std::sscanf(line.c_str(), "%lx-%lx ", &begin, &end) == 2)
      inside = begin <= target && target < end;
    if (inside && line.rfind("VmFlags:", 0) == 0) return line;
  }
  return "";
}

// In a child process (the policy is process-wide): 0 when the policy holds, else which part
// failed; kSkipped where the allocator is not glibc's brk heap (sanitizer builds).
int check_policy_in_this_process() {
  if (!meshflow::tune_process_heap()) return kSkipped;
  const void* const heap_end = sbrk(0);
  constexpr std::size_t kBuffer = 8u << 20;  // above glibc's default mmap threshold (128 KiB)
  auto* const buffer = static_cast<char*>(std::malloc(kBuffer));
  if (buffer == nullptr) return 1;
  std::memset(buffer, 1, kBuffer);
  if (buffer + kBuffer > static_cast<const char*>(heap_end)) return 2;  // not from the heap
  // Its end (its start may lie below the first 2 MiB boundary of the grown heap, left unflagged).
  if (vm_flags_at(buffer + kBuffer - 1).find(" hg") == std::string::npos) return 3;
  std::free(buffer);
  if (sbrk(0) != heap_end) return 4;  // the heap was trimmed or grew
  return 0;
}

TEST(ProcessHeap, LargeBuffersComeFromAKeptHeapFlaggedForHugePages) {
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) _exit(check_policy_in_this_process());
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  const int code = WEXITSTATUS(status);
  if (code == kSkipped) GTEST_SKIP() << "the allocator is not glibc's malloc (sanitizer build?)";
  EXPECT_EQ(code, 0) << "1: malloc failed, 2: an 8 MiB buffer was mapped outside the heap, "
                        "3: the heap is not flagged for huge pages, 4: freeing changed the heap";
}

}  // namespace
