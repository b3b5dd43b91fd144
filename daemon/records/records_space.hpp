// SPDX-License-Identifier: Apache-2.0
// The records_disk_full condition, judged by the as-applied writer thread once a second (a
// statvfs can block on a busy card: never in a real-time loop).
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>

#include "daemon/records/as_applied_log.hpp"

namespace weedspray::daemon {

// Bytes the daemon's (unprivileged) user may still write in `dir`'s file system (statvfs
// f_bavail); std::nullopt when it cannot be read.
std::optional<std::uint64_t> available_bytes(const std::filesystem::path& dir);

// Records are at risk while a write fails or lines wait in memory, or when the free space is
// under `floor_bytes` (unknown free space alone is not judged).
bool records_at_risk(const AsAppliedHealth& health, std::optional<std::uint64_t> available,
                     std::uint64_t floor_bytes);

}  // namespace weedspray::daemon
