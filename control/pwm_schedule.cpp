// SPDX-License-Identifier: Apache-2.0
#include "control/pwm_schedule.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace weedspray::control {

using std::chrono::nanoseconds;

std::vector<std::size_t> outer_first_order(std::size_t valve_count) {
  std::vector<std::size_t> order;
  order.reserve(valve_count);
  std::size_t low = 0;
  std::size_t high = valve_count;
  while (low < high) {
    order.push_back(low++);
    if (low < high) order.push_back(--high);
  }
  return order;
}

PwmSchedule::PwmSchedule(const PwmConfig& config)
    : valve_count_(config.valve_count),
      period_(0),
      min_on_(config.min_on_time),
      min_off_(config.min_off_time),
      immediate_(config.immediate_start_stop) {
  if (config.valve_count < 1 || config.valve_count > kMaxPwmValves) {
    throw std::invalid_argument("PwmConfig.valve_count must be 1..32, got " +
                                std::to_string(config.valve_count));
  }
  if (!(config.frequency_hz >= 1.0 && config.frequency_hz <= 20.0)) {
    throw std::invalid_argument("PwmConfig.frequency_hz must be 1..20 Hz, got " +
                                std::to_string(config.frequency_hz));
  }
  period_ = nanoseconds(std::llround(1e9 / config.frequency_hz));
  if (min_on_.count() < 0 || min_off_.count() < 0) {
    throw std::invalid_argument("PwmConfig.min_on_time/min_off_time must be >= 0");
  }
  if (min_on_ + min_off_ > period_) {
    throw std::invalid_argument("PwmConfig.min_on_time + min_off_time exceed the PWM period");
  }
  std::vector<std::size_t> order =
      config.order.empty() ? outer_first_order(valve_count_) : config.order;
  if (order.size() != valve_count_) {
    throw std::invalid_argument("PwmConfig.order must list each of the " +
                                std::to_string(valve_count_) + " valves once");
  }
  std::array<bool, kMaxPwmValves> seen{};
  for (std::size_t slot = 0; slot < order.size(); ++slot) {
    const std::size_t valve = order[slot];
    if (valve >= valve_count_ || seen[valve]) {
      throw std::invalid_argument("PwmConfig.order is not a permutation of 0.." +
                                  std::to_string(valve_count_ - 1) + " (entry " +
                                  std::to_string(slot) + " = " + std::to_string(valve) + ")");
    }
    seen[valve] = true;
    valves_[valve].offset =
        config.phase_mode == PwmPhaseMode::kStaggered
            ? nanoseconds(period_.count() * static_cast<nanoseconds::rep>(slot) /
                          static_cast<nanoseconds::rep>(valve_count_))
            : nanoseconds(0);
  }
  start(nanoseconds(0));
}

void PwmSchedule::start(nanoseconds t0) noexcept {
  for (std::size_t v = 0; v < valve_count_; ++v) {
    Valve& valve = valves_[v];
    valve.started = false;
    // A virtual closed period precedes the first one, so period_start is never a future time.
    valve.period_start = t0 + valve.offset - period_;
    valve.next_period_start = t0 + valve.offset;
    valve.grid_origin = t0 + valve.offset;
    valve.on_time = nanoseconds(0);
    valve.latched_duty_pct = 0.0;
    valve.closed_at = t0 - min_off_;  // outputs were forced safe before a (re)start
  }
  cursor_ = t0;
  mask_ = 0;
}

void PwmSchedule::set_duty(std::size_t valve, double duty_pct) noexcept {
  set_duty(valve, duty_pct, cursor_);
}

void PwmSchedule::set_duties(std::span<const double> duty_pct) noexcept {
  set_duties(duty_pct, cursor_);
}

