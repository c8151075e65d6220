#pragma once
// A memory allocator policy for a process that meshes: the meshflow programs call it first
// thing; an application embedding meshflow may (the library itself never touches the
// allocator).
//
// A meshing process touches tens to hundreds of MB once: kurt3d scan000 at 5 cm faulted in
// 13 600 pages of 4 KiB (about a third of its CPU time on a VM, where every fault is a trap to
// the hypervisor), and buffers freed between stages went back to the kernel to be faulted in
// again by the next. tune_process_heap() keeps the C library's heap for the process's life and
// asks for transparent huge pages on it, so the same run faults about 600 times.

namespace meshflow {

/// Sets glibc's malloc up for one meshing process: one heap shared by all threads (the main
/// one, grown by brk), allocations up to 32 MiB served from it instead of fresh mappings,
/// freed memory kept for reuse instead of returned to the kernel, the heap grown in large steps
/// and the first 256 MiB flagged for transparent huge pages (MADV_HUGEPAGE; the kernel honours
/// it where /sys/kernel/mm/transparent_hugepage/enabled is "madvise" or "always"). Untouched
/// heap is only address space: resident memory grows with what the run uses.
/// Call first in main, before any thread starts; not thread-safe. Worth it for processes that
/// mesh and exit or mesh frame after frame; it trades memory given back for speed. Returns false
/// where the C library is not glibc or the heap could not be grown in one step (nothing is changed
/// then, apart from malloc's tuning parameters). O(1).
bool tune_process_heap();

}  // namespace meshflow
