// SPDX-License-Identifier: Apache-2.0
// The control loop's thread: travel, frames, pressure and the meter in, valve duties out.
#include <algorithm>
#include <cmath>

#include "control/turn_rate.hpp"
#include "daemon/sprayer/geometry.hpp"
#include "daemon/sprayer/loop_time.hpp"
#include "daemon/sprayer/shared_position.hpp"
#include "daemon/sprayer/sprayer.hpp"
#include "daemon/sprayer/step_settings.hpp"

namespace weedspray::daemon {

using loop_time::from_seconds;
using loop_time::seconds;
using namespace std::chrono_literals;

static_assert(control::kMaxCommandNozzles == io::kMaxValves);

namespace {

// Same meter K and nozzle lines (what the flow trim's correction is relative to).
bool same_calibration(const LiveParams& a, const LiveParams& b, std::size_t nozzles) noexcept {
  if (a.flow_pulses_per_litre != b.flow_pulses_per_litre) return false;
  for (std::size_t n = 0; n < nozzles; ++n) {
    const control::NozzleLine& x = a.lines[n];
    const control::NozzleLine& y = b.lines[n];
    if (x.slope_l_per_min_per_pct != y.slope_l_per_min_per_pct ||
        x.intercept_l_per_min != y.intercept_l_per_min ||
        x.calibration_pressure_mpa != y.calibration_pressure_mpa ||
        x.full_open_flow_l_per_min != y.full_open_flow_l_per_min)
      return false;
  }
  return true;
}

}  // namespace
// per phase window (control/phase_windows.hpp) into the detector.
void Sprayer::feed_nozzle_health(control::PhaseWindows& windows, Nanos now, bool spraying,
                                 std::uint64_t pulses, double pulses_per_litre) noexcept {
  io::ValvePwmStats pwm;
  if (!pwm_driver_->try_stats(pwm)) return;  // the slot was busy: the next cycle catches up
  if (!spraying || pwm.expired) {
    windows.restart();
    return;
  }
  if (windows.update(pwm.schedule_start, pwm.last_mask, pwm.last_mask_written_at, now, pulses,
                     pulses_per_litre)) {
    nozzle_health_->add_window(windows.open_s(), windows.metered_l(), windows.window_s());
  }
}

void Sprayer::control_loop(std::stop_token stop) noexcept {
  constexpr Nanos kPeriod = kControlLoopPeriod;  // 500 Hz (step_settings.hpp)
  constexpr Nanos kFlowWindow = 250ms;
  io::PeriodicLoop loop(*io_.clock, kPeriod, io_.clock->now(), &timing_.control_loop,
                        from_seconds(config_.alarms.timing_tolerance_ms / 1e3));
  const std::size_t nozzles = nozzle_owner_.size();
  const Nanos record_period = from_seconds(1.0 / config_.pwm.frequency_hz);
  LiveParams params = params_.read();
  std::uint64_t params_version = params_.version();
  ControlStatus status;
  status.nozzles = static_cast<std::uint32_t>(nozzles);
  Nanos last = io_.clock->now();
  Nanos next_record = last + record_period;
  double volume_at_last_record = 0;
  std::uint64_t flow_count_start = io_.flow != nullptr ? io_.flow->snapshot().count : 0;
  std::uint64_t volume_count = flow_count_start;
  Nanos flow_window_start = last;
  double fixed_distance = 0;
  std::uint64_t frames_lost = 0;
  // speed.source = "fleet": another board's speed and odometer are this board's travel.
  const bool fleet_travel = speed_source_ == SpeedSource::kFleet;
  const bool wheel_travel = odometry_.has_value() && !fleet_travel;
  SharedMotionTracker shared_motion(from_seconds(config_.speed.shared_timeout_s));
  SharedMotionSample shared_sample;
  GnssSample gnss;
  // gnss.source = "fleet": the owning board's fix comes with its motion samples; this loop is
  // then the one writer of gnss_ (no gpsd thread runs).
  const bool fleet_fix = io_.gnss_from_fleet && fleet_travel;
  const bool has_gnss = io_.gnss != nullptr || fleet_fix;
  const Nanos lost_fix_timeout = from_seconds(config_.gnss.lost_fix_timeout_s);
  // Turn compensation (control/turn_rate.hpp): each nozzle's ground speed and the extra
  // distance its arc has run beyond the centre line's, so the rate law and the schedule use
  // the nozzle's own travel on a curve.
  const bool gnss_yaw = config_.turn.yaw_source == "gnss" && io_.gnss != nullptr;
  const bool imu_yaw = config_.turn.yaw_source == "imu" && io_.yaw_sensor != nullptr;
  const bool turn_compensation = config_.turn.compensation && (gnss_yaw || imu_yaw);
  constexpr Nanos kImuStale = 100ms;  // 10 of its samples: an older rate is not used
  io::Stamped<double> imu_sample;
  control::YawRateConfig yaw_config;
  yaw_config.min_speed_m_per_s = config_.turn.min_speed_m_per_s;
  yaw_config.filter_time_constant_s = config_.turn.yaw_filter_s;
  yaw_config.max_fix_gap_s = config_.gnss.lost_fix_timeout_s;
  control::YawRateEstimator yaw_rate(yaw_config);
  Nanos last_fix_time{-1};
  std::array<double, io::kMaxValves> right_offset_m{};
  for (std::size_t n = 0; n < nozzles; ++n)
    right_offset_m[n] = nozzle_right_offset_m(config_.boom, n);
  std::array<double, io::kMaxValves> nozzle_speed{};
  std::array<double, io::kMaxValves> arc_extra_m{};  // nozzle's travel minus the centre line's
  std::array<double, io::kMaxValves> frame_odometer{};
  std::array<double, io::kMaxValves> target_flow{};                // the rate law's flow per nozzle
  std::array<control::NozzleLine, io::kMaxValves> scaled_lines{};  // rescaled by the re-check
  RecheckWindow recheck_window;
  io::ValvePwmStats pwm_grid;  // the valve thread's schedule start
  bool was_enabled = false;
  // One staggered phase (period / nozzles), the meter read a lag behind the valves.
  control::PhaseWindows health_windows(
      from_seconds(1.0 / (config_.pwm.frequency_hz *
                          static_cast<double>(std::max<std::size_t>(nozzles, 1)))),
      control::kMeterLag);
  std::uint64_t health_reset_seen = params.trip_reset;
  LiveParams trim_calibration = params;  // the meter K and lines the trim learned against
  while (!stop.stop_requested()) {
    loop.wait_next();
    const Nanos now = io_.clock->now();
    const double dt = seconds(now - last);
    last = now;
    if (params_.version() != params_version) {
      params_version = params_.version();
      params_.try_read(params);
      // The trim's correction is relative to the calibration it learned against: a new meter K
      // or nozzle line (sprayctl calibrate) starts it afresh.
      if (!same_calibration(trim_calibration, params, nozzles)) {
        nozzle_command_.reset_trim();
        if (recheck_) recheck_->reset();  // a new reference: every nozzle read afresh
        trim_calibration = params;
      }
    }
    // Travel: the wheel's pulses are the distance base whenever it is wired (another board's
    // odometer with speed.source = "fleet"); the speed comes from speed.source
    // (daemon/sprayer/ground_speed.hpp).
    GroundSpeedInputs speed_in;
    speed_in.source = speed_source_;
    speed_in.wheel_wired = odometry_.has_value();
    speed_in.fixed_speed_m_per_s = config_.wheel.fixed_speed_m_per_s;
    if (odometry_) {
      const io::PulseSnapshot wheel = io_.wheel->snapshot();
      odometry_->update(wheel.count, wheel.last_edge_time, now);
      if (wheel_travel) status.distance_m = odometry_->distance_m();
      speed_in.wheel_speed_m_per_s = odometry_->speed_m_per_s();
    }
    if (fleet_travel) {
      shared_motion_.try_read(shared_sample);  // a collision keeps the previous sample
      shared_motion.update(shared_sample, now);
      speed_in.shared_fresh = shared_motion.fresh();
      speed_in.shared_speed_m_per_s = shared_motion.speed_m_per_s();
      status.shared_motion_lost = !shared_motion.fresh();
      status.shared_motion_seen = shared_motion.had_sample();
      if (fleet_fix && shared_motion.took_sample()) {
        gnss = shared_gnss_sample(shared_sample, shared_motion);
        gnss_.publish(gnss);
      }
    }
    if (io_.gnss != nullptr) gnss_.try_read(gnss);  // a collision keeps the previous fix
    if (has_gnss) {
      speed_in.gnss_usable = gnss_fix_usable(gnss, now, lost_fix_timeout);
      speed_in.gnss_speed_m_per_s = gnss.value.speed_m_per_s;
    }
    if (io_.gnss != nullptr) {  // gnss_yaw: a receiver's own fixes only
      if (turn_compensation && gnss_yaw && gnss.sample_time != last_fix_time) {
        last_fix_time = gnss.sample_time;
        // The receiver's own fix times difference best (no USB or gpsd latency jitter).
        const double fix_time_s = gnss.value.utc_ns != 0
                                      ? static_cast<double>(gnss.value.utc_ns) * 1e-9
                                      : seconds(gnss.sample_time);
        if (speed_in.gnss_usable) {
          yaw_rate.add_fix(gnss.value.course_deg, gnss.value.speed_m_per_s, fix_time_s);
        } else {
          yaw_rate.reset();
        }
      }
      if (turn_compensation && gnss_yaw && !speed_in.gnss_usable) yaw_rate.reset();
    }
    const GroundSpeed ground = select_ground_speed(speed_in);
    status.speed_m_per_s = ground.speed_m_per_s;
    status.speed_source = ground.used;
    status.speed_fell_back = ground.fell_back;
    if (fleet_travel) {
      status.distance_m = shared_motion.distance_m();
    } else if (!odometry_) {
      fixed_distance += status.speed_m_per_s * dt;
      status.distance_m = fixed_distance;
    }
    status.yaw_rate_deg_per_s = 0.0;
    if (turn_compensation && gnss_yaw) status.yaw_rate_deg_per_s = yaw_rate.rate_deg_per_s();
    if (turn_compensation && imu_yaw && imu_yaw_rate_.try_read(imu_sample) &&
        now - imu_sample.sample_time <= kImuStale) {
      status.yaw_rate_deg_per_s = imu_sample.value;
    }
    for (std::size_t n = 0; n < nozzles; ++n) {
      nozzle_speed[n] = control::nozzle_ground_speed_m_per_s(
          status.speed_m_per_s, status.yaw_rate_deg_per_s, right_offset_m[n]);
      arc_extra_m[n] += (nozzle_speed[n] - status.speed_m_per_s) * dt;
    }
    if (io_.flow != nullptr) {
      const io::PulseSnapshot flow = io_.flow->snapshot();
      // The volume is the meter's pulses themselves, counted in every state: integrating the
      // windowed flow below would lag it and lose part of each start and stop.
      status.volume_l +=
          static_cast<double>(flow.count - volume_count) / params.flow_pulses_per_litre;
      volume_count = flow.count;
      status.flow_pulses = flow.count;
      // Measured flow over a sliding window.
      if (now - flow_window_start >= kFlowWindow) {
        status.flow_l_per_min = static_cast<double>(flow.count - flow_count_start) /
                                params.flow_pulses_per_litre / seconds(now - flow_window_start) *
                                60.0;
        flow_count_start = flow.count;
        flow_window_start = now;
      }
    }
    // New frames: pin their densities to the ground they imaged. Densities (not duties) are
    // pinned so the rate law uses the speed and pressure at the moment the patch is sprayed.
    for (std::size_t c = 0; c < camera_count_; ++c) {
      auto& worker = cameras_[c];
      while (auto frame = worker.frames.try_pop()) {
        const double frame_distance =
            wheel_travel
                ? odometry_->distance_at(frame->capture_time)
                : status.distance_m - status.speed_m_per_s * seconds(now - frame->capture_time);
        const auto zones = static_cast<std::size_t>(frame->rows * frame->cols);
        // More than 5 % of a footprint of ground between two frames was never seen.
        if (frame_distance - worker.last_frame_distance_m > 1.05 * worker.footprint_length_m &&
            worker.last_frame_distance_m > -1e8) {
          ++status.coverage_gaps;
        }
        worker.last_frame_distance_m = frame_distance;
        worker.vision_failed = frame->vision_failed;
        // Each nozzle's own travel when the frame was taken (the centre line's when driving
        // straight): the plan and the look-ahead are in that nozzle's odometer.
        const auto count = static_cast<std::size_t>(worker.nozzle_count);
        const double since_capture_s = seconds(now - frame->capture_time);
        for (std::size_t local = 0; local < count; ++local) {
          const std::size_t n = local + static_cast<std::size_t>(worker.first_nozzle);
          const double extra = nozzle_speed[n] - status.speed_m_per_s;
          frame_odometer[local] = frame_distance + arc_extra_m[n] - extra * since_capture_s;
        }
        const std::span<const double> odometers(frame_odometer.data(), count);
        worker.scheduler->add_frame(odometers,
                                    std::span<const double>(frame->density.data(), zones));
        worker.crop_scheduler->add_frame(
            odometers, std::span<const double>(frame->crop_density.data(), zones));
        const Nanos scheduled = io_.clock->now();
        status.last_latency_ms = seconds(scheduled - frame->capture_time) * 1e3;
        ++status.frames_scheduled;
        if (!latencies_.try_push(static_cast<float>(status.last_latency_ms))) ++frames_lost;
      }
    }
    PressureStatus pressure;
    const bool have_pressure = pressure_.try_read(pressure);
    const bool pressure_stale = !have_pressure || !pressure.sensor_ok ||
                                seconds(now - pressure.time) > params.stale_timeout_s;
    status.inputs_stale = pressure_stale;
    // Without the owning board's samples the ground under the nozzles is unknown: closed.
    const bool spray = params.valves_enabled && !pressure_stale && !status.shared_motion_lost;
    // A calibration moves liquid only with the pump on (the daemon runs it for the
    // calibration in Idle) and the pressure sensor fresh.
    const bool calibrating = params.calibration_valves && params.pump_enabled &&
                             !params.valves_enabled && !pressure_stale;
    // The schedule judges a planned density at the pressure the last cycle's duties used.
    const double compensation_pressure = nozzle_command_.outputs().compensation_pressure_mpa;
    for (std::size_t n = 0; n < nozzles; ++n) {
      const int owner = nozzle_owner_[n];
      double density = 0;
      if (owner >= 0) {
        const auto& worker = cameras_[static_cast<std::size_t>(owner)];
        // The plan holds densities: the rate law says which of them open the valve, so ground
        // that needs no spray closes the valve with the closing lead.
        const auto sprays = [&](double planned_density) {
          return control::spray_decision(params.law, params.lines[n], planned_density,
                                         nozzle_speed[n], compensation_pressure)
                     .duty_pct > 0.0;
        };
        const std::size_t local = n - static_cast<std::size_t>(worker.first_nozzle);
        const double nozzle_odometer = status.distance_m + arc_extra_m[n];
        density = worker.scheduler->value_at(local, nozzle_odometer, nozzle_speed[n], sprays);
        status.crop_density[n] =
            worker.crop_scheduler->duty_at(local, nozzle_odometer, nozzle_speed[n]);
      }
      status.density[n] = density;
      // A camera whose weed model fails closes its own nozzles until it processes frames again.
      const bool blind = owner >= 0 && cameras_[static_cast<std::size_t>(owner)].vision_failed;
      target_flow[n] = spray && !blind
                           ? control::target_flow_l_per_min(params.law, density, nozzle_speed[n])
                           : 0.0;
    }
    // The headland re-check (control/nozzle_recheck.hpp) may hold one nozzle open alone and
    // rescales each nozzle's line by its last reading.
    std::span<const control::NozzleLine> command_lines(params.lines.data(), nozzles);
    bool recheck_holds = false;
    if (recheck_) {
      const bool started = params.valves_enabled && !was_enabled;
      if (started) recheck_->reset();  // a new job: re-check at its first window
      recheck_holds = step_recheck(recheck_window, now, spray, target_flow, pressure, params,
                                   status, scaled_lines);
      command_lines = std::span<const control::NozzleLine>(scaled_lines.data(), nozzles);
    }
    was_enabled = params.valves_enabled;
    // The duties (control/nozzle_command_step.hpp): the lab's rig runs the same step at the
    // same period, so `weedspray-lab experiment` measures this law, quantiser and trim.
    control::NozzleCommandInputs command_in;
    command_in.dt_s = dt;
    command_in.spraying = spray && !recheck_holds;
    command_in.trim = io_.flow != nullptr;
    command_in.law = params.law;
    command_in.pressure_compensation = params.pressure_compensation;
    command_in.pressure_mpa = pressure.pressure_mpa;
    command_in.setpoint_mpa = params.setpoint_mpa;
    command_in.pulses = status.flow_pulses;
    command_in.pulses_per_litre = params.flow_pulses_per_litre;
    command_in.target_flow_l_per_min = std::span<const double>(target_flow.data(), nozzles);
    command_in.lines = command_lines;
    // The PWM grid's time, for flows above the band (alternating whole periods); a busy slot
    // keeps the last read (the schedule's start moves only when the valves restart).
    (void)pwm_driver_->try_stats(pwm_grid);
    command_in.schedule_time_s = pwm_grid.expired ? -1.0 : seconds(now - pwm_grid.schedule_start);
    const control::NozzleCommandOutputs& commanded = nozzle_command_.step(command_in);
    io::ValveCommand command;
    command.valve_count = static_cast<std::uint32_t>(nozzles);
    double open_sum = 0;
    for (std::size_t n = 0; n < nozzles; ++n) {
      // A calibration holds the duties it asked for (spray is off then: the step closed all);
      // so does a re-check (the step was told not to spray).
      command.duty_pct[n] = calibrating     ? params.calibration_duty_pct[n]
                            : recheck_holds ? recheck_->duties()[n]
                                            : commanded.duty_pct[n];
      open_sum += command.duty_pct[n] / 100.0;
    }
    status.open_fraction = nozzles > 0 ? open_sum / static_cast<double>(nozzles) : 0.0;
    if (open_sum > 0.0) status.valves_last_open = now;
    status.flow_trim_active = commanded.trim.active;
    status.flow_trim_correction = commanded.trim.correction;
    status.calibration_ratio = commanded.trim.calibration_ratio;
    status.calibration_ratio_known = commanded.trim.calibration_ratio_known;
    command.issued_at = now;
    pwm_driver_->command(command);
    for (std::size_t n = 0; n < nozzles; ++n) status.duty_pct[n] = command.duty_pct[n];
    if (nozzle_health_ && io_.flow != nullptr) {
      // ClearAlarms after a clean: the nozzles' flows are learned afresh as the new baseline.
      if (params.trip_reset != health_reset_seen) {
        health_reset_seen = params.trip_reset;
        nozzle_health_->reset();
      }
      status.nozzle_health_reset = health_reset_seen;
      feed_nozzle_health(health_windows, now, spray, status.flow_pulses,
                         params.flow_pulses_per_litre);
      for (std::size_t n = 0; n < std::min(nozzles, control::kMaxHealthNozzles); ++n)
        status.nozzle_flow_ratio[n] = nozzle_health_->ratio(n);
      status.nozzle_flow_fault = nozzle_health_->alarmed_nozzle();
      status.nozzle_flow_fault_low = nozzle_health_->alarmed_low();
    }

    if (spray && status.speed_m_per_s > 0) {
      double nozzle_speed_sum = 0;  // the boom's swept width x speed, each nozzle on its arc
      for (std::size_t n = 0; n < nozzles; ++n) nozzle_speed_sum += nozzle_speed[n];
      const double area = nozzle_speed_sum * dt * config_.boom.nozzle_width_m;
      status.area_m2 += area;
      status.uniform_volume_l += control::nominal_dose_l_per_m2(params.law) * area;
    }
    if (now >= next_record) {
      next_record += record_period;
      if (next_record <= now) next_record = now + record_period;
      AppliedRecord record;
      record.time = now;
      record.distance_m = status.distance_m;
      record.speed_m_per_s = status.speed_m_per_s;
      record.pressure_mpa = pressure.pressure_mpa;
      record.flow_l_per_min = status.flow_l_per_min;
      record.volume_l = status.volume_l - volume_at_last_record;
      volume_at_last_record = status.volume_l;
      record.nozzles = status.nozzles;
      for (std::size_t n = 0; n < nozzles; ++n) {
        record.duty_pct[n] = static_cast<float>(status.duty_pct[n]);
        record.density[n] = static_cast<float>(status.density[n]);
        record.crop_density[n] = static_cast<float>(status.crop_density[n]);
        record.nozzle_speed_m_per_s[n] = static_cast<float>(nozzle_speed[n]);
        record.nozzle_flow_l_per_min[n] = static_cast<float>(control::flow_for_duty_l_per_min(
            params.lines[n], status.duty_pct[n], pressure.pressure_mpa));
      }
      if (has_gnss) {
        record.fix = gnss.value;
        record.fix_time = gnss.sample_time;
        record.fix_usable = speed_in.gnss_usable;
      }
      record.yaw_rate_deg_per_s = status.yaw_rate_deg_per_s;
      records_.try_push(record);  // a full queue drops the record (the writer is stuck)
    }
    status.time = now;
    status.cycles = loop.cycles();
    status.overruns = loop.overruns();
    status.misses = loop.misses();
    control_.publish(status);
  }
}

}  // namespace weedspray::daemon
