// SPDX-License-Identifier: Apache-2.0
#include "io/linux/gpio_pulse_input.hpp"

#include <gpiod.h>
#include <poll.h>

#include <array>
#include <cerrno>
#include <gpiod.hpp>
#include <stdexcept>
#include <system_error>

#include "io/linux/gpio_lines.hpp"

namespace weedspray::io::hw {

namespace {
// The uAPI v1 kernel event queue holds 16 events; a read that returns that many may have
// lost some (the kernel drops silently when it is full).
constexpr unsigned kKernelQueueEvents = 16;
constexpr unsigned kBatch = 64;
constexpr int kPollTimeoutMs = 50;  // bounds the reaction to a stop request
}  // namespace

struct GpioPulseInput::Impl {
  gpiod::line line;
  int fd = -1;
  LatestValue<PulseSnapshot> published;
  RealtimeThread thread;

  void run(std::stop_token stop) noexcept {
    std::array<gpiod_line_event, kBatch> events{};
    PulseSnapshot s;
    pollfd pfd{fd, POLLIN, 0};
    while (!stop.stop_requested()) {
      const int ready = poll(&pfd, 1, kPollTimeoutMs);
      if (ready == 0 || (ready < 0 && errno == EINTR)) continue;
      if (ready < 0 || (pfd.revents & (POLLERR | POLLHUP | POLLNVAL))) {
        ++s.error_count;
        published.publish(s);
        if (pfd.revents & POLLNVAL) return;  // the fd is gone: nothing more to count
        continue;
      }
      const int n = gpiod_line_event_read_fd_multiple(fd, events.data(), kBatch);
      if (n < 0) {
        ++s.error_count;
        published.publish(s);
        continue;
      }
      // Only the counted edge is requested, so every event is one pulse.
      s.count += static_cast<std::uint64_t>(n);
      if (n > 0) {
        const timespec& ts = events[static_cast<std::size_t>(n) - 1].ts;
        s.last_edge_time = std::chrono::seconds{ts.tv_sec} + std::chrono::nanoseconds{ts.tv_nsec};
      }
      if (static_cast<unsigned>(n) >= kKernelQueueEvents) ++s.overflow_count;
      published.publish(s);
    }
  }
};

GpioPulseInput::GpioPulseInput(const GpioPulseInputConfig& config)
    : impl_(std::make_unique<Impl>()) {
  impl_->line = detail::find_line(config.chip, config.line);
  std::bitset<32> flags = detail::bias_flags(config.bias);
  if (config.line.active_low) flags |= gpiod::line_request::FLAG_ACTIVE_LOW;
  const int type = config.counted_edge == PulseEdge::kRising
                       ? gpiod::line_request::EVENT_RISING_EDGE
                       : gpiod::line_request::EVENT_FALLING_EDGE;
  try {
    impl_->line.request({config.consumer, type, flags});
  } catch (const std::system_error& e) {
    throw std::runtime_error("pulse input " + detail::describe(config.chip, config.line) +
                             ": requesting edge events failed (" + e.code().message() + ")");
  }
  impl_->fd = impl_->line.event_get_fd();
  Impl* impl = impl_.get();
  impl_->thread =
      RealtimeThread(ThreadRole::kPulseInput, [impl](std::stop_token stop) { impl->run(stop); });
}

GpioPulseInput::~GpioPulseInput() {
  impl_->thread.stop_and_join();
  try {
    impl_->line.release();
  } catch (...) {
  }
}

PulseSnapshot GpioPulseInput::snapshot() const noexcept {
  // The writer (ws-pulses) runs above every reader in the priority table, so a reader is never
  // spinning while the writer it preempted is stuck mid-write.
  return impl_->published.read();
}

RtStatus GpioPulseInput::thread_status() const noexcept {
  return impl_->thread.status();
}

}  // namespace weedspray::io::hw
