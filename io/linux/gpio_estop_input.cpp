// SPDX-License-Identifier: Apache-2.0
#include "io/linux/gpio_estop_input.hpp"

#include <gpiod.h>
#include <poll.h>
#include <time.h>

#include <array>
#include <cerrno>
#include <gpiod.hpp>
#include <stdexcept>
#include <system_error>

#include "io/latest_value.hpp"
#include "io/linux/gpio_lines.hpp"
#include "io/linux/monotonic_clock.hpp"

namespace weedspray::io::hw {
namespace {

using std::chrono::nanoseconds;

// The kernel stamps GPIO events on CLOCK_MONOTONIC (Linux 5.7 and later); a stamp from another
// clock (older kernels: CLOCK_REALTIME) is replaced by the time the event was read.
nanoseconds edge_time(const timespec& ts, nanoseconds read_at) noexcept {
  const nanoseconds t = std::chrono::seconds{ts.tv_sec} + nanoseconds{ts.tv_nsec};
  return t > read_at || read_at - t > std::chrono::seconds(1) ? read_at : t;
}

}  // namespace

struct GpioEstopInput::Impl {
  gpiod::line line;
  int fd = -1;
  nanoseconds closing_hold{};
  bool initial_closed = false;
  EstopReaction reaction;
  LatestValue<EstopSample> published;
  RealtimeThread thread;

  void run(std::stop_token stop) noexcept {
    NormallyClosedContact contact(closing_hold, initial_closed, monotonic_now());
    EstopSample s;
    s.circuit_closed = contact.closed();
    s.time = contact.changed_at();
    const auto opened = [&](nanoseconds at) noexcept {
      reaction.on_open(reaction.context, at);
      ++s.openings;
    };
    if (!s.circuit_closed) opened(s.time);
    published.publish(s);
    std::array<gpiod_line_event, 16> events{};
    pollfd pfd{fd, POLLIN, 0};
    while (!stop.stop_requested()) {
      const int timeout_ms =
          detail::poll_timeout_ms(contact.pending(), contact.pending_until(), monotonic_now(), 50);
      const int ready = poll(&pfd, 1, timeout_ms);
      const nanoseconds read_at = monotonic_now();
      bool read_failed = ready < 0 && errno != EINTR;
      if (ready > 0) {
        const int n = gpiod_line_event_read_fd_multiple(fd, events.data(), events.size());
        read_failed = n < 0;
        for (int i = 0; i < n; ++i) {
          const gpiod_line_event& e = events[static_cast<std::size_t>(i)];
          const bool closed = e.event_type == GPIOD_LINE_EVENT_RISING_EDGE;
          if (contact.feed(closed, edge_time(e.ts, read_at))) opened(edge_time(e.ts, read_at));
        }
      }
      if (read_failed) {
        ++s.error_count;
        // Not trusted closed: the stop acts, and the circuit must prove itself closed again.
        contact.feed(false, read_at);
        opened(read_at);
        // A descriptor that keeps failing must not spin this, the highest-priority thread.
        const timespec pause{.tv_sec = 0, .tv_nsec = 10'000'000};
        nanosleep(&pause, nullptr);
      }
      contact.settle(monotonic_now());
      s.circuit_closed = contact.closed();
      s.time = contact.changed_at();
      published.publish(s);
    }
  }
};

GpioEstopInput::GpioEstopInput(const GpioEstopInputConfig& config)
    : impl_(std::make_unique<Impl>()) {
  impl_->line = detail::find_line(config.chip, config.line);
  impl_->closing_hold = config.closing_hold;
  std::bitset<32> flags;
  if (config.line.active_low) flags |= gpiod::line_request::FLAG_ACTIVE_LOW;
  try {
    impl_->line.request({config.consumer, gpiod::line_request::EVENT_BOTH_EDGES, flags});
    impl_->initial_closed = impl_->line.get_value() != 0;
  } catch (const std::system_error& e) {
    throw std::runtime_error("E-stop input " + detail::describe(config.chip, config.line) +
                             ": requesting edge events failed (" + e.code().message() + ")");
  }
  impl_->fd = impl_->line.event_get_fd();
  EstopSample s;
  s.circuit_closed = impl_->initial_closed;
  s.time = monotonic_now();
  impl_->published.publish(s);
}

GpioEstopInput::~GpioEstopInput() {
  disarm();
  try {
    impl_->line.release();
  } catch (...) {
  }
}

void GpioEstopInput::arm(const EstopReaction& reaction) {
  disarm();
  impl_->reaction = reaction;
  Impl* impl = impl_.get();
  impl_->thread =
      RealtimeThread(ThreadRole::kEstop, [impl](std::stop_token stop) { impl->run(stop); });
}

void GpioEstopInput::disarm() noexcept {
  impl_->thread.stop_and_join();
}

EstopSample GpioEstopInput::sample() const noexcept {
  return impl_->published.read();
}

RtStatus GpioEstopInput::thread_status() const noexcept {
  return impl_->thread.status();
}

}  // namespace weedspray::io::hw
