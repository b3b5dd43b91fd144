// SPDX-License-Identifier: Apache-2.0
// The exit watcher's two tools: seeing the daemon begin to die (PF_EXITING / zombie, never a
// stopped process) and receiving the daemon's safe writes with copies of their descriptors.
#include <fcntl.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "daemon/backends/emergency_write_handoff.hpp"
#include "daemon/backends/safe_outputs_watch.hpp"
#include "daemon/supervision/process_exit_probe.hpp"
#include "io/emergency_outputs.hpp"

namespace weedspray::daemon {
namespace {

using namespace std::chrono_literals;

bool says_exiting(const std::string& line) {
  return stat_line_says_exiting(line.data(), line.size());
}

TEST(ProcessExitProbe, ReadsTheFlagsFieldAfterTheLastParenthesis) {
  // flags 4194560 = 0x400100 (PF_RANDOMIZE | PF_FORKNOEXEC): running, not exiting.
  EXPECT_FALSE(says_exiting("42 (weedsprayd) S 1 42 42 0 -1 4194560 130 0 0 0\n"));
  // The same with PF_EXITING (0x4) set: 4194564.
  EXPECT_TRUE(says_exiting("42 (weedsprayd) R 1 42 42 0 -1 4194564 130 0 0 0\n"));
  // A command name with spaces and a ") 4 " inside must not shift the fields.
  EXPECT_FALSE(says_exiting("42 (a) 4 4 4 4 4 4 b) S 1 42 42 0 -1 4194560 130\n"));
  EXPECT_TRUE(says_exiting("42 (a) 4 4 4 4 4 4 b) S 1 42 42 0 -1 4194564 130\n"));
  EXPECT_TRUE(says_exiting("42 (weedsprayd) Z 1 42 42 0 -1 4194560 130\n"));
  EXPECT_FALSE(says_exiting("42 (weedsprayd) T 1 42 42 0 -1 4194560 130\n"));  // stopped
  EXPECT_FALSE(says_exiting("42 (weedsprayd"));
  EXPECT_FALSE(says_exiting("42 (weedsprayd) S 1 42"));
}

TEST(ProcessExitProbe, SeesAKilledChildButNotAStoppedOne) {
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    for (;;) pause();
  }
  const ProcessExitProbe probe(child);
  ASSERT_TRUE(probe.valid());
  EXPECT_FALSE(probe.exiting());
  // Stopped (a hung daemon looks like this to the watcher): not its business.
  ASSERT_EQ(kill(child, SIGSTOP), 0);
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, WUNTRACED), child);
  ASSERT_TRUE(WIFSTOPPED(status));
  for (int i = 0; i < 10; ++i) {
    EXPECT_FALSE(probe.exiting());
    std::this_thread::sleep_for(2ms);
  }
  ASSERT_EQ(kill(child, SIGKILL), 0);
  const auto deadline = std::chrono::steady_clock::now() + 5s;
  bool seen = false;
  while (!(seen = probe.exiting()) && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(1ms);
  EXPECT_TRUE(seen) << "SIGKILL not seen before the child was reaped";
  ASSERT_EQ(waitpid(child, &status, 0), child);
  EXPECT_TRUE(probe.exiting()) << "a reaped process must read as ended";
}

