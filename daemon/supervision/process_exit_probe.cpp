// SPDX-License-Identifier: Apache-2.0
#include "daemon/supervision/process_exit_probe.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <string>
#include <utility>

namespace weedspray::daemon {

namespace {

// include/linux/sched.h; not exported to user space, stable since Linux 2.6.
constexpr unsigned long kPfExiting = 0x00000004;

}  // namespace

ProcessExitProbe::ProcessExitProbe(pid_t pid) {
  const std::string path = "/proc/" + std::to_string(pid) + "/stat";
  fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
}

ProcessExitProbe::~ProcessExitProbe() {
  if (fd_ >= 0) ::close(fd_);
}

ProcessExitProbe::ProcessExitProbe(ProcessExitProbe&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)) {}

ProcessExitProbe& ProcessExitProbe::operator=(ProcessExitProbe&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = std::exchange(other.fd_, -1);
  }
  return *this;
}

bool ProcessExitProbe::exiting() const noexcept {
  if (fd_ < 0) return false;
  char buffer[1024];
  const ssize_t n = ::pread(fd_, buffer, sizeof buffer - 1, 0);
  // Reaped: the kernel answers ESRCH on the still-open file.
  if (n < 0) return errno == ESRCH;
  return stat_line_says_exiting(buffer, static_cast<std::size_t>(n));
}

bool stat_line_says_exiting(const char* text, std::size_t length) noexcept {
  // "PID (COMM) S PPID PGRP SESSION TTY TPGID FLAGS ...": COMM may hold spaces and ')', so
  // the fields are counted from the last ')'.
  std::size_t close = length;
  for (std::size_t i = 0; i < length; ++i)
    if (text[i] == ')') close = i;
  if (close == length) return false;
  const char* p = text + close + 1;
  const char* end = text + length;
  char field[24];
  for (int index = 3; index <= 9; ++index) {  // state is field 3, flags field 9
    while (p < end && *p == ' ') ++p;
    std::size_t n = 0;
    while (p < end && *p != ' ' && *p != '\n' && n + 1 < sizeof field) field[n++] = *p++;
    if (n == 0) return false;
    field[n] = '\0';
    if (index == 3 && (field[0] == 'Z' || field[0] == 'X')) return true;
    if (index == 9) {
      char* parsed_end = nullptr;
      const unsigned long flags = std::strtoul(field, &parsed_end, 10);
      return parsed_end != field && (flags & kPfExiting) != 0;
    }
  }
  return false;
}

}  // namespace weedspray::daemon
