// SPDX-License-Identifier: Apache-2.0
#include "daemon/sprayer/step_settings.hpp"

#include <algorithm>
#include <cstdint>

namespace weedspray::daemon {
namespace {

std::chrono::nanoseconds from_seconds(double s) {
  return std::chrono::nanoseconds(static_cast<std::int64_t>(s * 1e9));
}

}  // namespace

control::FuzzyPidConfig pressure_controller_config(const Config& config) {
  const auto& p = config.pressure;
  control::FuzzyPidConfig c;
  c.base.gains = {p.kp, p.ki, p.kd};
  c.base.output_min = p.output_min;
  c.base.output_max = p.output_max;
  c.base.anti_windup = control::AntiWindup::kBackCalculation;
  c.base.derivative_filter_s = 0.01;
  c.correction_weights = {p.cp, p.ci, p.cd};
  c.error_range = p.range_mpa;
  return c;
}

control::PressureLoopConfig pressure_loop_config(const Config& config) {
  control::PressureLoopConfig c;
  c.mode = config.pressure.controller == "pid" ? control::PressureControlMode::kPid
                                               : control::PressureControlMode::kFuzzyPid;
  c.controller = pressure_controller_config(config);
  c.period_s = 1.0 / config.pressure.loop_hz;
  return c;
}

control::PwmConfig pwm_config(const Config& config) {
  control::PwmConfig pwm;
  const auto n = static_cast<std::size_t>(config.boom.nozzles);
  pwm.valve_count = n;
  pwm.frequency_hz = config.pwm.frequency_hz;
  pwm.phase_mode = config.pwm.staggered ? control::PwmPhaseMode::kStaggered
                                        : control::PwmPhaseMode::kSynchronous;
  if (config.pwm.order == "outer_first") {
    pwm.order = control::outer_first_order(n);
  } else if (config.pwm.order == "inner_first") {
    pwm.order = control::outer_first_order(n);
    std::reverse(pwm.order.begin(), pwm.order.end());
  } else {
    for (std::size_t i = 0; i < n; ++i) pwm.order.push_back(i);
  }
  pwm.min_on_time = from_seconds(config.pwm.min_on_s);
  pwm.min_off_time = from_seconds(config.pwm.min_off_s);
  // A spray start/stop happens when the ground under the nozzle starts/stops needing it, not at
  // the valve's next period start (up to 50 cm later at 2.5 m/s and 5 Hz).
  pwm.immediate_start_stop = true;
  return pwm;
}

control::NozzleCommandConfig nozzle_command_config(const Config& config) {
  control::NozzleCommandConfig c;
  c.nozzles = static_cast<std::size_t>(config.boom.nozzles);
  // The valves' PWM grid, from the schedule the valve thread runs.
  const control::PwmSchedule schedule(pwm_config(config));
  c.pwm_period_s = std::chrono::duration<double>(schedule.period()).count();
  for (std::size_t n = 0; n < c.nozzles; ++n)
    c.phase_offset_s[n] = std::chrono::duration<double>(schedule.phase_offset(n)).count();
  c.cycle_s = std::chrono::duration<double>(kControlLoopPeriod).count();
  const int n = config.spray.quantiser_levels;
  if (n >= 2) {
    // Closed, n levels from duty_min_pct to duty_max_pct, open: at most 16 (n <= 14).
    std::size_t count = 0;
    c.quantiser_levels_pct[count++] = 0.0;
    for (int i = 0; i < n; ++i) {
      const double level = config.spray.duty_min_pct +
                           (config.spray.duty_max_pct - config.spray.duty_min_pct) * i / (n - 1);
      // duty_min_pct = 0 or duty_max_pct = 100: that level is the closed or open one already.
      if (level > c.quantiser_levels_pct[count - 1] && level < 100.0)
        c.quantiser_levels_pct[count++] = level;
    }
    c.quantiser_levels_pct[count++] = 100.0;
    c.quantiser_level_count = count;
    c.quantiser_hysteresis_pct = config.spray.hysteresis_pct;
  }
  return c;
}

control::SprayLawConfig spray_law_config(const Config& config) {
  control::SprayLawConfig law;
  law.nominal_flow_l_per_min = config.spray.nominal_flow_l_per_min;
  law.nozzle_width_m = config.boom.nozzle_width_m;
  law.nominal_speed_m_per_s = config.spray.nominal_speed_m_per_s;
  law.max_density = config.spray.max_density;
  law.decision_threshold = config.spray.decision_threshold;
  law.min_duty_pct = config.spray.duty_min_pct;
  law.max_duty_pct = config.spray.duty_max_pct;
  law.low_duty_policy = config.spray.low_duty_policy == "close"
                            ? control::LowDutyPolicy::kClose
                            : control::LowDutyPolicy::kRaiseToMin;
  return law;
}

const Config& default_settings() {
  static const Config defaults = default_config();
  return defaults;
}

}  // namespace weedspray::daemon
