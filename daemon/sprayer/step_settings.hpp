// SPDX-License-Identifier: Apache-2.0
// The control steps' settings from a configuration: the one translation of [pressure], [pwm],
// [boom] and [spray] into control/ structs. The daemon's loops build their steps with it; the lab's
// closed-loop rig takes the same settings from the default configuration, so an experiment
// runs the daemon's gains, loop rate and valve timing unless it says otherwise.
#pragma once

#include <chrono>

#include "control/nozzle_command_step.hpp"
#include "control/pressure_loop_step.hpp"
#include "control/pwm_schedule.hpp"
#include "control/spray_rate_law.hpp"
#include "daemon/config/config.hpp"

namespace weedspray::daemon {

control::FuzzyPidConfig pressure_controller_config(const Config& config);
control::PressureLoopConfig pressure_loop_config(const Config& config);
control::PwmConfig pwm_config(const Config& config);
// The valve duties' step: [boom] nozzles and the [spray] quantiser; the trim's defaults.
control::NozzleCommandConfig nozzle_command_config(const Config& config);

// The spray-rate law: [spray] rate, duty band and low-duty policy, [boom] nozzle width.
control::SprayLawConfig spray_law_config(const Config& config);

// The control loop's period: a frame waits at most this long to be scheduled, and at 2.5 m/s
// the vehicle moves 5 mm per cycle. The lab's rig steps the valve duties at the same period.
inline constexpr std::chrono::nanoseconds kControlLoopPeriod = std::chrono::milliseconds(2);

// default_config(), built once per process (the schema's defaults).
const Config& default_settings();

}  // namespace weedspray::daemon
