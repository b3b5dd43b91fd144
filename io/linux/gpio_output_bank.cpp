// SPDX-License-Identifier: Apache-2.0
#include "io/linux/gpio_output_bank.hpp"

#include <linux/gpio.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <gpiod.hpp>
#include <set>
#include <stdexcept>
#include <system_error>

#include "io/emergency_outputs.hpp"
#include "io/linux/gpio_lines.hpp"

namespace weedspray::io::hw {

struct GpioOutputBank::Impl {
  gpiod::line_bulk bulk;
  std::string chip_name;
  std::uint32_t invert_mask = 0;  // active-low lines: logical 1 = physical 0
  std::uint32_t safe_mask = 0;    // logical
  std::vector<int> values;        // reused by write(): no allocation at run time
  int handle_fd = -1;             // the kernel line handle (for the fatal-exit handler)
};

namespace {

// The process's GPIO line-handle descriptors (uAPI v1, which libgpiod 1.6 uses). libgpiod 1.6
// has no accessor for an output request's descriptor, and the fatal-signal handler needs one
// to write the safe values without the library: the bank's handle is the one that appears
// across its request (requests happen one at a time, at start-up).
std::set<int> line_handle_fds() {
  std::set<int> fds;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator("/proc/self/fd", ec)) {
    std::error_code link_ec;
    const auto target = std::filesystem::read_symlink(entry.path(), link_ec);
    if (!link_ec && target.string() == "anon_inode:gpio-linehandle") {
      fds.insert(std::stoi(entry.path().filename().string()));
    }
  }
  return fds;
}

}  // namespace

GpioOutputBank::GpioOutputBank(const GpioOutputBankConfig& config)
    : impl_(std::make_unique<Impl>()) {
  if (config.lines.empty() || config.lines.size() > 32)
    throw std::runtime_error("GPIO output bank: needs 1..32 lines, got " +
                             std::to_string(config.lines.size()));
  std::vector<int> defaults;
  std::vector<unsigned int> offsets;
  for (std::size_t i = 0; i < config.lines.size(); ++i) {
    const GpioLineConfig& lc = config.lines[i];
    const gpiod::line line = detail::find_line(config.chip, lc);
    const std::string chip = line.get_chip().name();
    if (i > 0 && chip != impl_->chip_name)
      throw std::runtime_error("GPIO output bank: " + detail::describe(config.chip, lc) +
                               " is on " + chip + " but line 0 is on " + impl_->chip_name +
                               "; one bank must be on one chip");
    impl_->chip_name = chip;
    offsets.push_back(line.offset());
    if (lc.active_low) impl_->invert_mask |= 1U << i;
    if (lc.safe_value) impl_->safe_mask |= 1U << i;
    defaults.push_back((lc.safe_value != lc.active_low) ? 1 : 0);
  }
  // libgpiod's line_bulk wants every line from ONE chip object (each lookup above opened its
  // own), so the lines are fetched again from a single handle of that chip.
  impl_->bulk = detail::open_chip(impl_->chip_name).get_lines(offsets);
  // Active-low is applied here, per line, because a bulk request shares one flag set.
  // The request's default values are the safe values: no glitch at start-up.
  const std::set<int> handles_before = line_handle_fds();
  try {
    impl_->bulk.request({config.consumer, gpiod::line_request::DIRECTION_OUTPUT, 0}, defaults);
  } catch (const std::system_error& e) {
    const std::string message = "GPIO output bank on " + impl_->chip_name +
                                ": requesting the lines failed (" + e.code().message() + ")";
    if (e.code().value() == EBUSY) throw GpioLineBusy(message + ": line busy");
    throw std::runtime_error(message);
  }
  impl_->values.resize(config.lines.size());
  const std::set<int> handles_after = line_handle_fds();
  std::vector<int> added;
  for (int fd : handles_after)
    if (!handles_before.contains(fd)) added.push_back(fd);
  if (added.size() == 1) impl_->handle_fd = added.front();
}

GpioOutputBank::~GpioOutputBank() {
  force_safe();
  try {
    impl_->bulk.release();
  } catch (...) {
  }
}

std::size_t GpioOutputBank::size() const noexcept {
  return impl_->values.size();
}

int GpioOutputBank::write(std::uint32_t mask) noexcept {
  // Once a fatal-exit handler has written the lines safe, no write may open them again.
  const EmergencyOutputs::OrdinaryWrite gate;
  const std::uint32_t physical = (gate.allowed() ? mask : impl_->safe_mask) ^ impl_->invert_mask;
  for (std::size_t i = 0; i < impl_->values.size(); ++i)
    impl_->values[i] = static_cast<int>((physical >> i) & 1U);
  try {
    impl_->bulk.set_values(impl_->values);  // one GPIOHANDLE_SET_LINE_VALUES ioctl
  } catch (const std::system_error& e) {
    return -e.code().value();
  } catch (...) {
    return -EIO;
  }
  if (gate.closed_since_entry()) return force_safe();
  return 0;
}

int GpioOutputBank::force_safe() noexcept {
  // The raw ioctl with its own payload touches no shared buffer, so another thread may force a
  // line safe while its owner is stuck in write() (the loops' cross-watch does).
  constexpr int kAttempts = 3;
  EmergencyWrite safe;
  int result = -EIO;
  if (emergency_write(safe)) {
    for (int attempt = 0; attempt < kAttempts; ++attempt) {
      if (::ioctl(safe.fd, safe.request, safe.payload.data()) >= 0) return 0;
      result = -errno;
    }
  }
  // No handle found, or the kernel refused it: through libgpiod as a last try.
  const int through_library = write(impl_->safe_mask);
  return through_library == 0 ? 0 : (result != -EIO ? result : through_library);
}

std::string GpioOutputBank::describe() const {
  std::string text = impl_->chip_name + (impl_->bulk.size() == 1 ? " line " : " lines ");
  std::string names;
  for (unsigned i = 0; i < impl_->bulk.size(); ++i) {
    const gpiod::line line = impl_->bulk.get(i);
    if (i > 0) {
      text.push_back(',');
      names.push_back(',');
    }
    text.append(std::to_string(line.offset()));
    const std::string name = line.name();
    names.append(name.empty() ? "?" : name);
  }
  return text + " (" + names + ")";
}

std::uint32_t GpioOutputBank::safe_mask() const noexcept {
  return impl_->safe_mask;
}

bool GpioOutputBank::emergency_write(EmergencyWrite& out) const noexcept {
  if (impl_->handle_fd < 0) return false;
  out = EmergencyWrite{};
  out.kind = EmergencyWrite::Kind::kIoctl;
  out.fd = impl_->handle_fd;
  out.request = GPIOHANDLE_SET_LINE_VALUES_IOCTL;
  static_assert(sizeof(gpiohandle_data) <= sizeof(out.payload));
  gpiohandle_data data{};
  const std::uint32_t physical = impl_->safe_mask ^ impl_->invert_mask;
  for (std::size_t i = 0; i < impl_->values.size(); ++i) data.values[i] = (physical >> i) & 1U;
  std::memcpy(out.payload.data(), &data, sizeof data);
  out.length = sizeof data;
  return true;
}

std::string GpioOutputBank::chip_name() const {
  return impl_->chip_name;
}

std::vector<unsigned int> GpioOutputBank::offsets() const {
  std::vector<unsigned int> out;
  for (unsigned i = 0; i < impl_->bulk.size(); ++i) out.push_back(impl_->bulk.get(i).offset());
  return out;
}

}  // namespace weedspray::io::hw
