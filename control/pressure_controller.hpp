// SPDX-License-Identifier: Apache-2.0
// The pressure-loop controller the daemon picks from config (SPEC §4): the conventional PID or
// the fuzzy-adaptive PID, behind one small value type so the comparison in the UGV paper can be
// rerun by changing one key. Pure; update() is allocation-free and noexcept.
#pragma once

#include <variant>

#include "control/fuzzy_pid.hpp"
#include "control/pid.hpp"

namespace weedspray::control {

enum class PressureControlMode { kPid, kFuzzyPid };

class PressureController {
 public:
  // kPid uses config.base only; kFuzzyPid uses all of config. Throws std::invalid_argument.
  PressureController(PressureControlMode mode, const FuzzyPidConfig& config);

  double update(double setpoint, double measurement, double dt_s) noexcept;
  void enable(double current_output, double setpoint, double measurement) noexcept;
  void disable() noexcept;
  bool enabled() const noexcept;
  void reset() noexcept;

  PressureControlMode mode() const noexcept { return mode_; }
  double output() const noexcept;
  // Gains used in the last cycle (base gains for kPid).
  PidGains current_gains() const noexcept;
  const PidTerms& last_terms() const noexcept;

 private:
  PressureControlMode mode_;
  std::variant<Pid, FuzzyPid> controller_;
};

}  // namespace weedspray::control
