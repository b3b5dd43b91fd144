// SPDX-License-Identifier: Apache-2.0
// Test-side access to a gpio-sim chip made by guest-init.sh: finds its device and gpiochip
// through configfs (never assumes gpiochipN numbers) and reads/pulls the simulated lines
// through sysfs, i.e. from outside libgpiod, the way a wired peer would see them.
#pragma once

#include <string>

namespace weedspray::vm_test {

class GpioSimChip {
 public:
  // `config_name` is the directory under /sys/kernel/config/gpio-sim/. Throws
  // std::runtime_error naming the missing file when the chip does not exist.
  explicit GpioSimChip(const std::string& config_name);

  const std::string& label() const noexcept { return label_; }
  const std::string& chip_name() const noexcept { return chip_name_; }  // "gpiochip1"
  std::string device_path() const { return "/dev/" + chip_name_; }

  // The physical level the line has now (driven by a consumer, else its pull). Throws.
  int value(unsigned int offset) const;
  // Sets the simulated pull: an input edge when no consumer drives the line. Throws.
  void pull(unsigned int offset, bool up) const;
  // /sys/devices/platform/<dev_name>/<chip_name>/sim_gpioN
  std::string line_dir(unsigned int offset) const;

 private:
  std::string label_;
  std::string chip_name_;
  std::string sysfs_dir_;  // /sys/devices/platform/<dev_name>/<chip_name>
};

// The fastest edge source sysfs offers, for rate tests: the line's `pull` file stays open, so
// an edge costs one pwrite and nothing else (GpioSimChip::pull opens the file every time).
class GpioSimPullWriter {
 public:
  // Opens sim_gpioN/pull of `chip`. Throws std::runtime_error naming the file.
  GpioSimPullWriter(const GpioSimChip& chip, unsigned int offset);
  ~GpioSimPullWriter();
  GpioSimPullWriter(const GpioSimPullWriter&) = delete;
  GpioSimPullWriter& operator=(const GpioSimPullWriter&) = delete;

  // False when the kernel refused the write (errno tells why).
  bool set(bool up) const noexcept;

 private:
  int fd_ = -1;
};

}  // namespace weedspray::vm_test
