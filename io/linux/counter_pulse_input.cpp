// SPDX-License-Identifier: Apache-2.0
#include "io/linux/counter_pulse_input.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include "io/latest_value.hpp"
#include "io/linux/monotonic_clock.hpp"
#include "io/linux/sysfs_text.hpp"

namespace weedspray::io::hw {

namespace fs = std::filesystem;

namespace {

// "18446744073709551615\n" plus room to tell an over-long value from a valid one.
constexpr std::size_t kReadBufferSize = 32;
constexpr std::uint32_t kBackwardsDelta = 1U << 31;

std::string errno_text(int error) {
  return std::strerror(error);
}

// One pread from offset 0: sysfs regenerates the attribute on each read from the start.
bool read_u64(int fd, std::uint64_t& value) noexcept {
  char buffer[kReadBufferSize];
  const ssize_t n = ::pread(fd, buffer, sizeof(buffer), 0);
  if (n <= 0 || static_cast<std::size_t>(n) == sizeof(buffer)) return false;
  return parse_counter_value({buffer, static_cast<std::size_t>(n)}, value);
}

// Opens `path` or throws with the errno text.
int open_or_throw(const fs::path& path, int flags, const std::string& hint) {
  const int fd = ::open(path.c_str(), flags | O_CLOEXEC);
  if (fd < 0)
    throw std::runtime_error("counter: cannot open " + path.string() + ": " + errno_text(errno) +
                             hint);
  return fd;
}

struct FdCloser {
  int fd;
  ~FdCloser() {
    if (fd >= 0) ::close(fd);
  }
};

// interrupt-cnt requests its interrupt disabled (IRQ_NOAUTOEN): nothing counts until 1 is
// written to `enable`. Counters without an `enable` attribute always count.
void enable_counting(const fs::path& count_dir) {
  const fs::path enable = count_dir / "enable";
  std::error_code ec;
  if (!fs::exists(enable, ec)) return;
  const std::string permission_hint =
      ". weedsprayd does not run as root and its unit makes /sys read-only: let udev enable the "
      "counter at boot (rule 60-weedspray.rules in /usr/lib/udev/rules.d, from "
      "systemd/weedspray.udev.rules), or run `echo 1 > " +
      enable.string() + "` as root";
  std::uint64_t enabled = 0;
  {
    const FdCloser reader{open_or_throw(enable, O_RDONLY, "")};
    if (!read_u64(reader.fd, enabled) || enabled > 1)
      throw std::runtime_error("counter: " + enable.string() + " does not hold 0 or 1");
  }
  if (enabled == 1) return;
  const FdCloser writer{open_or_throw(enable, O_WRONLY, permission_hint)};
  if (::pwrite(writer.fd, "1\n", 2, 0) != 2)
    throw std::runtime_error("counter: writing 1 to " + enable.string() +
                             " failed: " + errno_text(errno) + permission_hint);
}

}  // namespace

std::string resolve_counter_device_dir(const std::string& device, const std::string& sysfs_root) {
  if (device.empty()) throw std::runtime_error("counter: no device configured");
  if (device.front() == '/') {
    if (!fs::is_directory(device))
      throw std::runtime_error("counter: no counter directory " + device);
    return device;
  }
  const fs::path direct = fs::path(sysfs_root) / device;
  std::error_code ec;
  if (fs::is_directory(direct, ec)) return direct.string();
  std::string found;
  for (const auto& entry : fs::directory_iterator(sysfs_root, ec)) {
    if (read_first_line(entry.path() / "name") != device) continue;
    if (!found.empty())
      throw std::runtime_error("counter: both " + found + " and " + entry.path().string() +
                               " are named '" + device + "': configure the directory instead");
    found = entry.path().string();
  }
  if (!found.empty()) return found;
  throw std::runtime_error(
      "counter: device '" + device + "' not found under " + sysfs_root +
      " (neither a counterN directory nor a counter's name). Is the interrupt-cnt module "
      "loaded and its device-tree node (compatible = \"interrupt-counter\") applied? "
      "`grep . " +
      sysfs_root + "/*/name` lists the counters");
}

bool parse_counter_value(std::string_view text, std::uint64_t& value) noexcept {
  if (!text.empty() && text.back() == '\n') text.remove_suffix(1);
  if (text.empty()) return false;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  return error == std::errc{} && end == text.data() + text.size();
}

CounterTotal::Change CounterTotal::update(std::uint64_t raw) noexcept {
  // The low 32 bits advance by one per pulse whatever the counter's width (see the header).
  const auto delta = static_cast<std::uint32_t>(raw - reference_);
  reference_ = raw;
  if (delta == 0) return Change::kNone;
  if (delta >= kBackwardsDelta) return Change::kWentBackwards;
  count_ += delta;
  return Change::kCounted;
}

struct CounterPulseInput::Impl {
  std::string count_path;
  int fd = -1;
  std::chrono::nanoseconds poll_period{};
  std::uint64_t first_raw = 0;  // the kernel's total at start
  MonotonicClock clock;
  LatestValue<PulseSnapshot> published;
  RealtimeThread thread;

