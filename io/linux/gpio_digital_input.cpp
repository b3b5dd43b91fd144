// SPDX-License-Identifier: Apache-2.0
#include "io/linux/gpio_digital_input.hpp"

#include <gpiod.h>
#include <poll.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <gpiod.hpp>
#include <stdexcept>
#include <system_error>

#include "io/latest_value.hpp"
#include "io/linux/gpio_lines.hpp"
#include "io/linux/monotonic_clock.hpp"

namespace weedspray::io::hw {

struct GpioDigitalInput::Impl {
  gpiod::line line;
  int fd = -1;
  std::chrono::nanoseconds debounce{};
  bool initial = false;
  LatestValue<DigitalInputSample> published;
  RealtimeThread thread;

  void run(std::stop_token stop) noexcept {
    Debouncer debouncer(debounce, initial);
    DigitalInputSample s;
    s.active = initial;
    s.time = monotonic_now();
    published.publish(s);
    std::array<gpiod_line_event, 16> events{};
    pollfd pfd{fd, POLLIN, 0};
    while (!stop.stop_requested()) {
      const int timeout_ms = detail::poll_timeout_ms(debouncer.pending(), debouncer.pending_until(),
                                                     monotonic_now(), 50);
      const int ready = poll(&pfd, 1, timeout_ms);
      if (ready < 0 && errno != EINTR) {
        ++s.error_count;
        published.publish(s);
        continue;
      }
      bool changed = false;
      if (ready > 0) {
        const int n = gpiod_line_event_read_fd_multiple(fd, events.data(), events.size());
        if (n < 0) {
          ++s.error_count;
        } else {
          for (int i = 0; i < n; ++i) {
            const timespec& ts = events[static_cast<std::size_t>(i)].ts;
            const auto t = std::chrono::seconds{ts.tv_sec} + std::chrono::nanoseconds{ts.tv_nsec};
            changed |= debouncer.feed(
                events[static_cast<std::size_t>(i)].event_type == GPIOD_LINE_EVENT_RISING_EDGE, t);
          }
        }
      }
      changed |= debouncer.settle(monotonic_now());
      if (changed) {
        s.active = debouncer.level();
        s.time = debouncer.changed_at();
        ++s.change_count;
      }
      if (changed || ready != 0) published.publish(s);
    }
  }
};

GpioDigitalInput::GpioDigitalInput(const GpioDigitalInputConfig& config)
    : impl_(std::make_unique<Impl>()) {
  impl_->line = detail::find_line(config.chip, config.line);
  impl_->debounce = config.debounce;
  std::bitset<32> flags = detail::bias_flags(config.bias);
  if (config.line.active_low) flags |= gpiod::line_request::FLAG_ACTIVE_LOW;
  try {
    impl_->line.request({config.consumer, gpiod::line_request::EVENT_BOTH_EDGES, flags});
    impl_->initial = impl_->line.get_value() != 0;
  } catch (const std::system_error& e) {
    throw std::runtime_error("digital input " + detail::describe(config.chip, config.line) +
                             ": requesting edge events failed (" + e.code().message() + ")");
  }
  impl_->fd = impl_->line.event_get_fd();
  Impl* impl = impl_.get();
  impl_->thread =
      RealtimeThread(ThreadRole::kDigitalInput, [impl](std::stop_token stop) { impl->run(stop); });
}

GpioDigitalInput::~GpioDigitalInput() {
  impl_->thread.stop_and_join();
  try {
    impl_->line.release();
  } catch (...) {
  }
}

DigitalInputSample GpioDigitalInput::sample() const noexcept {
  return impl_->published.read();
}

RtStatus GpioDigitalInput::thread_status() const noexcept {
  return impl_->thread.status();
}

}  // namespace weedspray::io::hw
