// SPDX-License-Identifier: Apache-2.0
#include "tools/hil/sim_gpio_lines.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace weedspray::hil {
namespace {

int open_attribute(const std::string& chip_dir, int offset, const char* name, int flags) {
  const std::string path = chip_dir + "/sim_gpio" + std::to_string(offset) + "/" + name;
  const int fd = ::open(path.c_str(), flags | O_CLOEXEC);
  if (fd < 0) throw std::runtime_error("cannot open " + path + ": " + std::strerror(errno));
  return fd;
}

}  // namespace

SimOutputLine::SimOutputLine(const std::string& chip_dir, int offset)
    : fd_(open_attribute(chip_dir, offset, "value", O_RDONLY)) {}

SimOutputLine::~SimOutputLine() {
  ::close(fd_);
}

bool SimOutputLine::high() const {
  char text[4] = {};
  if (::pread(fd_, text, sizeof text, 0) < 1)
    throw std::runtime_error(std::string("gpio-sim value read failed: ") + std::strerror(errno));
  return text[0] == '1';
}

SimInputLine::SimInputLine(const std::string& chip_dir, int offset)
    : fd_(open_attribute(chip_dir, offset, "pull", O_WRONLY)) {
  write_pull(false);
}

SimInputLine::~SimInputLine() {
  ::close(fd_);
}

void SimInputLine::write_pull(bool up) {
  const char* text = up ? "pull-up" : "pull-down";
  if (::pwrite(fd_, text, std::strlen(text), 0) < 0)
    throw std::runtime_error(std::string("gpio-sim pull write failed: ") + std::strerror(errno));
}

void SimInputLine::step(std::uint64_t wanted) {
  if (high_) {
    write_pull(false);
    high_ = false;
  } else if (sent_ < wanted) {
    write_pull(true);
    high_ = true;
    ++sent_;
  }
}

}  // namespace weedspray::hil