void PwmSchedule::set_duty(std::size_t valve, double duty_pct, nanoseconds now) noexcept {
  if (valve >= valve_count_) return;
  Valve& v = valves_[valve];
  v.requested_duty_pct = std::isnan(duty_pct) ? 0.0 : std::clamp(duty_pct, 0.0, 100.0);
  if (!immediate_) return;
  now = std::max(now, cursor_);
  const bool open = (mask_ >> valve & 1u) != 0;
  // Closed for the rest of its period: never started, a 0 % period, or an immediate stop.
  const bool closed_all_period =
      !open && (!v.started || v.on_time == nanoseconds(0) || v.latched_duty_pct == 0.0);
  if (closed_all_period && on_time_for(v.requested_duty_pct) > nanoseconds(0)) {
    // Start a new period now instead of waiting for the stagger slot; next_edge() latches it.
    v.next_period_start = std::min(v.next_period_start, std::max(now, v.closed_at + min_off_));
  } else if (open && v.requested_duty_pct == 0.0) {
    // Close now: end this period's pulse here. The valve has been open since opened_at, which
    // may be many periods ago at 100 % duty; only that opening must last min_on_time.
    const nanoseconds close_at = std::max({now, v.opened_at + min_on_, v.period_start});
    if (close_at < v.period_start + v.on_time) {
      v.on_time = close_at - v.period_start;
      v.latched_duty_pct = 0.0;
    }
  }
}

void PwmSchedule::set_duties(std::span<const double> duty_pct, nanoseconds now) noexcept {
  const std::size_t n = std::min(duty_pct.size(), valve_count_);
  for (std::size_t v = 0; v < n; ++v) set_duty(v, duty_pct[v], now);
}

std::uint32_t PwmSchedule::force_closed() noexcept {
  for (std::size_t v = 0; v < valve_count_; ++v) {
    valves_[v].requested_duty_pct = 0.0;
    valves_[v].latched_duty_pct = 0.0;
    valves_[v].on_time = nanoseconds(0);
    if ((mask_ >> v & 1u) != 0) valves_[v].closed_at = cursor_;
  }
  mask_ = 0;
  return mask_;
}

nanoseconds PwmSchedule::on_time_for(double duty_pct) const noexcept {
  return on_time_for(duty_pct, period_);
}

nanoseconds PwmSchedule::on_time_for(double duty_pct, nanoseconds length) const noexcept {
  if (!(duty_pct > 0.0)) return nanoseconds(0);
  if (duty_pct >= 100.0) return length;
  auto on = nanoseconds(std::llround(duty_pct / 100.0 * static_cast<double>(length.count())));
  if (on > nanoseconds(0) && on < min_on_) on = (on * 2 < min_on_) ? nanoseconds(0) : min_on_;
  const nanoseconds off = length - on;
  if (off > nanoseconds(0) && off < min_off_) {
    on = (off * 2 < min_off_) ? length : length - min_off_;
  }
  return on;
}

nanoseconds PwmSchedule::period_end_on_grid(const Valve& valve, nanoseconds t) const noexcept {
  const nanoseconds shortest = std::max(period_ / 2, min_on_ + min_off_);
  const nanoseconds ahead = t + shortest - valve.grid_origin;
  const nanoseconds::rep periods =
      ahead.count() <= 0 ? 0 : (ahead.count() + period_.count() - 1) / period_.count();
  return valve.grid_origin + period_ * periods;
}

double PwmSchedule::effective_duty_pct(double duty_pct) const noexcept {
  return 100.0 * static_cast<double>(on_time_for(duty_pct).count()) /
         static_cast<double>(period_.count());
}

nanoseconds PwmSchedule::phase_offset(std::size_t valve) const noexcept {
  return valve < valve_count_ ? valves_[valve].offset : nanoseconds(0);
}

PwmValveState PwmSchedule::valve_state(std::size_t valve) const noexcept {
  if (valve >= valve_count_) return PwmValveState{};
  const Valve& v = valves_[valve];
  return PwmValveState{(mask_ >> valve & 1u) != 0, v.latched_duty_pct, v.period_start, v.on_time};
}

