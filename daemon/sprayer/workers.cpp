// SPDX-License-Identifier: Apache-2.0
// The sprayer's non-real-time workers: cameras, tank level, GNSS (with the wheel calibration),
// the yaw-rate sensor.
#include <algorithm>
#include <bit>
#include <cstring>

#include "daemon/sprayer/loop_time.hpp"
#include "daemon/sprayer/sprayer.hpp"

namespace weedspray::daemon {

using loop_time::from_seconds;
using loop_time::seconds;
using namespace std::chrono_literals;

void Sprayer::camera_loop(std::stop_token stop, CameraWorker& worker) noexcept {
  CameraStatus status;
  while (!stop.stop_requested() && !status.started) {
    status.started = worker.camera->start();
    if (!status.started) {
      ++status.errors;
      worker.status.publish(status);
      io_.clock->sleep_until(io_.clock->now() + 1s);
    }
  }
  Nanos previous_frame{};
  Nanos busy_until{};  // when the previous frame's processing ended
  io::Frame frame;
  while (!stop.stop_requested()) {
    const io::FrameStatus got = worker.camera->next_frame(frame, 100ms);
    if (got == io::FrameStatus::kEnd) break;
    if (got != io::FrameStatus::kOk) {
      if (got == io::FrameStatus::kError) ++status.errors;
      continue;
    }
    // A frame captured while the previous one went through the network is already old: skip it
    // for the next, fresh one, so a model slower than the frame interval costs frames, not
    // latency. Colour-only sources take ~1 ms: a frame they find waiting is one delivered late
    // (the thread was held up), and skipping it would leave its ground unseen.
    if (worker.uses_model && frame.timestamp < busy_until) {
      ++status.frames_skipped;
      worker.status.publish(status);
      continue;
    }
    const Nanos asked = io_.clock->now();
    std::optional<InferenceGate::Turn> turn;
    if (worker.uses_model) turn.emplace(inference_gate_.acquire());
    const Nanos t0 = io_.clock->now();
    const vision::FrameResult& result = worker.pipeline->process(frame.view);
    turn.reset();
    FrameDensities densities;
    densities.capture_time = frame.timestamp;
    densities.ready_time = io_.clock->now();
    busy_until = densities.ready_time;
    densities.rows = result.rows;
    densities.cols = result.cols;
    std::copy(result.zone_density.begin(), result.zone_density.end(), densities.density.begin());
    std::copy(result.crop_density.begin(), result.crop_density.end(),
              densities.crop_density.begin());
    // The weed model failed (an empty error is a malformed frame: zero densities, no alarm).
    const bool injected = worker.injected_failure.load();
    densities.vision_failed =
        injected || (!worker.pipeline->last_frame_ok() && !worker.pipeline->last_error().empty());
    status.vision_failed = densities.vision_failed;
    if (densities.vision_failed) {
      if (injected) {
        densities.density.fill(0.0);
        densities.crop_density.fill(0.0);
      }
      ++status.vision_failures;
      static const std::string kInjected = "failure injected by a test";
      const std::string& error = injected ? kInjected : worker.pipeline->last_error();
      const std::size_t n = std::min(error.size(), status.vision_error.size() - 1);
      std::memcpy(status.vision_error.data(), error.data(), n);
      status.vision_error[n] = '\0';
    }
    worker.frames.try_push(densities);
    if (worker.snapshot.wanted())
      worker.snapshot.fill(frame.view, frame.timestamp, *worker.pipeline, result);
    status.frame_bytes = SnapshotHandoff::packed_bytes(frame.view);
    status.class_map_pixels = worker.pipeline->class_map_pixels();
    ++status.frames;
    status.gate_wait_ms = seconds(t0 - asked) * 1e3;
    status.vision_ms = seconds(densities.ready_time - t0) * 1e3;
    if (previous_frame.count() > 0) {
      const double interval = seconds(frame.timestamp - previous_frame);
      if (interval > 0) {
        status.frame_rate_hz = status.frame_rate_hz == 0
                                   ? 1.0 / interval
                                   : 0.8 * status.frame_rate_hz + 0.2 / interval;
      }
    }
    previous_frame = frame.timestamp;
    status.last_frame_time = frame.timestamp;
    worker.status.publish(status);
  }
}

void Sprayer::tank_loop(std::stop_token stop) noexcept {
  const Nanos period = from_seconds(config_.modbus.poll_period_s);
  Nanos next = io_.clock->now();
  while (!stop.stop_requested()) {
    tank_.publish(io_.tank->read());
    next += period;
    // Sleep in short slices so a stop request is honoured promptly.
    while (!stop.stop_requested() && io_.clock->now() < next) {
      io_.clock->sleep_until(std::min(next, io_.clock->now() + 100ms));
    }
  }
}

void Sprayer::gnss_loop(std::stop_token stop) noexcept {
  // Each wait is short so a stop request is honoured promptly; the receiver reconnects itself.
  constexpr Nanos kWait = 100ms;
  const Nanos lost_fix_timeout = from_seconds(config_.gnss.lost_fix_timeout_s);
  control::WheelCalibration calibration(control::WheelCalibrationConfig{});
  std::uint64_t calibration_requests_served = 0;
  while (!stop.stop_requested()) {
    io::GnssFix fix;
    const bool got = io_.gnss->next_fix(fix, kWait);
    // The wheel counter as the fix arrives: the same latency at both ends of a run cancels.
    const std::uint64_t wheel_count = io_.wheel != nullptr ? io_.wheel->snapshot().count : 0;
    const Nanos arrived = io_.clock->now();
    const io::GnssLinkStats link = io_.gnss->stats();
    if (got) gnss_.publish(GnssSample{fix, arrived, link.connect_failures + link.disconnects});
    gnss_link_.publish(link);
    const std::uint64_t requests = wheel_calibration_requests_.load();
    if (requests != calibration_requests_served) {
      calibration_requests_served = requests;
      control::WheelCalibrationConfig config;
      config.run_distance_m = std::bit_cast<double>(wheel_calibration_distance_bits_.load());
      calibration = control::WheelCalibration(config);
      calibration.start();
      wheel_calibration_.publish({requests, calibration.status()});
    }
    if (got && calibration.status().state != control::WheelCalibrationState::kIdle &&
        calibration.status().state != control::WheelCalibrationState::kDone) {
      const GnssSample sample{fix, arrived, 0};
      control::CalibrationFix c;
      c.usable = gnss_fix_usable(sample, arrived, lost_fix_timeout);
      c.latitude_deg = fix.latitude_deg;
      c.longitude_deg = fix.longitude_deg;
      c.course_deg = fix.course_deg;
      c.speed_m_per_s = fix.speed_m_per_s;
      wheel_calibration_.publish({requests, calibration.add_fix(c, wheel_count)});
    }
  }
}

void Sprayer::imu_loop(std::stop_token stop) noexcept {
  // 100 Hz: a sysfs read of an I2C gyro takes ~0.3 ms; the control loop uses the latest.
  constexpr Nanos kPeriod = 10ms;
  io::PeriodicLoop loop(*io_.clock, kPeriod, io_.clock->now());
  std::uint64_t errors = 0;
  while (!stop.stop_requested()) {
    loop.wait_next();
    const io::YawRateSample sample = io_.yaw_sensor->read();
    if (!sample.ok) {
      ++errors;
      continue;  // the control loop stops using the rate once it is stale
    }
    imu_yaw_rate_.publish(io::Stamped<double>{sample.deg_per_s, io_.clock->now(), errors});
  }
}

std::uint64_t Sprayer::start_wheel_calibration(double run_distance_m) noexcept {
  if (io_.gnss == nullptr || io_.wheel == nullptr) return 0;
  wheel_calibration_distance_bits_.store(std::bit_cast<std::uint64_t>(run_distance_m));
  return wheel_calibration_requests_.fetch_add(1) + 1;
}

}  // namespace weedspray::daemon
