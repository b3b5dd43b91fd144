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

 private:
  std::string line_dir(unsigned int offset) const;

  std::string label_;
  std::string chip_name_;
  std::string sysfs_dir_;  // /sys/devices/platform/<dev_name>/<chip_name>
};

}  // namespace weedspray::vm_test