PwmValveState PwmSchedule::valve_state_at(std::size_t valve, nanoseconds t) const noexcept {
  if (valve >= valve_count_) return PwmValveState{};
  const Valve& v = valves_[valve];
  if (t < v.next_period_start) {
    const nanoseconds from = std::max(t, v.period_start);
    const bool open = v.started && v.on_time > nanoseconds(0) && from < v.period_start + v.on_time;
    return PwmValveState{open, v.latched_duty_pct, v.period_start, v.on_time};
  }
  // The next period (an immediate start's may be off the grid: it ends on it), then whole ones.
  const nanoseconds first_end = period_end_on_grid(v, v.next_period_start);
  if (t < first_end) {
    const nanoseconds on = on_time_for(v.requested_duty_pct, first_end - v.next_period_start);
    return PwmValveState{t < v.next_period_start + on, v.requested_duty_pct, v.next_period_start,
                         on};
  }
  const nanoseconds start = first_end + (t - first_end) / period_ * period_;
  const nanoseconds on = on_time_for(v.requested_duty_pct);
  return PwmValveState{t < start + on, v.requested_duty_pct, start, on};
}

std::uint32_t PwmSchedule::mask_at(nanoseconds t) const noexcept {
  std::uint32_t mask = 0;
  for (std::size_t v = 0; v < valve_count_; ++v) {
    if (valve_state_at(v, t).open) mask |= 1u << v;
  }
  return mask;
}

nanoseconds PwmSchedule::close_time(std::size_t v) const noexcept {
  const Valve& valve = valves_[v];
  // on_time may be 0 for an open valve only after an immediate stop at its period start.
  const bool closes_in_period = valve.started && (mask_ >> v & 1u) != 0 && valve.on_time < period_;
  return closes_in_period ? valve.period_start + valve.on_time : nanoseconds::max();
}

nanoseconds PwmSchedule::next_event_time() const noexcept {
  // Every pending event lies after the last applied one (or at it, for an immediate start/stop
  // requested at that instant): period starts advance by T > 0 and an off event lies inside its
  // period, so the earliest pending event is next.
  nanoseconds t = nanoseconds::max();
  for (std::size_t v = 0; v < valve_count_; ++v) {
    t = std::min({t, valves_[v].next_period_start, close_time(v)});
  }
  return t;
}

PwmEdge PwmSchedule::peek_edge() const noexcept {
  const nanoseconds t = next_event_time();
  std::uint32_t mask = mask_;
  for (std::size_t v = 0; v < valve_count_; ++v) {
    const std::uint32_t bit = 1u << v;
    if (close_time(v) == t) mask &= ~bit;
    if (valves_[v].next_period_start == t) {
      const nanoseconds length = period_end_on_grid(valves_[v], t) - t;
      mask = on_time_for(valves_[v].requested_duty_pct, length) > nanoseconds(0) ? (mask | bit)
                                                                                 : (mask & ~bit);
    }
  }
  return PwmEdge{t, mask};
}

PwmEdge PwmSchedule::next_edge() noexcept {
  const nanoseconds t = next_event_time();
  for (std::size_t v = 0; v < valve_count_; ++v) {
    Valve& valve = valves_[v];
    const std::uint32_t bit = 1u << v;
    const bool was_open = (mask_ & bit) != 0;
    if (close_time(v) == t) mask_ &= ~bit;
    if (valve.next_period_start == t) {
      valve.started = true;
      valve.period_start = t;
      valve.next_period_start = period_end_on_grid(valve, t);
      valve.latched_duty_pct = valve.requested_duty_pct;
      valve.on_time = on_time_for(valve.latched_duty_pct, valve.next_period_start - t);
      mask_ = valve.on_time > nanoseconds(0) ? (mask_ | bit) : (mask_ & ~bit);
    }
    if (was_open && (mask_ & bit) == 0) valve.closed_at = t;
    if (!was_open && (mask_ & bit) != 0) valve.opened_at = t;
  }
  cursor_ = t;
  return PwmEdge{t, mask_};
}

}  // namespace weedspray::control
