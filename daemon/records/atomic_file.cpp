// SPDX-License-Identifier: Apache-2.0
#include "daemon/records/atomic_file.hpp"

#include <unistd.h>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <string>
#include <system_error>

namespace weedspray::daemon {

void write_file_atomically(const std::filesystem::path& file, std::string_view contents) {
  const auto temp = std::filesystem::path(file.string() + ".tmp");
  {
    std::ofstream out(temp, std::ios::trunc);
    if (!out) throw std::runtime_error(temp.string() + ": cannot be written");
    out << contents;
    out.flush();
    if (!out) throw std::runtime_error(temp.string() + ": write failed");
  }
  // fsync the data before the rename so a power cut leaves either the old or the new file.
  if (FILE* f = std::fopen(temp.c_str(), "r")) {
    ::fsync(fileno(f));
    std::fclose(f);
  }
  std::error_code ec;
  std::filesystem::rename(temp, file, ec);
  if (ec) throw std::runtime_error(file.string() + ": " + ec.message());
}

}  // namespace weedspray::daemon
