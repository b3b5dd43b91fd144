// SPDX-License-Identifier: Apache-2.0
#include "tests/vm/gpio_sim_chip.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string_view>

namespace weedspray::vm_test {
namespace {

std::string read_first_word(const std::string& path) {
  std::ifstream file(path);
  std::string word;
  if (!(file >> word)) throw std::runtime_error("cannot read " + path);
  return word;
}

void write_text(const std::string& path, const std::string& text) {
  std::ofstream file(path);
  file << text << std::flush;
  if (!file) throw std::runtime_error("cannot write '" + text + "' to " + path);
}

}  // namespace

GpioSimChip::GpioSimChip(const std::string& config_name) : label_(config_name) {
  const std::string config_dir = "/sys/kernel/config/gpio-sim/" + config_name;
  const std::string dev_name = read_first_word(config_dir + "/dev_name");
  chip_name_ = read_first_word(config_dir + "/bank0/chip_name");
  sysfs_dir_ = "/sys/devices/platform/" + dev_name + "/" + chip_name_;
}

std::string GpioSimChip::line_dir(unsigned int offset) const {
  return sysfs_dir_ + "/sim_gpio" + std::to_string(offset);
}

int GpioSimChip::value(unsigned int offset) const {
  const std::string path = line_dir(offset) + "/value";
  const std::string text = read_first_word(path);
  if (text != "0" && text != "1") throw std::runtime_error(path + " holds '" + text + "'");
  return text == "1" ? 1 : 0;
}

void GpioSimChip::pull(unsigned int offset, bool up) const {
  write_text(line_dir(offset) + "/pull", up ? "pull-up" : "pull-down");
}

GpioSimPullWriter::GpioSimPullWriter(const GpioSimChip& chip, unsigned int offset) {
  const std::string path = chip.line_dir(offset) + "/pull";
  fd_ = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
  if (fd_ < 0) throw std::runtime_error("cannot open " + path + ": " + std::strerror(errno));
}

GpioSimPullWriter::~GpioSimPullWriter() {
  ::close(fd_);
}

bool GpioSimPullWriter::set(bool up) const noexcept {
  constexpr std::string_view kUp = "pull-up";
  constexpr std::string_view kDown = "pull-down";
  const std::string_view text = up ? kUp : kDown;
  return ::pwrite(fd_, text.data(), text.size(), 0) == static_cast<ssize_t>(text.size());
}

}  // namespace weedspray::vm_test
