// SPDX-License-Identifier: Apache-2.0
// A small state file replaced whole: written to "<file>.tmp", fsync'd, renamed over the old one,
// so a power cut leaves either the old or the new contents, never half of each.
#pragma once

#include <filesystem>
#include <string_view>

namespace weedspray::daemon {

// Throws std::runtime_error naming the file.
void write_file_atomically(const std::filesystem::path& file, std::string_view contents);

}  // namespace weedspray::daemon