  ~Impl() {
    if (fd >= 0) ::close(fd);
  }

  void run(std::stop_token stop) noexcept {
    PulseSnapshot s;
    CounterTotal total(first_raw);
    PeriodicLoop loop(clock, poll_period, clock.now() + poll_period);
    while (!stop.stop_requested()) {
      loop.wait_next();
      std::uint64_t raw = 0;
      const bool read_ok = read_u64(fd, raw);
      const std::chrono::nanoseconds polled_at = clock.now();
      if (!read_ok) {
        ++s.error_count;
      } else {
        switch (total.update(raw)) {
          case CounterTotal::Change::kNone:
            continue;
          case CounterTotal::Change::kCounted:
            s.count = total.count();
            s.last_edge_time = polled_at;
            break;
          case CounterTotal::Change::kWentBackwards:
            ++s.error_count;
            break;
        }
      }
      published.publish(s);
    }
  }
};

CounterPulseInput::CounterPulseInput(const CounterPulseInputConfig& config)
    : impl_(std::make_unique<Impl>()) {
  if (config.poll_period <= std::chrono::nanoseconds::zero())
    throw std::runtime_error("counter: poll_period must be positive");
  if (config.count_index < 0) throw std::runtime_error("counter: count_index must be >= 0");
  const fs::path count_dir =
      fs::path(resolve_counter_device_dir(config.device, config.sysfs_root)) /
      ("count" + std::to_string(config.count_index));
  enable_counting(count_dir);
  impl_->count_path = (count_dir / "count").string();
  impl_->fd = open_or_throw(impl_->count_path, O_RDONLY, "");
  errno = 0;  // tells a failed read (errno set) from content that is not a count
  if (!read_u64(impl_->fd, impl_->first_raw))
    throw std::runtime_error("counter: " + impl_->count_path + ": " +
                             (errno != 0 ? errno_text(errno) : "does not hold a decimal count"));
  impl_->poll_period = config.poll_period;
  Impl* impl = impl_.get();
  impl_->thread =
      RealtimeThread(ThreadRole::kPulseInput, [impl](std::stop_token stop) { impl->run(stop); });
}

CounterPulseInput::~CounterPulseInput() {
  impl_->thread.stop_and_join();
}

PulseSnapshot CounterPulseInput::snapshot() const noexcept {
  // The writer (ws-pulses) runs above every reader in the priority table, so a reader is never
  // spinning while the writer it preempted is stuck mid-write.
  return impl_->published.read();
}

RtStatus CounterPulseInput::thread_status() const noexcept {
  return impl_->thread.status();
}

const std::string& CounterPulseInput::count_path() const noexcept {
  return impl_->count_path;
}

}  // namespace weedspray::io::hw
