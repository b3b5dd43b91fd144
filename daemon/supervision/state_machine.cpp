// SPDX-License-Identifier: Apache-2.0
#include "daemon/supervision/state_machine.hpp"

namespace weedspray::daemon {

std::string_view to_string(SprayerState state) noexcept {
  switch (state) {
    case SprayerState::kStarting:
      return "Starting";
    case SprayerState::kIdle:
      return "Idle";
    case SprayerState::kSpraying:
      return "Spraying";
    case SprayerState::kFault:
      return "Fault";
  }
  return "?";
}

Transition StateMachine::handle(StateEvent event) {
  Transition t{.accepted = false, .from = state_, .to = state_, .reason = {}};
  const auto go = [&](SprayerState to) {
    t.accepted = true;
    t.to = to;
    state_ = to;
  };
  const auto refuse = [&](std::string reason) { t.reason = std::move(reason); };
  switch (event) {
    case StateEvent::kSetupDone:
      if (state_ == SprayerState::kStarting)
        go(SprayerState::kIdle);
      else
        refuse("already set up");
      break;
    case StateEvent::kStart:
      if (state_ == SprayerState::kIdle)
        go(SprayerState::kSpraying);
      else if (state_ == SprayerState::kSpraying)
        refuse("already spraying");
      else if (state_ == SprayerState::kFault)
        refuse("in Fault: clear the alarms first");
      else
        refuse("still starting up");
      break;
    case StateEvent::kStop:
      if (state_ == SprayerState::kSpraying)
        go(SprayerState::kIdle);
      else
        refuse("not spraying (state " + std::string(to_string(state_)) + ")");
      break;
    case StateEvent::kKeyPressed:
      if (state_ == SprayerState::kIdle)
        go(SprayerState::kSpraying);
      else if (state_ == SprayerState::kSpraying)
        go(SprayerState::kIdle);
      else
        refuse("key ignored in state " + std::string(to_string(state_)));
      break;
    case StateEvent::kFault:
      if (state_ != SprayerState::kFault)
        go(SprayerState::kFault);
      else
        refuse("already in Fault");
      break;
    case StateEvent::kAlarmsCleared:
      if (state_ == SprayerState::kFault)
        go(SprayerState::kIdle);
      else
        refuse("not in Fault");
      break;
  }
  return t;
}

}  // namespace weedspray::daemon
