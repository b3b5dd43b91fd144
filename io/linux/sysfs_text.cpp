// SPDX-License-Identifier: Apache-2.0
#include "io/linux/sysfs_text.hpp"

#include <fstream>

namespace weedspray::io::hw {

std::string read_first_line(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::string text;
  if (!in || !std::getline(in, text)) return {};
  return text;
}

}  // namespace weedspray::io::hw
