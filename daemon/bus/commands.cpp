// SPDX-License-Identifier: Apache-2.0
#include "daemon/bus/commands.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "daemon/config/config_schema.hpp"
#include "daemon/config/target_rate.hpp"
#include "daemon/supervision/alarm_details.hpp"

namespace weedspray::daemon {

CommandResult Commands::set_pressure_setpoint(double mpa) {
  constexpr double kMin = 0.05;
  const double max = std::min(1.0, to_.config.alarms.over_pressure_mpa);
  if (!(mpa >= kMin && mpa < max)) {
    char message[160];
    std::snprintf(message, sizeof message,
                  "pressure %.3g MPa outside %.3g..%.3g MPa (below alarms.over_pressure_mpa)", mpa,
                  kMin, max);
    return {kErrorInvalidArgument, message};
  }
  to_.operation.set_setpoint_mpa(mpa);
  spdlog::info("pressure set-point {:.3f} MPa", mpa);
  to_.operation.publish_params();
  return {};
}

CommandResult Commands::set_decision_threshold(double threshold) {
  const std::string refusal = outside_key_range("spray.decision_threshold", threshold);
  if (!refusal.empty()) return {kErrorInvalidArgument, "decision threshold " + refusal};
  to_.operation.set_decision_threshold(threshold);
  spdlog::info("decision threshold {:.3f} (until the configuration is reloaded)", threshold);
  to_.operation.publish_params();
  return {};
}

CommandResult Commands::set_target_rate(double l_per_ha) {
  const RateFlow rate = flow_for_target_rate(to_.config, l_per_ha);
  if (!rate.refusal.empty()) return {kErrorInvalidArgument, rate.refusal};
  to_.operation.set_nominal_flow_l_per_min(rate.flow_l_per_min);
  spdlog::info("dose {:.1f} L/ha: {:.3f} L/min per nozzle (until the configuration is reloaded)",
               l_per_ha, rate.flow_l_per_min);
  to_.operation.publish_params();
  return {};
}

CommandResult Commands::reload_config(ReloadReply reply) {
  to_.reloads.request(std::move(reply));
  return {};
}

CommandResult Commands::clear_alarms() {
  if (sprayer_ != nullptr && !sprayer_->reset_estop())
    spdlog::warn("E-stop circuit still open: the stop stays latched (close it, then clear)");
  const AlarmMask cleared = to_.alarms.clear();
  if (sprayer_ != nullptr) sprayer_->resume_heartbeat();
  to_.operation.reset_trips();
  report_alarms_cleared(cleared, "sprayctl clear-alarms", bus_);
  if (to_.operation.state() == SprayerState::kFault)
    to_.operation.transition(StateEvent::kAlarmsCleared, "ClearAlarms");
  to_.operation.publish_params();
  return {};
}

CommandResult Commands::inject_sim_fault(const std::string& name) {
  return to_.world.inject_fault(name);
}

CommandResult Commands::snapshot(std::uint32_t camera, SnapshotReply reply) {
  if (live_view_ == nullptr)
    return {kErrorUnavailable, "Snapshot: the cameras are not running yet"};
  return live_view_->request(camera, to_.backends.clock->now(), std::move(reply));
}

CommandResult Commands::calibrate_wheel(double run_distance_m, std::uint64_t& request) {
  if (!(run_distance_m >= 10.0 && run_distance_m <= 5000.0)) {
    return {kErrorInvalidArgument,
            "CalibrateWheel: the straight run must be 10..5000 m (100 m or more for an "
            "autonomous receiver, 1.5 m position error at each end)"};
  }
  if (sprayer_ == nullptr)
    return {kErrorUnavailable, "CalibrateWheel: the sprayer is not running yet"};
  request = sprayer_->start_wheel_calibration(run_distance_m);
  if (request == 0) {
    return {kErrorNotPermitted,
            "CalibrateWheel: needs a GNSS receiver ([gnss] enabled = true) and a wheel sensor "
            "(wheel.source = \"pulses\")"};
  }
  spdlog::info("wheel calibration {} started: {:.0f} m straight run", request, run_distance_m);
  return {};
}

CommandResult Commands::motion(double& speed_m_per_s, double& distance_m, std::uint64_t& time_ns,
                               SharedFix& fix) {
  if (sprayer_ == nullptr) return {kErrorUnavailable, "Motion: the sprayer is not running yet"};
  const ControlStatus control = sprayer_->control();
  if (control.cycles == 0) return {kErrorUnavailable, "Motion: no control cycle yet"};
  speed_m_per_s = control.speed_m_per_s;
  distance_m = control.distance_m;
  time_ns = static_cast<std::uint64_t>(control.time.count());
  fix = {};
  if (to_.backends.has_gnss()) {
    // Only a fix this board would place its own records by; its time is when it arrived here.
    const GnssSample gnss = sprayer_->gnss();
    const auto timeout = std::chrono::duration_cast<std::chrono::nanoseconds>(
        std::chrono::duration<double>(to_.config.gnss.lost_fix_timeout_s));
    if (gnss_fix_usable(gnss, to_.backends.clock->now(), timeout) && gnss.value.has_position()) {
      fix = {gnss.value.latitude_deg,
             gnss.value.longitude_deg,
             gnss.value.course_deg,
             gnss.value.mode,
             static_cast<std::uint64_t>(gnss.sample_time.count()),
             gnss.value.utc_ns};
    }
  }
  return {};
}

CommandResult Commands::feed_shared_motion(double speed_m_per_s, double distance_m,
                                           std::uint64_t sender_time_ns, const SharedFix& fix) {
  if (to_.config.speed.source != "fleet") {
    return {kErrorNotPermitted,
            "FeedSharedMotion: this board takes its speed from speed.source = \"" +
                to_.config.speed.source + "\", not \"fleet\""};
  }
  constexpr double kMaxSpeed = 50.0;  // m/s: no sprayer drives faster; a garbled sample does
  if (!(speed_m_per_s >= 0.0 && speed_m_per_s <= kMaxSpeed) || !std::isfinite(distance_m)) {
    return {kErrorInvalidArgument,
            "FeedSharedMotion: speed must be 0..50 m/s and the distance a number"};
  }
  if (sprayer_ == nullptr)
    return {kErrorUnavailable, "FeedSharedMotion: the sprayer is not running yet"};
  sprayer_->feed_shared_motion(speed_m_per_s, distance_m, sender_time_ns, fix);
  return {};
}

CommandResult Commands::calibration_command(
    const std::function<CommandResult(Calibrations&)>& command) {
  Calibrations* calibrations = to_.operation.calibrations();
  if (calibrations == nullptr || sprayer_ == nullptr)
    return {kErrorUnavailable, "the sprayer is not running yet"};
  const CommandResult result = command(*calibrations);
  if (result.ok()) to_.operation.publish_params();
  return result;
}

CommandResult Commands::start_catch_test(double seconds) {
  return calibration_command([&](Calibrations& c) {
    return c.start_catch_test(seconds, to_.operation.calibration_context());
  });
}

CommandResult Commands::calibrate_meter(double volume_l) {
  return calibration_command([&](Calibrations& c) { return c.calibrate_meter(volume_l); });
}

CommandResult Commands::calibrate_nozzles() {
  return calibration_command(
      [&](Calibrations& c) { return c.calibrate_nozzles(to_.operation.calibration_context()); });
}

CommandResult Commands::test_valve(std::uint32_t nozzle, double duty_pct, double seconds) {
  return calibration_command([&](Calibrations& c) {
    return c.test_valve(nozzle, duty_pct, seconds, to_.operation.calibration_context());
  });
}

CommandResult Commands::test_pump(double seconds) {
  return calibration_command(
      [&](Calibrations& c) { return c.test_pump(seconds, to_.operation.calibration_context()); });
}

void Commands::bus_lost() {
  spdlog::critical(
      "D-Bus connection lost: sprayctl can no longer stop the sprayer, so it stops now "
      "(valves closed, pump off) and exits for systemd to restart it Idle");
  to_.stop_now();
}

}  // namespace weedspray::daemon