TEST(EmergencyWriteHandoff, TheReceiverWritesThroughItsOwnCopyOfTheDescriptor) {
  char path[] = "/tmp/weedspray-handoff-XXXXXX";
  const int file = mkstemp(path);
  ASSERT_GE(file, 0);
  unlink(path);
  ASSERT_EQ(write(file, "1\n", 2), 2);  // an output "open"
  int fds[2];
  ASSERT_EQ(socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, fds), 0);
  io::EmergencyOutputs::clear();
  io::EmergencyWrite safe;
  safe.kind = io::EmergencyWrite::Kind::kPwrite;
  safe.fd = file;
  std::memcpy(safe.payload.data(), "0\n", 2);
  safe.length = 2;
  ASSERT_TRUE(io::EmergencyOutputs::add(safe));
  ASSERT_EQ(hand_emergency_writes(fds[0]), 1);
  io::EmergencyOutputs::clear();
  close(fds[0]);  // the sender is gone: its message is still there, then end-of-file

  io::EmergencyWrite received;
  ASSERT_EQ(receive_emergency_write(fds[1], received), 1);
  EXPECT_NE(received.fd, file);
  EXPECT_EQ(received.kind, io::EmergencyWrite::Kind::kPwrite);
  EXPECT_EQ(received.length, 2U);
  close(file);  // only the received copy keeps the file open now
  ASSERT_TRUE(io::EmergencyOutputs::add(received));
  EXPECT_EQ(io::EmergencyOutputs::trigger(), 0);
  char text[3] = {};
  EXPECT_EQ(pread(received.fd, text, 2, 0), 2);
  EXPECT_STREQ(text, "0\n");
  io::EmergencyOutputs::clear();
  close(received.fd);
  EXPECT_EQ(receive_emergency_write(fds[1], received), 0);
  close(fds[1]);
}

TEST(EmergencyWriteHandoff, AMessageWithoutADescriptorIsRefused) {
  int fds[2];
  ASSERT_EQ(socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, fds), 0);
  const io::EmergencyWrite bare;
  ASSERT_EQ(send(fds[0], &bare, sizeof bare, 0), static_cast<ssize_t>(sizeof bare));
  io::EmergencyWrite received;
  EXPECT_EQ(receive_emergency_write(fds[1], received), -EBADMSG);
  close(fds[0]);
  close(fds[1]);
}

}  // namespace
}  // namespace weedspray::daemon

namespace weedspray::daemon {
namespace {

using namespace std::chrono_literals;

// After the daemon is gone, the watcher requests every line at its safe value; a line the
// kernel has not released from the dying daemon yet is busy, and only that is retried.
TEST(ExitWatcherRetry, ABusyLineIsRetriedUntilItIsFree) {
  int calls = 0;
  std::vector<SafeWriteFailure> failures;
  const int attempts = write_retrying_busy_lines(
      [&](std::vector<SafeWriteFailure>& out) {
        if (++calls <= 2)
          out.push_back(
              {"pump: line offset 4 on GPIO chip 'gpiochip0' is busy (used by "
               "'weedsprayd')",
               true});
      },
      failures, 2s, 1ms);
  EXPECT_EQ(attempts, 3);
  EXPECT_EQ(calls, 3);
  EXPECT_TRUE(failures.empty());
}

TEST(ExitWatcherRetry, AMissingDeviceIsNotRetried) {
  std::vector<SafeWriteFailure> failures;
  const int attempts = write_retrying_busy_lines(
      [](std::vector<SafeWriteFailure>& out) {
        out.push_back({"valves: GPIO chip 'gpiochip9' not found or not accessible", false});
      },
      failures, 2s, 1ms);
  EXPECT_EQ(attempts, 1);
  ASSERT_EQ(failures.size(), 1U);
}

TEST(ExitWatcherRetry, ALineBusyForGoodIsGivenUpAfterTheRetryTime) {
  std::vector<SafeWriteFailure> failures;
  const auto start = std::chrono::steady_clock::now();
  const int attempts = write_retrying_busy_lines(
      [](std::vector<SafeWriteFailure>& out) {
        out.push_back({"led: busy", true});
      },
      failures, 50ms, 5ms);
  const auto took = std::chrono::steady_clock::now() - start;
  EXPECT_GT(attempts, 2);
  EXPECT_GE(took, 50ms);
  EXPECT_LT(took, 1s);
  ASSERT_EQ(failures.size(), 1U);
  EXPECT_TRUE(failures.front().line_busy);
}

}  // namespace
}  // namespace weedspray::daemon
