// SPDX-License-Identifier: Apache-2.0
// Which memory stays in RAM. A real-time thread must never wait on a page fault that reads from
// storage, so what they run is read in and locked at start: the program and every library it
// maps, except those named pageable (code only the vision thread runs, e.g. OpenCV's and BLAS's,
// which is most of the mapped code). Anonymous memory (heap, stacks) is locked as it is first
// touched (MCL_ONFAULT): the loops allocate and touch theirs before they start, and a malloc
// arena's reserved but unused address space costs no RAM. Locking every mapping whole
// (mlockall without MCL_ONFAULT) would hold each mapped library entire, and each thread's
// 8 MB stack, in a 2 GB board's RAM.
#pragma once

#include <cstddef>
#include <span>
#include <string_view>

namespace weedspray::io {

struct MemoryLockResult {
  int error = 0;  // 0, or the errno of mlockall (EPERM: not permitted; then nothing is locked)
  std::size_t locked_mappings = 0;    // file mappings read in and locked
  std::size_t locked_bytes = 0;       // their size
  std::size_t pageable_mappings = 0;  // file mappings of the pageable libraries, left unlocked
  std::size_t pageable_bytes = 0;
  std::size_t failed_mappings = 0;  // file mappings mlock refused (counted, not fatal)
};

// True when `path`'s file name starts with one of `prefixes` ("libopencv_" matches
// /usr/lib/x86_64-linux-gnu/libopencv_dnn.so.4.6.0).
bool is_pageable_library(std::string_view path,
                         std::span<const std::string_view> prefixes) noexcept;

// mlockall(MCL_CURRENT | MCL_FUTURE | MCL_ONFAULT), then every file mapping of /proc/self/maps
// is locked whole (read in now) unless it belongs to a pageable library, whose mappings are
// unlocked. Start-up only: it reads /proc and allocates.
MemoryLockResult lock_memory_except(std::span<const std::string_view> pageable_prefixes);

}  // namespace weedspray::io
