// SPDX-License-Identifier: Apache-2.0
#include "daemon/backends/safe_outputs_watch.hpp"

#include <poll.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "daemon/backends/backends.hpp"
#include "daemon/backends/emergency_write_handoff.hpp"
#include "daemon/backends/output_manifest.hpp"
#include "daemon/supervision/process_exit_probe.hpp"
#include "io/emergency_outputs.hpp"

namespace weedspray::daemon {

namespace {

// How long the dying daemon's line requests may take to be released.
constexpr auto kRetryFor = std::chrono::seconds(2);
constexpr auto kRetryEvery = std::chrono::milliseconds(2);
// How often the daemon's PF_EXITING flag is looked at: one pread of /proc/PID/stat (tens of
// microseconds, 100 a second, at normal priority), so a kill -9 is seen within ~10 ms, not
// after the kernel's teardown of the daemon's memory (0.2-0.8 s measured under emulation).
constexpr int kProbeEveryMs = 10;

double ms_since(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - since)
      .count();
}

// 0 at end-of-file, -EBADMSG for data (ignored), -errno on error.
int read_pipe(int fd) {
  char buffer[64];
  const ssize_t n = ::read(fd, buffer, sizeof buffer);
  if (n < 0) return errno == EINTR || errno == EAGAIN ? -EBADMSG : -errno;
  return n == 0 ? 0 : -EBADMSG;
}

// The handed-over descriptors keep the daemon's line requests alive: closed once the daemon is
// gone, so that the lines can be requested again (by the fallback below, then a new daemon).
void close_handed_writes() {
  io::EmergencyWrite write;
  for (std::size_t i = 0; io::EmergencyOutputs::get(i, write); ++i) ::close(write.fd);
  io::EmergencyOutputs::clear();
}

}  // namespace

int write_retrying_busy_lines(const std::function<void(std::vector<SafeWriteFailure>&)>& write,
                              std::vector<SafeWriteFailure>& failures,
                              std::chrono::nanoseconds retry_for,
                              std::chrono::nanoseconds retry_every) {
  const auto start = std::chrono::steady_clock::now();
  int attempts = 0;
  for (;;) {
    failures.clear();
    ++attempts;
    write(failures);
    // Only a line still held (the kernel releasing the daemon's requests) is worth a retry; a
    // missing chip or device stays missing.
    const bool busy = std::any_of(failures.begin(), failures.end(),
                                  [](const SafeWriteFailure& f) { return f.line_busy; });
    if (!busy || std::chrono::steady_clock::now() - start > retry_for) return attempts;
    std::this_thread::sleep_for(retry_every);
  }
}

int watch_and_write_safe_outputs(int fd, int daemon_pid, const std::filesystem::path& config_path,
                                 const std::filesystem::path& manifest_path, const char* program) {
  for (int signal : {SIGTERM, SIGINT, SIGHUP}) std::signal(signal, SIG_IGN);
  const std::optional<Config> loaded =
      load_safe_outputs_config(config_path, manifest_path, program);
  if (!loaded) {
    std::fprintf(stderr, "%s: no configuration: not watching\n", program);
    return 1;
  }
  const Config& config = *loaded;
  // Only while the daemon is still our parent is the PID surely its (not a reused one).
  ProcessExitProbe probe;
  if (daemon_pid > 0) {
    probe = ProcessExitProbe(daemon_pid);
    if (getppid() != daemon_pid) probe = ProcessExitProbe();
  }
  // A pipe (an older daemon, a test) carries nothing: only its end-of-file counts.
  struct stat fd_stat {};
  const bool is_socket = ::fstat(fd, &fd_stat) == 0 && S_ISSOCK(fd_stat.st_mode);
  io::EmergencyOutputs::clear();
  bool written_early = false;
  int early_failures = 0;
  std::chrono::steady_clock::time_point exiting_seen{};
  for (;;) {
    pollfd watched{fd, POLLIN, 0};
    const int ready = ::poll(&watched, 1, probe.valid() && !written_early ? kProbeEveryMs : -1);
    if (ready > 0) {
      io::EmergencyWrite write;
      const int got = is_socket ? receive_emergency_write(fd, write) : read_pipe(fd);
      if (got == 0) break;  // end-of-file: the daemon's process has ended
      if (got > 0) {
        if (!io::EmergencyOutputs::add(write)) ::close(write.fd);
      } else if (got != -EBADMSG) {
        std::fprintf(stderr, "%s: reading the watch socket (fd %d): %s; writing the outputs now\n",
                     program, fd, std::strerror(-got));
        break;
      }
    } else if (ready < 0 && errno != EINTR) {
      std::fprintf(stderr, "%s: poll: %s; writing the outputs now\n", program,
                   std::strerror(errno));
      break;
    }
    if (!written_early && probe.valid() && probe.exiting()) {
      // The daemon is dying (kill -9 or any exit): its line requests live on in our copies.
      exiting_seen = std::chrono::steady_clock::now();
      early_failures = io::EmergencyOutputs::trigger();
      written_early = true;
    }
  }
  const auto ended = std::chrono::steady_clock::now();
  if (written_early) {
    std::printf(
        "%s: weedsprayd exiting: %zu handed-over outputs written safe (%d failed), %.1f ms "
        "before its files were closed\n",
        program, io::EmergencyOutputs::size(), early_failures,
        std::chrono::duration<double, std::milli>(ended - exiting_seen).count());
  } else if (io::EmergencyOutputs::size() > 0) {
    const int failed = io::EmergencyOutputs::trigger();
    std::printf("%s: weedsprayd ended: %zu handed-over outputs written safe (%d failed)\n", program,
                io::EmergencyOutputs::size(), failed);
  }
  close_handed_writes();
  // Then as before: each output requested at its safe value (this is what holds them safe from
  // now on, with the request's bias, and covers any output that was not handed over).
  std::vector<SafeWriteFailure> failures;
  const int attempts = write_retrying_busy_lines(
      [&](std::vector<SafeWriteFailure>& out) { write_hw_safe_outputs(config, out); }, failures,
      kRetryFor, kRetryEvery);
  const double ms = ms_since(ended);
  for (const auto& failure : failures)
    std::fprintf(stderr, "%s: %s\n", program, failure.message.c_str());
  if (failures.empty())
    std::printf("%s: weedsprayd ended: outputs written safe %.1f ms later (%d attempt%s)\n",
                program, ms, attempts, attempts == 1 ? "" : "s");
  std::fflush(stdout);
  return failures.empty() ? 0 : 1;
}

}  // namespace weedspray::daemon
