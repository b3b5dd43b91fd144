// SPDX-License-Identifier: Apache-2.0
#include "daemon/records/records_space.hpp"

#include <sys/statvfs.h>

namespace weedspray::daemon {

std::optional<std::uint64_t> available_bytes(const std::filesystem::path& dir) {
  struct statvfs fs {};
  if (::statvfs(dir.c_str(), &fs) != 0) return std::nullopt;
  return static_cast<std::uint64_t>(fs.f_bavail) * fs.f_frsize;
}

bool records_at_risk(const AsAppliedHealth& health, std::optional<std::uint64_t> available,
                     std::uint64_t floor_bytes) {
  if (health.error != 0 || health.held_lines > 0) return true;
  return available.has_value() && *available < floor_bytes;
}

}  // namespace weedspray::daemon
