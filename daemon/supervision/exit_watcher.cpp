// SPDX-License-Identifier: Apache-2.0
#include "daemon/supervision/exit_watcher.hpp"

#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <vector>

extern char** environ;

namespace weedspray::daemon {

std::filesystem::path default_exit_watcher_program() {
  std::error_code error;
  const auto self = std::filesystem::read_symlink("/proc/self/exe", error);
  return (error ? std::filesystem::path("/usr/sbin") : self.parent_path()) /
         "weedspray-safe-outputs";
}

ExitWatcher start_exit_watcher(const std::filesystem::path& config_path,
                               const std::filesystem::path& manifest_path,
                               const std::filesystem::path& program, std::string& error) {
  ExitWatcher watcher;
  // Said here rather than left to posix_spawn: under an emulator (qemu-user) a failed exec
  // shows only as a child exiting with status 127.
  if (::access(program.c_str(), X_OK) != 0) {
    error = program.string() + ": " + std::strerror(errno);
    return watcher;
  }
  // A socket pair rather than a pipe: the daemon hands the watcher its outputs' descriptors
  // over it later (backends/emergency_write_handoff.hpp). Datagrams keep each write whole.
  int fds[2];
  if (socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, fds) != 0) {
    error = std::string("socketpair: ") + std::strerror(errno);
    return watcher;
  }
  // One end becomes the child's fd 3 (dup2 clears close-on-exec there); the other,
  // close-on-exec, stays only here.
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[0], 3);
  std::error_code absolute_error;
  const std::string config = std::filesystem::absolute(config_path, absolute_error).string();
  const std::string program_text = program.string();
  std::vector<std::string> args = {program_text,
                                   "--config",
                                   config,
                                   "--when-closed",
                                   "3",
                                   "--daemon-pid",
                                   std::to_string(getpid())};
  if (!manifest_path.empty()) {
    args.emplace_back("--manifest");
    args.push_back(std::filesystem::absolute(manifest_path, absolute_error).string());
  }
  std::vector<char*> argv;
  for (auto& arg : args) argv.push_back(arg.data());
  argv.push_back(nullptr);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, program_text.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  close(fds[0]);
  if (rc != 0) {
    close(fds[1]);
    error = program_text + ": " + std::strerror(rc);
    return watcher;
  }
  watcher.pid = pid;
  watcher.socket_fd = fds[1];
  return watcher;
}

namespace {

// Whether the watcher ended, reaped; `how` says how.
bool reaped(const ExitWatcher& watcher, std::string& how) {
  int status = 0;
  if (::waitpid(watcher.pid, &status, WNOHANG) != watcher.pid) return false;
  how = WIFSIGNALED(status) ? "was killed by signal " + std::to_string(WTERMSIG(status))
                            : "exited with status " + std::to_string(WEXITSTATUS(status));
  return true;
}

}  // namespace

ExitWatcherKeeper::ExitWatcherKeeper(Launch launch, ExitWatcher started, std::string start_error,
                                     std::chrono::nanoseconds retry_every)
    : keeping_(true),
      launch_(std::move(launch)),
      watcher_(started),
      last_error_(std::move(start_error)),
      retry_every_(retry_every) {}

ExitWatcherKeeper::Check ExitWatcherKeeper::check(std::chrono::nanoseconds now) {
  if (!keeping_) return {};
  std::string how;
  if (watcher_.pid >= 0) {
    if (!reaped(watcher_, how)) {
      // A restarted watcher that has lived a retry interval is trusted again.
      if (ending_at_once_ && now - last_start_ >= retry_every_) ending_at_once_ = false;
      return {ending_at_once_ ? State::kLost : State::kRunning, last_error_};
    }
    ::close(watcher_.socket_fd);
    last_error_ = "exit watcher (pid " + std::to_string(watcher_.pid) + ") " + how;
    ending_at_once_ = started_once_ && now - last_start_ < retry_every_;
    watcher_ = {};
  }
  if (started_once_ && now - last_start_ < retry_every_) return {State::kLost, last_error_};
  started_once_ = true;
  last_start_ = now;
  std::string error;
  watcher_ = start_exit_watcher(launch_.config, launch_.manifest, launch_.program, error);
  if (watcher_.pid < 0) {
    last_error_ = "exit watcher not started: " + error;
    return {State::kLost, last_error_};
  }
  // One that keeps ending as soon as it starts is no watcher: lost, though started again.
  return {ending_at_once_ ? State::kLost : State::kRestarted, last_error_, true};
}

}  // namespace weedspray::daemon
