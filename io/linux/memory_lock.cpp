// SPDX-License-Identifier: Apache-2.0
#include "io/linux/memory_lock.hpp"

#include <sys/mman.h>

#include <cerrno>
#include <cstdint>
#include <fstream>
#include <sstream>
#include <string>

namespace weedspray::io {

bool is_pageable_library(std::string_view path,
                         std::span<const std::string_view> prefixes) noexcept {
  const std::size_t slash = path.rfind('/');
  const std::string_view name = slash == std::string_view::npos ? path : path.substr(slash + 1);
  for (std::string_view prefix : prefixes)
    if (!prefix.empty() && name.starts_with(prefix)) return true;
  return false;
}

MemoryLockResult lock_memory_except(std::span<const std::string_view> pageable_prefixes) {
  MemoryLockResult result;
  if (mlockall(MCL_CURRENT | MCL_FUTURE | MCL_ONFAULT) != 0) {
    result.error = errno;
    return result;
  }
  std::ifstream maps("/proc/self/maps");
  std::string line;
  while (std::getline(maps, line)) {
    // start-end perms offset dev inode [path]
    std::istringstream fields(line);
    std::string range, perms, offset, device, inode, path;
    fields >> range >> perms >> offset >> device >> inode >> path;
    if (path.empty() || path.front() != '/') continue;  // anonymous, [heap], [stack], [vdso]
    if (perms.find_first_of("rwx") == std::string::npos) continue;  // a guard: nothing to read
    const std::size_t dash = range.find('-');
    if (dash == std::string::npos) continue;
    const auto start = static_cast<std::uintptr_t>(std::stoull(range.substr(0, dash), nullptr, 16));
    const auto end = static_cast<std::uintptr_t>(std::stoull(range.substr(dash + 1), nullptr, 16));
    void* address = reinterpret_cast<void*>(start);
    const std::size_t bytes = end - start;
    if (is_pageable_library(path, pageable_prefixes)) {
      munlock(address, bytes);
      ++result.pageable_mappings;
      result.pageable_bytes += bytes;
    } else if (mlock(address, bytes) == 0) {
      ++result.locked_mappings;
      result.locked_bytes += bytes;
    } else {
      ++result.failed_mappings;
    }
  }
  return result;
}

}  // namespace weedspray::io
