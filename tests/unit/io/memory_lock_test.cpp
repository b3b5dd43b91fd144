// SPDX-License-Identifier: Apache-2.0
#include "io/linux/memory_lock.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace weedspray::io {
namespace {

constexpr std::array<std::string_view, 2> kOpenCvAndBlas = {"libopencv_", "libblas"};

TEST(MemoryLock, APageableLibraryIsKnownByItsFileName) {
  EXPECT_TRUE(
      is_pageable_library("/usr/lib/x86_64-linux-gnu/libopencv_dnn.so.4.6.0", kOpenCvAndBlas));
  EXPECT_TRUE(is_pageable_library("libblas.so.3", kOpenCvAndBlas));
  EXPECT_FALSE(is_pageable_library("/usr/lib/x86_64-linux-gnu/libc.so.6", kOpenCvAndBlas));
  EXPECT_FALSE(is_pageable_library("/opt/libopencv_/libc.so.6", kOpenCvAndBlas));
  EXPECT_FALSE(is_pageable_library("/usr/lib/libopencv_core.so", {}));
}

struct Mapping {
  std::string path;
  long size_kb = 0, rss_kb = 0;
  bool locked = false;  // VmFlags "lo" (Locked: counts shared pages in proportion)
};

// Every file mapping of this process with its Size, Rss and lock flag from /proc/self/smaps.
std::vector<Mapping> file_mappings() {
  std::vector<Mapping> mappings;
  std::ifstream smaps("/proc/self/smaps");
  std::string line;
  while (std::getline(smaps, line)) {
    std::istringstream fields(line);
    std::string first;
    fields >> first;
    if (first.find('-') != std::string::npos && first.back() != ':') {
      std::string perms, offset, device, inode, path;
      fields >> perms >> offset >> device >> inode >> path;
      mappings.push_back(
          Mapping{.path = perms.find_first_of("rwx") == std::string::npos ? "" : path});
      continue;
    }
    if (mappings.empty()) continue;
    if (first == "VmFlags:") {
      for (std::string flag; fields >> flag;)
        if (flag == "lo") mappings.back().locked = true;
      continue;
    }
    long kb = 0;
    fields >> kb;
    if (first == "Size:") mappings.back().size_kb = kb;
    if (first == "Rss:") mappings.back().rss_kb = kb;
  }
  std::erase_if(mappings, [](const Mapping& m) { return m.path.empty() || m.path[0] != '/'; });
  return mappings;
}

// In a child (a locked test process would stay locked): the program is read in and locked whole,
// libm (which every C++ program maps and this test names pageable) is not locked at all.
TEST(MemoryLock, TheProgramIsLockedWholeAndAPageableLibraryIsLeftOut) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer turns mlock and mlockall into no-ops";
#endif
  if (geteuid() != 0) GTEST_SKIP() << "locking a whole program needs root (CAP_IPC_LOCK)";
  int report[2];
  ASSERT_EQ(pipe(report), 0);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    close(report[0]);
    constexpr std::array<std::string_view, 1> kLibm = {"libm.so"};
    const MemoryLockResult locked = lock_memory_except(kLibm);
    std::string problems;
    if (locked.error != 0) problems += "mlockall failed: " + std::to_string(locked.error) + "\n";
    const std::string program = std::filesystem::read_symlink("/proc/self/exe").string();
    int program_mappings = 0, libm_mappings = 0;
    for (const Mapping& m : file_mappings()) {
      if (m.path == program) {
        ++program_mappings;
        if (!m.locked || m.rss_kb != m.size_kb)
          problems += "program mapping: size " + std::to_string(m.size_kb) + " kB, resident " +
                      std::to_string(m.rss_kb) + (m.locked ? ", locked\n" : ", not locked\n");
      } else if (is_pageable_library(m.path, kLibm)) {
        ++libm_mappings;
        if (m.locked) problems += m.path + ": locked\n";
      }
    }
    if (program_mappings == 0) problems += "no mapping of " + program + "\n";
    if (libm_mappings == 0 || locked.pageable_mappings != static_cast<std::size_t>(libm_mappings))
      problems += "libm mappings: " + std::to_string(libm_mappings) + " in smaps, " +
                  std::to_string(locked.pageable_mappings) + " left pageable\n";
    if (write(report[1], problems.data(), problems.size()) < 0) _exit(2);
    _exit(problems.empty() ? 0 : 1);
  }
  close(report[1]);
  std::string problems;
  std::array<char, 512> buffer;
  for (ssize_t n; (n = read(report[0], buffer.data(), buffer.size())) > 0;)
    problems.append(buffer.data(), static_cast<std::size_t>(n));
  close(report[0]);
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << problems;
}

}  // namespace
}  // namespace weedspray::io
