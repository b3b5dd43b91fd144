// SPDX-License-Identifier: Apache-2.0
#include "daemon/supervision/memory_residency.hpp"

#include <spdlog/spdlog.h>

#include <array>
#include <cstring>

#include "io/linux/memory_lock.hpp"

namespace weedspray::daemon {

namespace {

constexpr std::array<std::string_view, 16> kPageableLibraries = {
    "libopencv_",  "libopenblas", "liblapack", "libblas",     "libgfortran", "libquadmath",
    "libprotobuf", "libtbb",      "libX11",    "libxcb",      "libXau",      "libXdmcp",
    "libGL",       "libOpenGL",   "libjpeg",   "libturbojpeg"};

double megabytes(std::size_t bytes) {
  return static_cast<double>(bytes) / (1024.0 * 1024.0);
}

}  // namespace

std::span<const std::string_view> pageable_libraries() noexcept {
  return kPageableLibraries;
}

void lock_what_the_loops_run() {
  const io::MemoryLockResult locked = io::lock_memory_except(pageable_libraries());
  if (locked.error != 0) {
    spdlog::info("memory not locked (mlockall: {})", std::strerror(locked.error));
    return;
  }
  spdlog::info(
      "memory: {:.1f} MB of the program and its libraries locked ({} mappings), {:.1f} MB "
      "of the vision thread's libraries left pageable; heap and stacks locked as used",
      megabytes(locked.locked_bytes), locked.locked_mappings, megabytes(locked.pageable_bytes));
  if (locked.failed_mappings != 0)
    spdlog::warn("memory: {} mappings could not be locked (RLIMIT_MEMLOCK?)",
                 locked.failed_mappings);
}

}  // namespace weedspray::daemon
