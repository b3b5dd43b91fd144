// SPDX-License-Identifier: Apache-2.0
// The control steps' settings from a configuration: the one translation of [pressure], [pwm]
// and [boom] into control/ structs. The daemon's loops build their steps with it; the lab's
// closed-loop rig takes the same settings from the default configuration, so an experiment
// runs the daemon's gains, loop rate and valve timing unless it says otherwise.
#pragma once

#include "control/pressure_loop_step.hpp"
#include "control/pwm_schedule.hpp"
#include "daemon/config/config.hpp"

namespace weedspray::daemon {

control::FuzzyPidConfig pressure_controller_config(const Config& config);
control::PressureLoopConfig pressure_loop_config(const Config& config);
control::PwmConfig pwm_config(const Config& config);
// default_config(), built once per process (the schema's defaults).
const Config& default_settings();

}  // namespace weedspray::daemon
