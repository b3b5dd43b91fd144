// SPDX-License-Identifier: Apache-2.0
#include "daemon/records/run_marker.hpp"

#include <unistd.h>

#include <string>
#include <system_error>

#include "daemon/records/atomic_file.hpp"

namespace weedspray::daemon {

RunMarker::RunMarker(std::filesystem::path file) : file_(std::move(file)) {
  std::error_code ec;
  previous_run_unfinished_ = std::filesystem::exists(file_, ec);
  write_file_atomically(file_, "pid = " + std::to_string(::getpid()) + "\n");
}

void RunMarker::finish() noexcept {
  std::error_code ec;
  std::filesystem::remove(file_, ec);
}

}  // namespace weedspray::daemon
