// SPDX-License-Identifier: Apache-2.0
// The sprayer's operating state, as pure logic (no threads, no I/O):
//   Starting -> Idle (sensors live, valves closed, pump off) <-> Spraying
//   any -> Fault (latched, safe) -> Idle only when the alarms are cleared.
#pragma once

#include <string>
#include <string_view>

namespace weedspray::daemon {

enum class SprayerState { kStarting, kIdle, kSpraying, kFault };

std::string_view to_string(SprayerState state) noexcept;

enum class StateEvent {
  kSetupDone,      // everything opened and the loops run
  kStart,          // D-Bus Start(), autostart
  kStop,           // D-Bus Stop()
  kKeyPressed,     // the start/stop key toggles Idle <-> Spraying
  kFault,          // a fault-class alarm was raised
  kAlarmsCleared,  // ClearAlarms() with no fault condition left
};

struct Transition {
  bool accepted = false;
  SprayerState from = SprayerState::kStarting;
  SprayerState to = SprayerState::kStarting;
  std::string reason;  // why a request was refused (empty when accepted)
};

class StateMachine {
 public:
  SprayerState state() const noexcept { return state_; }
  Transition handle(StateEvent event);

  // Valves may open and the pump run only while Spraying; Idle keeps sensors live, valves
  // closed and the pump off, except that a calibration runs the pump in Idle (`calibrating`).
  // Fault never runs it, whatever else asks.
  bool valves_enabled() const noexcept { return state_ == SprayerState::kSpraying; }
  bool pump_enabled(bool calibrating = false) const noexcept {
    return state_ == SprayerState::kSpraying || (calibrating && state_ == SprayerState::kIdle);
  }

 private:
  SprayerState state_ = SprayerState::kStarting;
};

}  // namespace weedspray::daemon
