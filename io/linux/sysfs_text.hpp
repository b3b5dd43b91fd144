// SPDX-License-Identifier: Apache-2.0
// First line of a sysfs (or any text) attribute, shared by the backends that find their device
// by its sysfs `name` (IIO ADCs, the counter subsystem).
#pragma once

#include <filesystem>
#include <string>

namespace weedspray::io::hw {

// The file's first line without its newline; "" if it cannot be opened or is empty.
std::string read_first_line(const std::filesystem::path& path);

}  // namespace weedspray::io::hw
