// SPDX-License-Identifier: Apache-2.0
#include "io/linux/gpsd_gnss.hpp"

#include <gps.h>

#include <algorithm>
#include <cmath>
#include <thread>

namespace weedspray::io::hw {

struct GpsdGnss::Connection {
  gps_data_t data{};
};

namespace {

double finite_or_unknown(double value) {
  return std::isfinite(value) ? value : GnssFix::kUnknown;
}

GnssFixMode mode_of(int gpsd_mode) {
  if (gpsd_mode >= MODE_3D) return GnssFixMode::k3D;
  if (gpsd_mode == MODE_2D) return GnssFixMode::k2D;
  return GnssFixMode::kNone;
}

// A TPV report (and the latest SKY's satellites and DOP) as a fix.
GnssFix fix_of(const gps_data_t& data) {
  GnssFix fix;
  fix.mode = mode_of(data.fix.mode);
  if (data.set & TIME_SET) {
    fix.utc_ns = static_cast<std::int64_t>(data.fix.time.tv_sec) * 1'000'000'000 +
                 static_cast<std::int64_t>(data.fix.time.tv_nsec);
  }
  if (fix.mode != GnssFixMode::kNone) {
    fix.latitude_deg = finite_or_unknown(data.fix.latitude);
    fix.longitude_deg = finite_or_unknown(data.fix.longitude);
    fix.speed_m_per_s = finite_or_unknown(data.fix.speed);
    fix.course_deg = finite_or_unknown(data.fix.track);
    fix.eph_m = finite_or_unknown(data.fix.eph);
  }
  if (fix.mode == GnssFixMode::k3D) fix.altitude_m = finite_or_unknown(data.fix.altMSL);
  // gpsd reports a mode before the first position arrives (a TPV with only error estimates):
  // without a position it is no fix.
  if (!std::isfinite(fix.latitude_deg) || !std::isfinite(fix.longitude_deg)) {
    fix.mode = GnssFixMode::kNone;
  }
  fix.hdop = finite_or_unknown(data.dop.hdop);
  fix.satellites_used = static_cast<std::uint32_t>(std::max(0, data.satellites_used));
  return fix;
}

}  // namespace

GpsdGnss::GpsdGnss(GpsdGnssConfig config)
    : config_(std::move(config)), connection_(std::make_unique<Connection>()) {
  stats_.publish(counters_);
}

GpsdGnss::~GpsdGnss() {
  disconnect();
}

bool GpsdGnss::connect() noexcept {
  connection_->data = gps_data_t{};
  if (gps_open(config_.host.c_str(), config_.port.c_str(), &connection_->data) != 0) return false;
  if (gps_stream(&connection_->data, WATCH_ENABLE | WATCH_JSON, nullptr) != 0) {
    gps_close(&connection_->data);
    return false;
  }
  connected_ = true;
  return true;
}

void GpsdGnss::disconnect() noexcept {
  if (!connected_) return;
  gps_close(&connection_->data);
  connected_ = false;
}

bool GpsdGnss::next_fix(GnssFix& fix, std::chrono::nanoseconds wait) noexcept {
  const Steady::time_point deadline = Steady::now() + wait;
  bool got = false;
  if (!connected_) {
    // Between attempts: wait out the backoff (at most `wait` of it per call).
    if (Steady::now() < next_attempt_)
      std::this_thread::sleep_until(std::min(deadline, next_attempt_));
    if (Steady::now() >= next_attempt_) {
      if (connect()) {
        ++counters_.connects;
        retry_ = std::chrono::milliseconds(0);
      } else {
        ++counters_.connect_failures;
        retry_ =
            retry_.count() == 0 ? config_.first_retry : std::min(retry_ * 2, config_.max_retry);
        next_attempt_ = Steady::now() + retry_;
      }
    }
  }
  if (connected_) got = read_until(fix, deadline);
  if (got) ++counters_.fixes;
  counters_.connected = connected_;
  stats_.publish(counters_);
  return got;
}

bool GpsdGnss::read_until(GnssFix& fix, Steady::time_point deadline) noexcept {
  gps_data_t& data = connection_->data;
  for (;;) {
    const auto left =
        std::chrono::duration_cast<std::chrono::microseconds>(deadline - Steady::now());
    if (left.count() <= 0 || !gps_waiting(&data, static_cast<int>(left.count()))) return false;
    // Only what this message sets: a TPV sets MODE_SET, a SKY (satellites, DOP) does not.
    data.set = 0;
    if (gps_read(&data, nullptr, 0) < 0) {
      // gpsd went away (or sent what libgps could not read): reconnect after the first delay.
      disconnect();
      ++counters_.disconnects;
      retry_ = config_.first_retry;
      next_attempt_ = Steady::now() + retry_;
      return false;
    }
    if (data.set & MODE_SET) {
      fix = fix_of(data);
      return true;
    }
  }
}

}  // namespace weedspray::io::hw
