// SPDX-License-Identifier: Apache-2.0
// The as-applied log on a full disk: no torn line ever, lines held and written in order when
// space returns, dropped lines counted and visible as a seq gap.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "daemon/records/as_applied_log.hpp"
#include "daemon/records/line_appender.hpp"

namespace weedspray::daemon {
namespace {

namespace fs = std::filesystem;

// A disk with `space_left` bytes: a write past it lands short (what lands is on the file), one
// with nothing left fails with ENOSPC, as write(2) does on a full file system.
struct FakeDisk {
  static inline std::size_t space_left = SIZE_MAX;
  static ssize_t write(int fd, const void* data, std::size_t size) {
    if (space_left == 0) {
      errno = ENOSPC;
      return -1;
    }
    const std::size_t n = std::min(size, space_left);
    const ssize_t written = ::write(fd, data, n);
    if (written > 0) space_left -= static_cast<std::size_t>(written);
    return written;
  }
};

class AsAppliedFullDisk : public ::testing::Test {
 protected:
  void SetUp() override {
    FakeDisk::space_left = SIZE_MAX;
    dir_ = fs::temp_directory_path() /
           ("weedspray-full-disk-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
  }
  void TearDown() override {
    FakeDisk::space_left = SIZE_MAX;
    fs::remove_all(dir_);
  }

  static AppliedRecord record(int i) {
    AppliedRecord r;
    r.time = std::chrono::milliseconds(200 * i);
    r.volume_l = 0.01;
    r.nozzles = 3;
    r.duty_pct = {25, 50, 75};
    return r;
  }

  // The seq of every line of every file, in file order; fails on any line that is not whole
  // (no newline, or not the header's column count).
  std::vector<std::uint64_t> seqs_on_disk() const {
    std::vector<fs::path> files;
    for (const auto& entry : fs::directory_iterator(dir_)) files.push_back(entry.path());
    std::sort(files.begin(), files.end());
    std::vector<std::uint64_t> seqs;
    for (const auto& file : files) {
      std::ifstream in(file, std::ios::binary);
      std::stringstream text;
      text << in.rdbuf();
      const std::string content = text.str();
      EXPECT_FALSE(content.empty()) << file;
      if (content.empty()) continue;
      EXPECT_EQ(content.back(), '\n') << file << ": torn last line";
      std::istringstream lines(content);
      std::string header;
      std::getline(lines, header);
      EXPECT_TRUE(header.ends_with(",seq")) << header;
      const auto columns = std::count(header.begin(), header.end(), ',');
      std::string line;
      while (std::getline(lines, line)) {
        EXPECT_EQ(std::count(line.begin(), line.end(), ','), columns) << file << ": " << line;
        seqs.push_back(std::stoull(line.substr(line.rfind(',') + 1)));
      }
    }
    return seqs;
  }

  static std::vector<std::uint64_t> range(std::uint64_t first, std::uint64_t last) {
    std::vector<std::uint64_t> out;
    for (std::uint64_t s = first; s <= last; ++s) out.push_back(s);
    return out;
  }

  fs::path dir_;
};

TEST_F(AsAppliedFullDisk, NoTornLineAndTheHeldLinesGoOutInOrderWhenSpaceReturns) {
  AsAppliedLog log(dir_, 1 << 20, 5, {}, kHeldLinesMaxBytes, &FakeDisk::write);
  for (int i = 0; i < 10; ++i) ASSERT_TRUE(log.write(record(i)));
  log.flush();
  EXPECT_EQ(seqs_on_disk(), range(1, 10));
  // The disk fills up in the middle of the 11th line.
  FakeDisk::space_left = 40;
  EXPECT_FALSE(log.write(record(10)));
  EXPECT_EQ(seqs_on_disk(), range(1, 10)) << "the part of line 11 that landed is cut off";
  EXPECT_EQ(log.health().error, ENOSPC);
  for (int i = 11; i < 30; ++i) EXPECT_FALSE(log.write(record(i)));
  for (int second = 0; second < 3; ++second) log.flush();  // still full: nothing goes out
  EXPECT_EQ(seqs_on_disk(), range(1, 10));
  AsAppliedHealth health = log.health();
  EXPECT_EQ(health.error, ENOSPC);
  EXPECT_EQ(health.held_lines, 20U);
  EXPECT_EQ(health.dropped_lines, 0U);
  EXPECT_GE(health.write_errors, 4U);

  FakeDisk::space_left = SIZE_MAX;  // space freed
  EXPECT_FALSE(log.write(record(30))) << "held behind the older lines, in order";
  log.flush();
  health = log.health();
  EXPECT_EQ(health.error, 0);
  EXPECT_EQ(health.held_lines, 0U);
  EXPECT_TRUE(log.write(record(31)));
  log.flush();
  EXPECT_EQ(seqs_on_disk(), range(1, 32));
}

TEST_F(AsAppliedFullDisk, LinesPastTheBoundAreDroppedCountedAndLeaveASeqGap) {
  // Room in memory for about 5 lines.
  std::string one_line;
  {
    AsAppliedLog probe(dir_ / "probe", 1 << 20, 5);
    probe.write(record(0));
    probe.flush();
    std::ifstream in(probe.current_file());
    std::getline(in, one_line);
    std::getline(in, one_line);
  }
  fs::remove_all(dir_ / "probe");
  AsAppliedLog log(dir_, 1 << 20, 5, {}, 5 * (one_line.size() + 1) + 2, &FakeDisk::write);
  ASSERT_TRUE(log.write(record(0)));
  FakeDisk::space_left = 0;
  for (int i = 1; i <= 20; ++i) EXPECT_FALSE(log.write(record(i)));
  log.flush();
  EXPECT_EQ(log.health().held_lines, 5U);
  EXPECT_EQ(log.health().dropped_lines, 15U);
  FakeDisk::space_left = SIZE_MAX;
  log.flush();
  ASSERT_TRUE(log.write(record(21)));
  log.flush();
  // Seq 1, the five held (2..6), then the gap of the 15 dropped (7..21), then 22.
  std::vector<std::uint64_t> expected = range(1, 6);
  expected.push_back(22);
  EXPECT_EQ(seqs_on_disk(), expected);
  EXPECT_EQ(log.health().dropped_lines, 15U);
  EXPECT_EQ(log.health().error, 0);
}

TEST_F(AsAppliedFullDisk, SeqRunsOnAcrossRotationAndAFullDiskAtTheNewHeader) {
  AsAppliedLog log(dir_, 4096, 100, {}, kHeldLinesMaxBytes, &FakeDisk::write);
  int i = 0;
  for (; i < 100; ++i) log.write(record(i));
  log.flush();
  // Full at whatever point comes next, rotation and its header included, then free again.
  for (std::size_t left : {0UL, 7UL, 120UL, 300UL, 0UL}) {
    FakeDisk::space_left = left;
    for (int k = 0; k < 37; ++k) log.write(record(i++));
    log.flush();
  }
  FakeDisk::space_left = SIZE_MAX;
  log.flush();
  for (int k = 0; k < 50; ++k) log.write(record(i++));
  log.flush();
  EXPECT_EQ(log.health().dropped_lines, 0U);
  EXPECT_EQ(seqs_on_disk(), range(1, static_cast<std::uint64_t>(i)));
}

TEST(LineAppender, ARealShortWriteAtTheFileSizeLimitIsCutBack) {
  // RLIMIT_FSIZE makes the kernel write a line only part-way (then EFBIG), as a full disk does;
  // in a child, since the limit holds for the whole process.
  const fs::path file =
      fs::temp_directory_path() / ("weedspray-fsize-" + std::to_string(::getpid()) + ".csv");
  fs::remove(file);
  const std::string line = "0123456789,abcdefghij,0123456789\n";  // 33 bytes
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    std::signal(SIGXFSZ, SIG_IGN);
    const rlimit limit{100, 100};  // 3 lines and part of a 4th
    if (::setrlimit(RLIMIT_FSIZE, &limit) != 0) ::_exit(10);
    LineAppender appender;
    if (appender.open(file) != 0) ::_exit(11);
    for (int i = 0; i < 3; ++i) {
      if (appender.append(line) != 0) ::_exit(12);
    }
    // Each try lands 1 byte (short: reported as ENOSPC), which is cut off again.
    for (int i = 0; i < 2; ++i) {
      if (appender.append(line) != ENOSPC) ::_exit(13);
    }
    ::_exit(appender.size() == 3 * line.size() ? 0 : 14);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  std::ifstream in(file, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(), line + line + line);
  fs::remove(file);
}

TEST(LineAppender, OpeningAFileCutsItsTornLastLine) {
  const fs::path file =
      fs::temp_directory_path() / ("weedspray-torn-" + std::to_string(::getpid()) + ".csv");
  std::ofstream(file, std::ios::binary) << "a,b\n1,2\n3,";
  LineAppender appender;
  ASSERT_EQ(appender.open(file), 0);
  EXPECT_EQ(appender.size(), 8U);
  ASSERT_EQ(appender.append("5,6\n"), 0);
  appender.close();
  std::ifstream in(file, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(), "a,b\n1,2\n5,6\n");
  fs::remove(file);
}

}  // namespace
}  // namespace weedspray::daemon
